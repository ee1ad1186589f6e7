"""The framing both pushlearn protocols share (docs/protocol.md §2).

Each direction of a connection is a stream of frames: a 4-byte big-endian
unsigned length ``L``, then ``L`` bytes holding one protobuf message. ``L``
does not count itself and is at most :data:`MAX_FRAME_SIZE` (16 MiB); a
larger prefix is refused as soon as its 4 bytes are read, before anything is
allocated for the body. ``L = 0`` is legal: the message with every field at
its default. This is *not* protobuf's varint-delimited format.

The functions work on any binary stream with ``read(n)`` / ``write(b)``:
``sys.stdin.buffer`` and ``sys.stdout.buffer``, ``io.BytesIO``, pipes, and
sockets through ``socket.makefile("rb")`` / ``socket.makefile("wb")``.
"""

from __future__ import annotations

import struct
from typing import Any, Protocol, TypeVar

__all__ = [
    "MAX_FRAME_SIZE",
    "ProtocolError",
    "decode_body",
    "decode_length",
    "encode_frame",
    "read_frame",
    "write_frame",
]

MAX_FRAME_SIZE = 16 * 1024 * 1024
"""The largest frame body either side accepts, in bytes (16 MiB)."""

_PREFIX = struct.Struct(">I")


class ProtocolError(Exception):
    """The byte stream is not a valid sequence of frames or messages.

    Raised for a truncated frame, an oversized length prefix, a body that
    does not decode as the expected message, and for messages that break a
    protocol's rules (e.g. a first message that is not the expected hello).
    The stream can no longer be trusted to be aligned on frames.
    """


class Readable(Protocol):
    """A binary stream that can be read from (``read(n) -> bytes``)."""

    def read(self, n: int, /) -> bytes | None:
        """Up to ``n`` bytes; fewer only at the end of the stream."""
        ...


class Writable(Protocol):
    """A binary stream that can be written to."""

    def write(self, data: bytes, /) -> int | None:
        """Writes ``data``."""
        ...


M = TypeVar("M")


def encode_frame(message: Any) -> bytes:
    """The frame of one protobuf message: its length prefix and its bytes.

    Raises :class:`ProtocolError` if the encoded message exceeds
    :data:`MAX_FRAME_SIZE` (no peer would accept it).
    """
    body: bytes = message.SerializeToString()
    if len(body) > MAX_FRAME_SIZE:
        raise ProtocolError(
            f"a {type(message).__name__} of {len(body)} bytes exceeds the frame limit "
            f"of {MAX_FRAME_SIZE} bytes (16 MiB)"
        )
    return _PREFIX.pack(len(body)) + body


def write_frame(stream: Writable, message: Any) -> None:
    """Writes one framed protobuf message to ``stream`` and flushes it.

    Prefix and body go out in a single ``write`` call (one TCP segment for a
    small message on a socket file).
    """
    stream.write(encode_frame(message))
    flush = getattr(stream, "flush", None)
    if flush is not None:
        flush()


def decode_length(prefix: bytes) -> int:
    """The body length a 4-byte prefix announces.

    Raises :class:`ProtocolError` when it exceeds :data:`MAX_FRAME_SIZE`.
    """
    (length,) = _PREFIX.unpack(prefix)
    if length > MAX_FRAME_SIZE:
        hint = ""
        if prefix[:4].isascii() and prefix[:4].decode("ascii").isprintable():
            hint = f" (the bytes are the text {prefix.decode('ascii')!r}: is the peer speaking another protocol?)"
        raise ProtocolError(
            f"frame length prefix {length} exceeds the limit of {MAX_FRAME_SIZE} bytes (16 MiB){hint}"
        )
    return int(length)


def decode_body(body: bytes, message_type: type[M]) -> M:
    """Parses ``body`` as a ``message_type``; :class:`ProtocolError` if it is not one."""
    message: Any = message_type()
    try:
        message.ParseFromString(body)
    except Exception as err:  # protobuf raises DecodeError or, in some backends, others
        raise ProtocolError(
            f"a frame of {len(body)} bytes does not decode as {message_type.__name__}: {err}"
        ) from err
    return message  # type: ignore[no-any-return]


def _read_exactly(stream: Readable, n: int) -> bytes:
    """Exactly ``n`` bytes, fewer only if the stream ends first."""
    chunks: list[bytes] = []
    remaining = n
    while remaining > 0:
        chunk = stream.read(remaining)
        if not chunk:
            break
        chunks.append(chunk)
        remaining -= len(chunk)
    return b"".join(chunks)


def read_frame(stream: Readable, message_type: type[M]) -> M | None:
    """Reads one frame from ``stream`` and decodes it as a ``message_type``.

    Returns ``None`` when the stream ends cleanly between two frames. Raises
    :class:`ProtocolError` when it ends inside a frame (a truncated prefix or
    body), when the prefix announces more than :data:`MAX_FRAME_SIZE` bytes,
    or when the body does not decode as ``message_type``.
    """
    prefix = _read_exactly(stream, _PREFIX.size)
    if not prefix:
        return None
    if len(prefix) < _PREFIX.size:
        raise ProtocolError(
            f"the stream ended inside a frame's length prefix ({len(prefix)} of 4 bytes)"
        )
    length = decode_length(prefix)
    body = _read_exactly(stream, length)
    if len(body) < length:
        raise ProtocolError(
            f"the stream ended inside a frame: {len(body)} of {length} bytes of its body arrived"
        )
    return decode_body(body, message_type)
