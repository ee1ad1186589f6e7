"""SimClient against the real world daemon, and against peers that are not one."""

from __future__ import annotations

import itertools
import socket
import threading
from collections.abc import Callable, Iterator
from pathlib import Path

import pytest
from conftest import Daemon, sweep_centre
from pushlearn import ProtocolError, SimClient, SimError, State

STATES = 150


def push_from_start_line(world: SimClient, x0: float = 0.0) -> State:
    """The calibration push: reset, actuator at (x0, 0), Move (0, 0.5), 150 states in force."""
    world.reset()
    world.set_pose("actuator", x0, 0.0, 0.03)
    push = world.move(0.0, 0.5)
    state = None
    for state in itertools.islice(world.states(after=push), STATES):
        assert (state.applied_seq or 0) >= push
    assert state is not None
    return state


def blue_pose(state: State) -> list[str]:
    x, y, theta = state.blocks[15]
    return [f"{x:.4f}", f"{y:.4f}", f"{theta:.4f}"]


def test_a_lockstep_push_reproduces_the_calibration_sweep(
    start_sim: Callable[..., Daemon], sim_bin: Path
) -> None:
    daemon = start_sim("--mode", "lockstep")
    with SimClient.connect(port=daemon.port) as world:
        assert world.lockstep
        end = push_from_start_line(world)
    # The push is the sweep's run from x0 = 0, bit for bit; compared as the
    # old example client printed it.
    assert blue_pose(end) == sweep_centre(sim_bin)
    assert end.step == 1500 and end.sim_time == pytest.approx(1.5)
    assert end.blocks[15].y > 0.8  # and it did move: from 0.25


def test_a_realtime_push_pushes_the_block(start_sim: Callable[..., Daemon]) -> None:
    daemon = start_sim("--mode", "realtime", "--real-time-rate", "2000")
    with SimClient.connect(port=daemon.port) as world:
        assert not world.lockstep
        end = push_from_start_line(world)
    x, y, _ = end.blocks[15]
    # Where exactly depends on when the commands arrived, within an interval.
    assert abs(x) < 0.05 and y > 0.55, (x, y)


def test_the_hello_is_exposed(start_sim: Callable[..., Daemon]) -> None:
    daemon = start_sim("--mode", "lockstep", "--latency-max", "2")
    with SimClient.connect(port=daemon.port) as world:
        hello = world.hello
        assert hello.scene == "one_block"
        assert hello.timing_mode == "lockstep" and hello.lockstep
        assert hello.publish_rate == 100 and world.publish_rate == 100
        assert hello.step_size == pytest.approx(0.001)
        assert [(b.name, b.id) for b in hello.bodies] == [
            ("actuator", 8),
            ("blockA", 15),
        ]
        assert hello.bodies[1].position == pytest.approx((0.0, 0.25, 0.05))
        assert hello.shapes["actuator"].sphere_radius is not None
        assert hello.shapes["blockA"].box_size is not None
        assert hello.latency_max_steps == 2
        assert world.address == f"127.0.0.1:{daemon.port}"


def test_without_latency_emulation_there_is_no_latency_maximum(
    start_sim: Callable[..., Daemon],
) -> None:
    daemon = start_sim("--mode", "lockstep")
    with SimClient.connect(port=daemon.port) as world:
        assert world.hello.latency_max_steps is None
        # ... and the world refuses a latency seed.
        world.latency_seed(7)
        with pytest.raises(SimError) as refused:
            world.sync()
        assert refused.value.kind == "INVALID_COMMAND"
        assert refused.value.seq == world.last_seq - 1


def test_world_errors_raise_sim_error_with_the_world_text(
    start_sim: Callable[..., Daemon],
) -> None:
    daemon = start_sim("--mode", "lockstep")
    with SimClient.connect(port=daemon.port) as world:
        bad = world.set_pose("blockC", 0.0, 0.0, 0.05)
        with pytest.raises(SimError) as refused:
            world.next_state()
        error = refused.value
        assert error.seq == bad and error.kind == "INVALID_COMMAND"
        assert "unknown body 'blockC'" in error.message
        assert f"command {bad} (INVALID_COMMAND)" in str(error)
        # The connection goes on: the refused command changed nothing.
        world.sync()
        assert world.next_state().step == 10


def test_sync_confirms_commands_and_keeps_the_states_it_read(
    start_sim: Callable[..., Daemon],
) -> None:
    daemon = start_sim("--mode", "lockstep")
    with SimClient.connect(port=daemon.port) as world:
        first = world.advance()
        world.advance()
        world.sync()  # both Advances accepted; their states may have arrived meanwhile
        steps = [world.next_state().step for _ in range(3)]
        assert steps == [
            10,
            20,
            30,
        ]  # two from the Advances above, the third sent by next_state
        assert world.last_seq == first + 3  # advance, advance, barrier, advance


def test_seqs_strictly_increase_from_first_seq(
    start_sim: Callable[..., Daemon],
) -> None:
    daemon = start_sim("--mode", "lockstep")
    with SimClient.connect(port=daemon.port, first_seq=1000) as world:
        seqs = [
            world.pause(),
            world.unpause(),
            world.set_publish_rate(10),
            world.move(0, 0),
        ]
        assert seqs == [1000, 1001, 1002, 1003]
        assert world.publish_rate == 10
        state = world.next_state(after=seqs[-1])
        assert state.step == 100  # 10 Hz: 100 steps per publish
        assert (state.applied_seq or 0) >= 1004  # its Advance


def test_pipelined_advances_are_not_doubled(start_sim: Callable[..., Daemon]) -> None:
    daemon = start_sim("--mode", "lockstep")
    with SimClient.connect(port=daemon.port) as world:
        for _ in range(4):
            world.advance()
        before = world.last_seq
        assert [world.next_state().step for _ in range(4)] == [10, 20, 30, 40]
        assert world.last_seq == before  # no Advance was needed
        assert world.next_state().step == 50
        assert world.last_seq == before + 1


def test_states_carry_bodies_velocities_and_counters(
    start_sim: Callable[..., Daemon],
) -> None:
    daemon = start_sim("--mode", "lockstep")
    with SimClient.connect(port=daemon.port) as world:
        move = world.move(0.0, 0.5)
        state = world.next_state(after=move)
        actuator = state.body("actuator")
        assert actuator.lin_vel is not None and actuator.lin_vel[1] == pytest.approx(
            0.5, abs=1e-3
        )
        assert state.actuator.y == pytest.approx(0.005, abs=1e-6)
        assert state.publish_seq is not None and state.applied_seq is not None


@pytest.mark.parametrize(
    ("call", "message"),
    [
        (lambda w: w.move(float("nan"), 0.0), "vx must be a finite number"),
        (lambda w: w.set_publish_rate(7), "divisor of 1000"),
        (lambda w: w.set_pose("", 0, 0, 0), "needs a body name"),
        (lambda w: w.latency_seed(-1), "latency seed"),
    ],
)
def test_bad_arguments_raise_before_sending(
    start_sim: Callable[..., Daemon], call: Callable[[SimClient], object], message: str
) -> None:
    daemon = start_sim("--mode", "lockstep")
    with SimClient.connect(port=daemon.port) as world:
        before = world.last_seq
        with pytest.raises(ValueError, match=message):
            call(world)
        assert world.last_seq == before


# -- peers that are not a world ------------------------------------------------


@pytest.fixture
def fake_peer() -> Iterator[Callable[[bytes | None], int]]:
    """A function starting a listener that sends ``data`` (None: nothing) to each client."""
    servers: list[socket.socket] = []

    def start(data: bytes | None) -> int:
        server = socket.create_server(("127.0.0.1", 0))
        servers.append(server)

        def serve() -> None:
            try:
                while True:
                    conn, _ = server.accept()
                    if data == b"":
                        conn.close()
                        continue
                    if data is not None:
                        conn.sendall(data)
                    threading.Timer(5.0, conn.close).start()
            except OSError:
                pass

        threading.Thread(target=serve, daemon=True).start()
        return int(server.getsockname()[1])

    yield start
    for server in servers:
        server.close()


def free_port() -> int:
    with socket.socket() as probe:
        probe.bind(("127.0.0.1", 0))
        return int(probe.getsockname()[1])


def test_nothing_listening_says_so() -> None:
    port = free_port()
    with pytest.raises(
        ConnectionRefusedError,
        match=f"127.0.0.1:{port}.*is pushlearn-sim running there",
    ):
        SimClient.connect(port=port, timeout=2.0)


def test_a_silent_peer_times_out_with_a_hint(
    fake_peer: Callable[[bytes | None], int],
) -> None:
    port = fake_peer(None)
    expected = (
        f"no Hello from 127.0.0.1:{port} within 0.3 s: is pushlearn-sim running there?"
    )
    with pytest.raises(TimeoutError) as timed_out:
        SimClient.connect(port=port, timeout=0.3)
    assert str(timed_out.value) == expected


def test_an_http_server_is_not_a_world(
    fake_peer: Callable[[bytes | None], int],
) -> None:
    port = fake_peer(b"HTTP/1.1 400 Bad Request\r\n\r\n")
    with pytest.raises(
        ProtocolError, match="does not speak the pushlearn world protocol.*HTTP"
    ):
        SimClient.connect(port=port, timeout=2.0)


def test_a_peer_that_closes_at_once(fake_peer: Callable[[bytes | None], int]) -> None:
    port = fake_peer(b"")
    with pytest.raises(ConnectionError, match="without sending a Hello"):
        SimClient.connect(port=port, timeout=0.3).close()
