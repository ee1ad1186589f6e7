"""The shared framing: round trips and every way a stream can be broken."""

from __future__ import annotations

import io
import socket
import struct
import threading

import pytest
from pushlearn._pb import learner_pb2, pushlearn_pb2
from pushlearn.framing import (
    MAX_FRAME_SIZE,
    ProtocolError,
    encode_frame,
    read_frame,
    write_frame,
)


def move(seq: int, vy: float) -> object:
    return pushlearn_pb2.ClientMessage(
        seq=seq,
        actuator=pushlearn_pb2.ActuatorCommand(
            cmd=pushlearn_pb2.ActuatorCommand.MOVE,
            direction=pushlearn_pb2.Vector3d(y=vy),
        ),
    )


def test_the_move_example_of_the_protocol_page_is_what_the_encoder_writes() -> None:
    # docs/protocol.md §2: Move(0, 0.5) with seq 1 is these 21 bytes.
    expected = bytes.fromhex("00000011 0801 120d 0801 1209 11 000000000000e03f")
    assert encode_frame(move(1, 0.5)) == expected


def test_frames_round_trip_through_a_stream() -> None:
    stream = io.BytesIO()
    messages = [move(1, 0.5), move(2, -0.25), pushlearn_pb2.ClientMessage(seq=3)]
    for message in messages:
        write_frame(stream, message)
    stream.seek(0)
    back = [read_frame(stream, pushlearn_pb2.ClientMessage) for _ in messages]
    assert back == messages
    assert read_frame(stream, pushlearn_pb2.ClientMessage) is None  # clean end


def test_an_empty_message_is_a_zero_length_frame() -> None:
    stream = io.BytesIO(b"\x00\x00\x00\x00")
    message = read_frame(stream, learner_pb2.Request)
    assert message == learner_pb2.Request()
    assert encode_frame(learner_pb2.Request()) == b"\x00\x00\x00\x00"


def test_frames_round_trip_through_a_socket() -> None:
    left, right = socket.socketpair()
    requests = [learner_pb2.Request(seq=i, bye=learner_pb2.Bye()) for i in range(1, 50)]

    def send() -> None:
        with left.makefile("wb") as out:
            for request in requests:
                write_frame(out, request)
        left.close()

    sender = threading.Thread(target=send)
    sender.start()
    received = []
    with right.makefile("rb") as incoming:
        while (request := read_frame(incoming, learner_pb2.Request)) is not None:
            received.append(request)
    sender.join()
    right.close()
    assert received == requests


class Trickle(io.RawIOBase):
    """A raw stream returning one byte per read, as a slow pipe may."""

    def __init__(self, data: bytes) -> None:
        self._data = io.BytesIO(data)

    def readable(self) -> bool:
        return True

    def read(self, n: int = -1) -> bytes:
        return self._data.read(min(n, 1) if n >= 0 else 1)


def test_short_reads_are_completed() -> None:
    message = move(7, 0.5)
    assert (
        read_frame(Trickle(encode_frame(message)), pushlearn_pb2.ClientMessage)
        == message
    )


def test_a_truncated_prefix_is_an_error() -> None:
    with pytest.raises(ProtocolError, match=r"length prefix \(2 of 4 bytes\)"):
        read_frame(io.BytesIO(b"\x00\x00"), pushlearn_pb2.ClientMessage)


def test_a_truncated_body_is_an_error() -> None:
    frame = encode_frame(move(1, 0.5))
    with pytest.raises(ProtocolError, match=r"16 of 17 bytes"):
        read_frame(io.BytesIO(frame[:-1]), pushlearn_pb2.ClientMessage)


def test_an_oversized_length_is_refused_before_reading_the_body() -> None:
    stream = io.BytesIO(struct.pack(">I", MAX_FRAME_SIZE + 1) + b"x" * 10)
    with pytest.raises(ProtocolError, match="exceeds the limit"):
        read_frame(stream, pushlearn_pb2.ClientMessage)
    assert stream.tell() == 4  # nothing of the body was read


def test_the_largest_length_is_accepted() -> None:
    # A frame of exactly 16 MiB is legal framing (here: a body of zeros,
    # which is not a valid message, so decoding fails, not framing).
    stream = io.BytesIO(struct.pack(">I", MAX_FRAME_SIZE) + bytes(MAX_FRAME_SIZE))
    with pytest.raises(ProtocolError, match="does not decode"):
        read_frame(stream, pushlearn_pb2.ClientMessage)


def test_text_from_another_protocol_is_named() -> None:
    with pytest.raises(ProtocolError, match="'HTTP'.*another protocol"):
        read_frame(
            io.BytesIO(b"HTTP/1.1 400 Bad Request\r\n"), pushlearn_pb2.ServerMessage
        )


def test_an_undecodable_body_is_an_error() -> None:
    garbage = b"\xff\xff\xff\xff\xff"
    with pytest.raises(ProtocolError, match="5 bytes does not decode as ServerMessage"):
        read_frame(
            io.BytesIO(struct.pack(">I", len(garbage)) + garbage),
            pushlearn_pb2.ServerMessage,
        )


def test_an_oversized_message_is_not_written() -> None:
    state = learner_pb2.State(
        bodies=[pushlearn_pb2.ModelState(name="x" * (1 << 20)) for _ in range(17)]
    )
    stream = io.BytesIO()
    with pytest.raises(ProtocolError, match="exceeds the frame limit"):
        write_frame(stream, state)
    assert stream.getvalue() == b""
