"""pushlearn.World: the world of pushlearn-sim in this process, against the daemon itself."""

from __future__ import annotations

import math
import os
import threading
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from conftest import LIMIT, Daemon, run_python
from pushlearn import SimClient, State, World
from pushlearn._native import Worlds, step_messages
from pushlearn._pb import pushlearn_pb2

Command = tuple[Any, ...]
"""``("move", vx, vy)``, ``("advance",)``, ``("set_pose", name, x, y, z, yaw)``, …"""


def script(seed: int, messages: int = 120) -> list[Command]:
    """A session touching every command: a reset, a latency seed, poses and ghosts,
    pushes with a reset, a pause and a publish-rate change in between."""
    rng = np.random.default_rng(seed)
    commands: list[Command] = [
        ("move", 0.0, 0.0),
        ("reset",),
        ("set_pose", "actuator", 0.0, 0.1, 0.03, 0.0),
        ("set_pose", "blockAShadowTarget", 0.4, 0.5, 0.05, 1.2),
        ("advance",),
    ]
    for i in range(messages):
        vx, vy = (float(v) for v in rng.uniform(-0.5, 0.5, 2))
        commands += [("move", vx, vy + 0.3), ("advance",)]
        if i == messages // 3:
            commands += [("pause",), ("unpause",), ("publish_rate", 10), ("advance",)]
        if i == messages // 2:
            commands += [("publish_rate", 100), ("reset",), ("advance",)]
    return commands


def run_world(world: World, commands: list[Command]) -> list[pushlearn_pb2.WorldState]:
    """The states ``world`` publishes for ``commands``."""
    states = []
    for name, *args in commands:
        if name == "set_pose":
            body, x, y, z, yaw = args
            half = yaw / 2.0
            world.set_pose(body, (x, y, z), (0.0, 0.0, math.sin(half), math.cos(half)))
        elif name == "publish_rate":
            world.set_publish_rate(*args)
        elif name == "advance":
            world.advance()
            states.append(pushlearn_pb2.WorldState.FromString(world.state_bytes()))
        else:
            getattr(world, name)(*args)
    return states


def run_daemon(client: SimClient, commands: list[Command]) -> list[State]:
    """The states the daemon behind ``client`` publishes for ``commands``."""
    states = []
    for name, *args in commands:
        if name == "publish_rate":
            client.set_publish_rate(*args)
        elif name == "advance":
            client.advance()
            states.append(client.next_state(advance=False))
        else:
            getattr(client, name)(*args)
    return states


def bits(state: State) -> list[Any]:
    """Every number of ``state`` as its exact bits (``float.hex``), with names and counters."""
    out: list[Any] = [state.step, state.applied_seq, float(state.sim_time or 0).hex()]
    for body in state.bodies:
        numbers = [
            *body.position,
            *body.orientation,
            *(body.lin_vel or ()),
            *(body.ang_vel or ()),
        ]
        out.append((body.name, body.id, [float(v).hex() for v in numbers]))
    return out


@pytest.mark.parametrize(
    ("scene", "latency"),
    [("one_block", ["--latency-max", "2", "--latency-seed", "7"]), ("two_blocks", [])],
)
def test_the_in_process_world_equals_the_daemon_bit_for_bit(
    start_sim: Callable[..., Daemon], scene: str, latency: list[str]
) -> None:
    daemon = start_sim("--mode", "lockstep", "--scene", scene, *latency)
    world = World(scene, latency_max=2, latency_seed=7) if latency else World(scene)
    commands = script(seed=3)
    if latency:
        commands.insert(2, ("latency_seed", 11))
    with SimClient.connect("127.0.0.1", daemon.port) as client:
        hello = pushlearn_pb2.Hello.FromString(world.hello_bytes())
        assert hello.scene == client.hello.scene == scene
        assert (client.hello.latency_max_steps is None) == (not latency)
        expected = run_daemon(client, commands)
    got = run_world(world, commands)
    assert len(got) == len(expected) > 100
    for mine, theirs in zip(got, expected, strict=True):
        assert bits(State.from_world_state(mine)) == bits(theirs)
        assert mine.publish_seq == theirs.publish_seq
    # The array is the message's dynamic bodies, in scene order.
    last = expected[-1]
    dynamic = [b for b in last.bodies if "Shadow" not in b.name]
    assert world.body_names == [b.name for b in dynamic]
    rows = [
        [*b.position, *b.orientation, *(b.lin_vel or ()), *(b.ang_vel or ())]
        for b in dynamic
    ]
    assert world.state().tolist() == rows
    planar = world.state(planar=True).tolist()
    assert planar == [
        [b.position[0], b.position[1], b.yaw, r[7], r[8], r[12]]
        for b, r in zip(dynamic, rows, strict=True)
    ]


def test_worlds_stepped_from_threads_take_turns_and_stay_bit_identical() -> None:
    seeds = [1, 2, 3, 4]
    alone = [
        run_world(World("two_blocks", latency_max=3, latency_seed=s), script(s))
        for s in seeds
    ]
    results: dict[int, list[pushlearn_pb2.WorldState]] = {}
    start = threading.Barrier(len(seeds))

    def worker(seed: int) -> None:
        world = World("two_blocks", latency_max=3, latency_seed=seed)
        start.wait()
        results[seed] = run_world(world, script(seed))

    threads = [threading.Thread(target=worker, args=(s,)) for s in seeds]
    for thread in threads:
        thread.start()
    for thread in threads:
        thread.join()
    for seed, expected in zip(seeds, alone, strict=True):
        assert results[seed] == expected, f"the world of seed {seed} changed"
    # And one shared world, stepped by several threads, serves each call whole.
    shared = World()
    shared.advance()

    def push() -> None:
        for _ in range(50):
            assert shared.move_and_advance(0.0, 0.2).shape == (2, 13)

    threads = [threading.Thread(target=push) for _ in range(3)]
    for thread in threads:
        thread.start()
    for thread in threads:
        thread.join()
    assert shared.counters()[0] == 10 * 151


def test_worlds_step_together_as_each_alone() -> None:
    velocities = np.random.default_rng(5).uniform(-0.5, 0.5, (40, 3, 2))
    single = [World("two_blocks", latency_max=2, latency_seed=i) for i in range(3)]
    together = [World("two_blocks", latency_max=2, latency_seed=i) for i in range(3)]
    for world in (*single, *together):
        world.advance()
    worlds = Worlds(together)
    assert len(worlds) == 3
    for step in velocities:
        stacked = worlds.move_and_advance(step)
        assert stacked.shape == (3, 3, 13)
        for world, (vx, vy), rows in zip(single, step, stacked, strict=True):
            assert world.move_and_advance(vx, vy).tobytes() == rows.tobytes()
    # Worlds left out keep their last state and do not step.
    before = together[1].counters()
    worlds.move_and_advance(velocities[0], planar=True, stepped=[True, False, True])
    assert together[1].counters() == before
    assert together[0].counters()[0] == before[0] + 10


def test_the_floor_steps_the_same_messages() -> None:
    velocities = np.zeros((50, 2))
    assert step_messages(velocities, "one_block", latency_max=2) > 0.0
    with pytest.raises(ValueError, match=r"shape \(n, 2\)"):
        step_messages(np.zeros((4, 3)))
    assert step_messages(velocities, latency_max=2, episode_steps=7) > 0.0
    with pytest.raises(ValueError, match="episode_steps must be at least 1"):
        step_messages(velocities, episode_steps=0)


def refusals() -> list[tuple[str, Callable[[World], Any], str]]:
    nan, inf = math.nan, math.inf
    return [
        ("nan move", lambda w: w.move(nan, 0.0), "NaN"),
        ("inf move", lambda w: w.move(0.0, inf), "direction.y"),
        (
            "unknown body",
            lambda w: w.set_pose("blockZ", (0, 0, 0.05)),
            "unknown body 'blockZ'",
        ),
        ("ghost of nothing", lambda w: w.set_pose("blockZShadow", (0, 0, 0)), "blockZ"),
        (
            "matrix position",
            lambda w: w.set_pose("blockA", np.zeros((1, 3))),
            r"position must be 3 numbers .* shape \(1, 3\)",
        ),
        (
            "short position",
            lambda w: w.set_pose("blockA", (0, 0)),
            r"position must be 3 numbers \(x, y, z\), got an array of shape \(2,\)",
        ),
        (
            "long orientation",
            lambda w: w.set_pose("blockA", (0, 0, 0), (0, 0, 0, 1, 0)),
            r"orientation must be 4 numbers .* shape \(5,\)",
        ),
        (
            "nan position",
            lambda w: w.set_pose("blockA", (nan, 0, 0.05)),
            "not finite|NaN",
        ),
        ("far position", lambda w: w.set_pose("blockA", (1e9, 0, 0.05)), "beyond"),
        (
            "zero quaternion",
            lambda w: w.set_pose("blockA", (0, 0, 0.05), (0, 0, 0, 0)),
            "zero length",
        ),
        (
            "inf quaternion",
            lambda w: w.set_pose("blockA", (0, 0, 0.05), (0, 0, inf, 1)),
            "not finite|inf",
        ),
        ("rate", lambda w: w.set_publish_rate(7), "7 Hz does not divide 1000"),
        ("zero rate", lambda w: w.set_publish_rate(0), "publish_rate"),
        ("negative seed", lambda w: w.latency_seed(-1), "out of range"),
        ("state before advance", lambda w: w.state(), "no state yet"),
    ]


@pytest.mark.parametrize(
    ("what", "call", "match"), refusals(), ids=[r[0] for r in refusals()]
)
def test_bad_input_raises_naming_the_problem(
    what: str, call: Callable[[World], Any], match: str
) -> None:
    world = World(latency_max=2)
    with pytest.raises(ValueError, match=match):
        call(world)
    # Nothing happened: the world still steps from its start.
    assert world.advance()[1, :3].tolist() == pytest.approx([0.0, 0.25, 0.05], abs=1e-6)


def test_bad_worlds_and_commands_out_of_turn_are_refused() -> None:
    with pytest.raises(ValueError, match="unknown built-in scene `moon`"):
        World("moon")
    with pytest.raises(ValueError, match="does not divide 1000"):
        World(publish_rate=3)
    with pytest.raises(ValueError, match="does not emulate latency"):
        World().latency_seed(1)
    world = World()
    world.pause()
    with pytest.raises(ValueError, match="paused"):
        world.advance()
    world.unpause()
    assert world.advance().shape == (2, 13)
    with pytest.raises(ValueError, match="at least one World"):
        Worlds([])
    with pytest.raises(ValueError, match="same bodies"):
        Worlds([World(), World("two_blocks")])
    worlds = Worlds([World(), World()])
    with pytest.raises(ValueError, match=r"shape \(2, 2\)"):
        worlds.move_and_advance(np.zeros((3, 2)))
    with pytest.raises(ValueError, match=r"velocities\[1\] is not finite"):
        worlds.move_and_advance(np.array([[0.0, 0.0], [math.nan, 0.0]]))
    with pytest.raises(ValueError, match="stepped must have 2"):
        worlds.move_and_advance(np.zeros((2, 2)), stepped=[True])


def test_worlds_move_and_advance_steps_no_world_when_one_would_refuse() -> None:
    """Issue 49, item 7: with the second world paused, the first stepped and then
    the call raised, though everything is meant to be checked before any world
    steps. A world listed twice is refused (one step locks every world)."""
    first, second = World(), World()
    first.advance()
    second.advance()
    before = first.counters()
    second.pause()
    worlds = Worlds([first, second])
    with pytest.raises(ValueError, match="world 1: advance: the world is paused"):
        worlds.move_and_advance(np.array([[0.1, 0.0], [0.1, 0.0]]))
    assert first.counters() == before, "the first world did not step"
    never = World()
    with pytest.raises(ValueError, match="world 1: no state yet"):
        Worlds([first, never]).move_and_advance(
            np.array([[0.1, 0.0], [0.0, 0.0]]), stepped=[True, False]
        )
    assert first.counters() == before
    second.unpause()
    assert worlds.move_and_advance(np.zeros((2, 2))).shape == (2, 2, 13)
    assert first.counters()[0] == before[0] + 10
    with pytest.raises(ValueError, match="the same World"):
        Worlds([first, first])


def test_a_flood_of_moves_without_an_advance_is_refused_busy() -> None:
    """Issue 49, item 1, in-process: with latency emulation every Move waits for
    the next Advance, and a million of them took 45 → 202 MB. The daemon's bound
    on waiting commands now holds in the embedded world too."""
    world = World(latency_max=2)
    accepted = 0
    with pytest.raises(ValueError, match="^busy: 65536 accepted commands"):
        for _ in range(70_000):
            world.move(0.1, 0.0)
            accepted += 1
    assert accepted == 65_536
    world.advance()
    world.move(0.1, 0.0)


FORKS = """
import os, sys, threading, time
from pushlearn import World

stepping = World()
running = True

def step() -> None:
    while running:
        stepping.move_and_advance(0.1, 0.0)

threading.Thread(target=step, daemon=True).start()
time.sleep(0.2)
children = []
for _ in range(20):
    pid = os.fork()
    if pid == 0:
        code = 2
        try:
            World().advance()
            try:
                stepping.advance()
                code = 0
            except RuntimeError as err:
                code = 0 if "when the process forked" in str(err) else 3
        finally:
            os._exit(code)
    children.append(pid)
deadline = time.monotonic() + 60
hung = failed = 0
for pid in children:
    while True:
        done, status = os.waitpid(pid, os.WNOHANG)
        if done:
            failed += os.waitstatus_to_exitcode(status) != 0
            break
        if time.monotonic() > deadline:
            os.kill(pid, 9)
            os.waitpid(pid, 0)
            hung += 1
            break
        time.sleep(0.01)
running = False
print(f"hung {hung} failed {failed}")
"""


def test_a_fork_while_another_thread_steps_a_world_leaves_a_working_child() -> None:
    """Issue 49, item 4: 16 of 20 children forked while another thread stepped
    a world hung (a lock held at the fork). The extension now holds the worlds'
    locks across every fork (os.register_at_fork): a child can make and step
    new worlds, and the parent's world either works or says it was in use."""
    done = run_python(FORKS, timeout=3 * LIMIT)
    assert "hung 0 failed 0" in done.stdout, done.stdout + done.stderr


def test_a_scene_that_is_not_a_regular_file_is_refused_without_reading_it(
    tmp_path: Path,
) -> None:
    """Issue 49, item 12: World(scene) read a FIFO for ever holding the GIL, and
    /dev/zero until memory ran out."""
    fifo = tmp_path / "scene.fifo"
    os.mkfifo(fifo)
    snippet = (
        "from pushlearn import World\n"
        f"for path in [{str(fifo)!r}, '/dev/zero']:\n"
        "    try:\n"
        "        World(path)\n"
        "    except ValueError as err:\n"
        "        print('refused:', err)\n"
    )
    done = run_python(snippet)
    assert done.stdout.count("not a regular file") == 2, done.stdout + done.stderr
