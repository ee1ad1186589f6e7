"""A blocking client for the world daemon, ``pushlearn-sim`` (docs/protocol.md).

::

    from pushlearn import SimClient

    with SimClient.connect(port=11345) as world:
        print(world.hello.scene, world.hello.timing_mode, world.hello.publish_rate)
        world.reset()
        world.set_pose("actuator", 0.0, 0.0, 0.03)
        move = world.move(0.0, 0.5)
        state = world.next_state(after=move)      # the first state with the Move in force
        print(state.blocks[15])                   # the blue block's (x, y, theta)

The client reads the world's Hello on connecting and exposes it as
:attr:`SimClient.hello`. Commands are numbered with strictly increasing
``seq`` values and return them; the world answers only refused commands, with
an ``Error`` that :meth:`SimClient.next_state` (or any other read) raises as
:class:`SimError`. In lock-step mode :meth:`SimClient.next_state` sends the
Advance that makes the world publish the state it waits for, unless one is
already outstanding; so the same loop works in both timing modes.
"""

from __future__ import annotations

import math
import socket
from collections import deque
from collections.abc import Iterator
from dataclasses import dataclass, field
from types import TracebackType
from typing import Any, Self

from . import framing
from ._pb import pushlearn_pb2
from .framing import ProtocolError
from .learner import Body, Shape, State

__all__ = ["DEFAULT_PORT", "Shape", "SimClient", "SimError", "WorldHello"]

DEFAULT_PORT = 11345
"""The world daemon's default port."""

_U64 = 2**64


class SimError(Exception):
    """The world refused a command, or reports a fault: its ``Error`` message.

    ``seq`` is the refused command's seq (0 for errors about the connection
    or the world itself, e.g. a physics blow-up), ``kind`` the error kind's
    name (``"INVALID_COMMAND"``, ``"PHYSICS_BLEW_UP"``, …; programs should
    match on it, not on the text) and ``message`` the world's own text.
    """

    def __init__(
        self, message: str, seq: int = 0, kind: str = "KIND_UNSPECIFIED"
    ) -> None:
        self.message = message
        """The world's text, for people."""
        self.seq = seq
        """The seq of the refused command; 0 when the error is not about one command."""
        self.kind = kind
        """The ``Error.Kind`` name."""
        what = f"command {seq}" if seq else "the world"
        super().__init__(f"{what} ({kind}): {message}")


@dataclass(frozen=True)
class WorldHello:
    """The world's Hello: what the world is and how it runs (docs/protocol.md §4)."""

    scene: str
    """``"one_block"`` or ``"two_blocks"``."""
    step_size: float
    """Physics step in seconds (0.001)."""
    publish_rate: int
    """The publish rate in Hz when the connection was made."""
    timing_mode: str
    """``"realtime"`` or ``"lockstep"`` (from ``timing_kind``, or the string from older worlds)."""
    bodies: tuple[Body, ...]
    """Every body with its name, id and start pose."""
    shapes: dict[str, Shape] = field(default_factory=dict)
    """Each body's collision shape by name; empty from worlds older than the field."""
    latency_max_steps: int | None = None
    """Lock-step latency emulation's largest delay of a Move, in steps; ``None`` without it."""

    @property
    def lockstep(self) -> bool:
        """Whether the world runs in lock-step mode (it publishes only after an Advance)."""
        return self.timing_mode == "lockstep"

    @classmethod
    def from_proto(cls, hello: Any) -> WorldHello:
        """The Hello of a ``pushlearn.Hello`` message."""
        kinds = pushlearn_pb2.Hello
        if hello.timing_kind == kinds.TIMING_KIND_LOCKSTEP:
            mode = "lockstep"
        elif hello.timing_kind == kinds.TIMING_KIND_REALTIME:
            mode = "realtime"
        else:  # a world older than timing_kind says it only in the string
            mode = hello.timing_mode
        shapes = {shape.name: Shape.from_proto(shape) for shape in hello.shapes}
        return cls(
            scene=hello.scene,
            step_size=hello.step_size,
            publish_rate=hello.publish_rate,
            timing_mode=mode,
            bodies=tuple(Body.from_proto(m, velocities=True) for m in hello.bodies),
            shapes=shapes,
            latency_max_steps=(
                hello.latency_max_steps if hello.HasField("latency_max_steps") else None
            ),
        )


def _finite(**values: float) -> None:
    for name, value in values.items():
        if not isinstance(value, int | float) or isinstance(value, bool):
            raise TypeError(f"{name} must be a number, got {type(value).__name__}")
        if not math.isfinite(value):
            raise ValueError(f"{name} must be a finite number, got {value}")


class _FrameReader:
    """Frames from a socket, robust to timeouts: a partial frame stays buffered."""

    def __init__(self, sock: socket.socket) -> None:
        self._sock = sock
        self._buffer = bytearray()

    def _fill(self, n: int) -> bool:
        """Reads until ``n`` bytes are buffered; false if the peer closed first."""
        while len(self._buffer) < n:
            chunk = self._sock.recv(max(65536, n - len(self._buffer)))
            if not chunk:
                return False
            self._buffer += chunk
        return True

    def read(self) -> Any | None:
        """The next ``ServerMessage``; ``None`` when the peer closed between frames."""
        if not self._fill(4):
            if self._buffer:
                raise ProtocolError(
                    f"the world closed the connection inside a frame's length prefix "
                    f"({len(self._buffer)} of 4 bytes)"
                )
            return None
        length = framing.decode_length(bytes(self._buffer[:4]))
        if not self._fill(4 + length):
            raise ProtocolError(
                f"the world closed the connection inside a frame: {len(self._buffer) - 4} of "
                f"{length} bytes of its body arrived"
            )
        body = bytes(self._buffer[4 : 4 + length])
        del self._buffer[: 4 + length]
        return framing.decode_body(body, pushlearn_pb2.ServerMessage)


class SimClient:
    """A blocking connection to a world daemon (``pushlearn-sim``).

    Make one with :meth:`connect`. The command methods send one
    ``ClientMessage`` each and return its ``seq`` (strictly increasing, from
    ``first_seq``); they do not wait for anything. The world answers only
    commands it refuses: such an ``Error`` is raised as :class:`SimError` by
    the next read (:meth:`next_state`, :meth:`sync`). Arguments are checked
    before sending (finite numbers, a publish rate dividing 1000), so a
    mistake raises at the call that made it.

    Use it as a context manager, or call :meth:`close`.
    """

    def __init__(
        self,
        sock: socket.socket,
        hello: WorldHello,
        *,
        address: str,
        timeout: float | None,
        reader: _FrameReader,
        first_seq: int = 1,
    ) -> None:
        """Wraps a connected socket whose Hello was read; use :meth:`connect` instead."""
        self._sock = sock
        self._reader = reader
        self._address = address
        self._timeout = timeout
        self._next_seq = first_seq
        self._outstanding_advances = 0
        self._buffered: deque[State] = deque()
        self.hello = hello
        """The world's Hello (scene, timing mode, bodies, shapes, latency, …)."""
        self.publish_rate = hello.publish_rate
        """The publish rate in Hz, as last set through this client (or the Hello's)."""

    @classmethod
    def connect(
        cls,
        host: str = "127.0.0.1",
        port: int = DEFAULT_PORT,
        timeout: float | None = 10.0,
        *,
        first_seq: int = 1,
    ) -> SimClient:
        """Connects to the world at ``host:port`` and reads its Hello.

        ``timeout`` (seconds, ``None`` for none) bounds the connection, the
        wait for the Hello and every later wait for a message. ``first_seq``
        is the first command's seq: clients sharing a world should use
        disjoint ranges (docs/protocol.md §5, "Several clients").

        Raises ``ConnectionRefusedError``/``OSError`` when nothing accepts the
        connection, ``TimeoutError`` when no Hello arrives in time,
        :class:`ProtocolError` when the peer does not speak the protocol, and
        :class:`SimError` when the world refuses the connection (too many
        clients). Each message says which address and what to check.
        """
        if not 1 <= first_seq < _U64:
            raise ValueError(f"first_seq must be in 1 … 2⁶⁴ − 1, got {first_seq}")
        address = f"[{host}]:{port}" if ":" in host else f"{host}:{port}"
        hint = "is pushlearn-sim running there?"
        try:
            sock = socket.create_connection((host, port), timeout=timeout)
        except ConnectionRefusedError as err:
            raise ConnectionRefusedError(
                err.errno, f"cannot connect to {address}: connection refused: {hint}"
            ) from None
        except TimeoutError:
            raise TimeoutError(
                f"cannot connect to {address}{_within(timeout)}: {hint}"
            ) from None
        except OSError as err:
            raise OSError(
                err.errno, f"cannot connect to {address}: {err.strerror or err}"
            ) from None
        try:
            sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
            reader = _FrameReader(sock)
            try:
                message = reader.read()
            except TimeoutError:
                raise TimeoutError(
                    f"no Hello from {address}{_within(timeout)}: {hint}"
                ) from None
            except ProtocolError as err:
                raise ProtocolError(
                    f"{address} does not speak the pushlearn world protocol: {err} ({hint})"
                ) from None
            except OSError as err:
                raise ConnectionError(
                    f"the connection to {address} failed before its Hello: {err} ({hint})"
                ) from None
            if message is None:
                raise ConnectionError(
                    f"{address} closed the connection without sending a Hello: {hint}"
                )
            kind = message.WhichOneof("payload")
            if kind == "error":
                raise _sim_error(message.error)
            if kind != "hello":
                what = "an unknown message" if kind is None else f"a {kind}"
                raise ProtocolError(
                    f"{address} sent {what} instead of its Hello: {hint}"
                )
            hello = WorldHello.from_proto(message.hello)
        except BaseException:
            sock.close()
            raise
        return cls(
            sock,
            hello,
            address=address,
            timeout=timeout,
            reader=reader,
            first_seq=first_seq,
        )

    # -- properties ----------------------------------------------------------

    @property
    def address(self) -> str:
        """The world's address as ``HOST:PORT``."""
        return self._address

    @property
    def lockstep(self) -> bool:
        """Whether the world runs in lock-step mode."""
        return self.hello.lockstep

    @property
    def last_seq(self) -> int:
        """The seq of the last command sent (``first_seq − 1`` before any)."""
        return self._next_seq - 1

    # -- sending -------------------------------------------------------------

    def _send(self, **payload: Any) -> int:
        return self._send_all([payload])[0]

    def _send_all(self, payloads: list[dict[str, Any]]) -> list[int]:
        """Sends one ``ClientMessage`` per payload in a single write; their seqs."""
        first = self._next_seq
        if first + len(payloads) > _U64:
            raise OverflowError("the seq numbers are exhausted (2⁶⁴ − 1 commands)")
        seqs = list(range(first, first + len(payloads)))
        data = b"".join(
            framing.encode_frame(pushlearn_pb2.ClientMessage(seq=seq, **payload))
            for seq, payload in zip(seqs, payloads, strict=True)
        )
        try:
            self._sock.sendall(data)
        except OSError as err:
            raise ConnectionError(
                f"sending to the world at {self._address} failed: {err}"
            ) from err
        self._next_seq += len(payloads)
        return seqs

    def reset(self) -> int:
        """Resets every body to its start pose (the stored actuator command is kept:
        send ``move(0, 0)`` first to stop it). Returns the seq."""
        return self._send(control=pushlearn_pb2.SimControl(reset=True))

    def set_pose(
        self, name: str, x: float, y: float, z: float, yaw: float = 0.0
    ) -> int:
        """Puts body ``name`` at ``(x, y, z)`` with yaw ``yaw`` (rad). Returns the seq.

        Use z = 0.03 for the actuator and 0.05 for the blocks. ``*Shadow``
        names set visualisation ghosts.
        """
        if not isinstance(name, str) or not name:
            raise ValueError(f"set_pose needs a body name, got {name!r}")
        _finite(x=x, y=y, z=z, yaw=yaw)
        half = yaw / 2.0
        pose = pushlearn_pb2.Pose(
            position=pushlearn_pb2.Vector3d(x=x, y=y, z=z),
            orientation=pushlearn_pb2.Quaternion(
                x=0.0, y=0.0, z=math.sin(half), w=math.cos(half)
            ),
        )
        return self._send(
            set_pose=pushlearn_pb2.ModelStateV(
                models=[pushlearn_pb2.ModelState(name=name, pose=pose)]
            )
        )

    def move(self, vx: float, vy: float) -> int:
        """Sets the actuator's velocity to ``(vx, vy)`` m/s, world frame. Returns the seq."""
        return self._send(actuator=_move_command(vx, vy))

    def pause(self) -> int:
        """Pauses stepping. Returns the seq."""
        return self._send(control=pushlearn_pb2.SimControl(pause=True))

    def unpause(self) -> int:
        """Resumes stepping. Returns the seq."""
        return self._send(control=pushlearn_pb2.SimControl(pause=False))

    def set_publish_rate(self, hz: int) -> int:
        """Publishes every ``1000 / hz`` physics steps; ``hz`` must divide 1000. Returns the seq."""
        if (
            isinstance(hz, bool)
            or not isinstance(hz, int)
            or not 1 <= hz <= 1000
            or 1000 % hz
        ):
            raise ValueError(
                f"the publish rate must be a divisor of 1000 Hz, got {hz!r}"
            )
        seq = self._send(control=pushlearn_pb2.SimControl(publish_rate_hz=hz))
        self.publish_rate = hz
        return seq

    def advance(self) -> int:
        """Lock-step mode only: runs the world to its next publish. Returns the seq.

        :meth:`next_state` sends it for you when none is outstanding; call it
        yourself to keep several Advances in flight (docs/protocol.md §8).
        """
        seq = self._send(control=pushlearn_pb2.SimControl(advance=True))
        self._outstanding_advances += 1
        return seq

    def move_and_advance(self, vx: float, vy: float) -> int:
        """Lock-step mode: sends ``move(vx, vy)`` and the Advance that runs the world to
        its next publish, in one write, and returns the Move's seq.

        Read the state with ``next_state(after=seq)``. A program driving several
        worlds starts them all stepping this way before it waits for any (the
        Gymnasium vector environment does). Raises ``ValueError`` on a realtime
        world, which needs no Advance.
        """
        if not self.lockstep:
            raise ValueError(
                f"move_and_advance needs a lock-step world; {self._address} runs in "
                f"{self.hello.timing_mode} mode (use move and next_state)"
            )
        move, _ = self._send_all(
            [
                {"actuator": _move_command(vx, vy)},
                {"control": pushlearn_pb2.SimControl(advance=True)},
            ]
        )
        self._outstanding_advances += 1
        return move

    def move_and_observe(self, vx: float, vy: float) -> State:
        """Sends ``move(vx, vy)`` and returns the first state with it in force.

        In lock-step mode the Move and its Advance go out in one write
        (:meth:`move_and_advance`: one system call instead of two, the
        Gymnasium environments' step); otherwise, or while Advances are
        outstanding, this is ``next_state(after=move(vx, vy))``.
        """
        if not self.lockstep or self._outstanding_advances or self._buffered:
            return self.next_state(after=self.move(vx, vy))
        return self.next_state(after=self.move_and_advance(vx, vy))

    def latency_seed(self, seed: int) -> int:
        """Reseeds the world's latency emulation (lock-step with latency only). Returns the seq."""
        if isinstance(seed, bool) or not isinstance(seed, int) or not 0 <= seed < _U64:
            raise ValueError(
                f"the latency seed must be an integer in 0 … 2⁶⁴ − 1, got {seed!r}"
            )
        return self._send(control=pushlearn_pb2.SimControl(latency_seed=seed))

    def sync(self) -> None:
        """Waits until the world has received and accepted every command sent so far.

        Sends the protocol's barrier (a message without payload, which the
        world refuses at once, docs/protocol.md §5) and reads up to its
        answer. An ``Error`` for an earlier command raises :class:`SimError`;
        world states read meanwhile are kept for :meth:`next_state`.
        """
        barrier = self._send()
        while True:
            message = self._read_message(
                waiting_for=f"the answer to the barrier {barrier}"
            )
            kind = message.WhichOneof("payload")
            if kind == "world_state":
                self._buffered.append(self._take_state(message.world_state))
            elif kind == "error":
                if message.error.seq == barrier:
                    return
                raise _sim_error(message.error)
            elif kind == "hello":
                raise ProtocolError(f"{self._address} sent a second Hello")

    # -- receiving -----------------------------------------------------------

    def _read_message(self, *, waiting_for: str) -> Any:
        while True:
            try:
                message = self._reader.read()
            except TimeoutError:
                hint = ""
                if self.lockstep:
                    hint = " (a lock-step world publishes only after an Advance)"
                raise TimeoutError(
                    f"no message from the world at {self._address}{_within(self._timeout)} "
                    f"while waiting for {waiting_for}{hint}"
                ) from None
            except OSError as err:
                raise ConnectionError(
                    f"reading from the world at {self._address} failed: {err}"
                ) from err
            if message is None:
                raise ConnectionError(
                    f"the world at {self._address} closed the connection while this client "
                    f"waited for {waiting_for}"
                )
            if message.WhichOneof("payload") is None:
                continue  # a payload a newer world added: skip it (docs/protocol.md §6)
            return message

    def _take_state(self, world_state: Any) -> State:
        if self._outstanding_advances:
            self._outstanding_advances -= 1
        return State.from_world_state(world_state, self.hello.shapes)

    def next_state(
        self, *, after: int | None = None, advance: bool | None = None
    ) -> State:
        """The next world state, as a :class:`~pushlearn.State` with the world's counters.

        With ``after`` a command's seq, states produced before that command
        was in force (``applied_seq < after``) are skipped. In lock-step mode
        an Advance is sent before waiting whenever none is outstanding
        (``advance=False`` never sends one, ``advance=True`` always does).
        An ``Error`` from the world raises :class:`SimError`; ``TimeoutError``
        when nothing arrives within the connection's timeout.
        """
        while True:
            if self._buffered:
                state = self._buffered.popleft()
            else:
                if advance is True or (
                    advance is None and self.lockstep and not self._outstanding_advances
                ):
                    self.advance()
                message = self._read_message(waiting_for="a world state")
                kind = message.WhichOneof("payload")
                if kind == "error":
                    raise _sim_error(message.error)
                if kind == "hello":
                    raise ProtocolError(f"{self._address} sent a second Hello")
                state = self._take_state(message.world_state)
            if after is None or (state.applied_seq or 0) >= after:
                return state

    def states(self, *, after: int | None = None) -> Iterator[State]:
        """World states one after the other (:meth:`next_state` in a loop), forever.

        With ``after``, states before that command was in force are skipped.
        Stop with ``break`` or ``itertools.islice``.
        """
        while True:
            state = self.next_state(after=after)
            yield state

    # -- closing -------------------------------------------------------------

    def close(self) -> None:
        """Closes the connection (the world then forgets this client)."""
        self._sock.close()

    def __enter__(self) -> Self:
        return self

    def __exit__(
        self,
        exc_type: type[BaseException] | None,
        exc: BaseException | None,
        tb: TracebackType | None,
    ) -> None:
        self.close()

    def __repr__(self) -> str:
        return (
            f"SimClient({self._address}, scene={self.hello.scene!r}, "
            f"mode={self.hello.timing_mode!r}, rate={self.publish_rate} Hz)"
        )


def _move_command(vx: float, vy: float) -> Any:
    """The ``ActuatorCommand`` of a Move of ``(vx, vy)`` m/s; ValueError if not finite."""
    _finite(vx=vx, vy=vy)
    return pushlearn_pb2.ActuatorCommand(
        cmd=pushlearn_pb2.ActuatorCommand.MOVE,
        direction=pushlearn_pb2.Vector3d(x=vx, y=vy, z=0.0),
    )


def _within(timeout: float | None) -> str:
    return "" if timeout is None else f" within {timeout:g} s"


def _sim_error(error: Any) -> SimError:
    try:
        kind = pushlearn_pb2.Error.Kind.Name(error.kind)
    except ValueError:
        kind = f"kind {error.kind}"
    return SimError(error.message, seq=error.seq, kind=kind)
