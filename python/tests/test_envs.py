"""The Gymnasium environments (pushlearn.envs) on the in-process world and the real world daemon."""

from __future__ import annotations

import gc
import math
import os
import signal
import subprocess
import sys
import time
import warnings
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any, cast

import gymnasium as gym
import numpy as np
import pushlearn
import pytest
from conftest import LIMIT, Daemon, python_env
from gymnasium.utils.env_checker import check_env
from pushlearn import local_world
from pushlearn.envs import ENV_IDS
from pushlearn.envs.push import (
    ACTUATOR_SPEED,
    REACHED,
    THESIS_TARGETS,
    PushBlockEnv,
    TargetRegion,
    _goal_distances_one,
    goal_distances,
)
from pushlearn.local_world import LocalWorld, SimNotFound, find_sim_binary

gym.register_envs(pushlearn)

BLUE = (0x1F, 0x5F, 0xD0)
GREY = (0x44, 0x44, 0x44)


def process_gone(pid: int, within: float = 10.0) -> bool:
    """Whether process ``pid`` has ended (and been reaped) within ``within`` seconds."""
    deadline = time.monotonic() + within
    while time.monotonic() < deadline:
        try:
            os.kill(pid, 0)
        except ProcessLookupError:
            return True
        # A child of this process lingers as a zombie until it is reaped.
        try:
            if os.waitpid(pid, os.WNOHANG) != (0, 0):
                return True
        except ChildProcessError:
            pass
        time.sleep(0.02)
    return False


@pytest.fixture
def make() -> Iterator[Callable[..., Any]]:
    """``gymnasium.make`` (the world in this process unless ``sim`` says otherwise);
    closes every env at the end."""
    made: list[Any] = []

    def make_env(env_id: str = "pushlearn/PushBlock-v0", **kwargs: Any) -> Any:
        env = gym.make(env_id, **kwargs)
        made.append(env)
        return env

    yield make_env
    for env in made:
        env.close()


@pytest.mark.parametrize("daemon", [False, True], ids=["in-process", "daemon"])
@pytest.mark.parametrize("env_id", ENV_IDS)
def test_gymnasiums_own_checker_passes(
    env_id: str, daemon: bool, request: pytest.FixtureRequest
) -> None:
    where: dict[str, Any] = {}
    if daemon:
        where = {"sim": "daemon", "sim_bin": str(request.getfixturevalue("sim_bin"))}
    env = gym.make(env_id, render_mode="rgb_array", **where)
    try:
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            check_env(env.unwrapped)
        # Its only remarks are on the unbounded positions and velocities: the
        # world has no walls, and a bound it might break would be a lie.
        remarks = {str(w.message) for w in caught}
        assert {r for r in remarks if "infinity" not in r} == set()
    finally:
        env.close()


def test_the_spaces_and_the_registration_follow_the_goal_conventions(
    make: Callable[..., Any],
) -> None:
    env = make()
    assert env.spec.max_episode_steps == 3000
    assert set(env.observation_space.spaces) == {
        "observation",
        "achieved_goal",
        "desired_goal",
    }
    assert env.observation_space["observation"].shape == (10,)
    assert env.observation_space["achieved_goal"].shape == (3,)
    assert env.action_space.shape == (2,)
    assert (
        float(env.action_space.low[0]) == -1.0
        and float(env.action_space.high[0]) == 1.0
    )
    two = make("pushlearn/PushTwoBlocks-v0")
    assert two.observation_space["observation"].shape == (16,)
    assert two.observation_space["desired_goal"].shape == (6,)


def run_episode(env: Any, seed: int, actions: np.ndarray) -> list[bytes]:
    observation, _ = env.reset(seed=seed)
    frames = [b"".join(v.tobytes() for v in observation.values())]
    for action in actions:
        observation, reward, terminated, truncated, _ = env.step(action)
        frames.append(b"".join(v.tobytes() for v in observation.values()))
        frames.append(np.float64(reward).tobytes())
        if terminated or truncated:
            break
    return frames


@pytest.mark.parametrize("env_id", ENV_IDS)
def test_the_same_seed_and_actions_give_the_same_episode_bit_for_bit(
    env_id: str, make: Callable[..., Any]
) -> None:
    # Pushing actions (the actuator moves through the block's start), so the
    # latency emulation's draws decide the contacts.
    rng = np.random.default_rng(5)
    actions = np.column_stack([rng.uniform(-0.3, 0.3, 400), np.full(400, 1.0)]).astype(
        np.float32
    )
    first, second = make(env_id), make(env_id)
    a = run_episode(first, 7, actions)
    b = run_episode(second, 7, actions)
    assert len(a) == len(b) and a == b
    # The same env again, after an episode with another seed.
    run_episode(first, 8, actions[:50])
    assert run_episode(first, 7, actions) == a
    # Another seed draws another latency stream (and target): the episode differs.
    assert run_episode(second, 8, actions) != a


@pytest.mark.parametrize("env_id", ENV_IDS)
def test_the_in_process_world_gives_the_daemons_episodes_bit_for_bit(
    env_id: str, make: Callable[..., Any], sim_bin: Path
) -> None:
    rng = np.random.default_rng(6)
    actions = np.column_stack([rng.uniform(-0.3, 0.3, 300), np.full(300, 1.0)]).astype(
        np.float32
    )
    options = {"show_target": True, "reward_type": "dense"}
    in_process = make(env_id, **options)
    daemon = make(env_id, sim="daemon", sim_bin=str(sim_bin), **options)
    assert in_process.unwrapped.in_process and not daemon.unwrapped.in_process
    assert run_episode(in_process, 3, actions) == run_episode(daemon, 3, actions)
    # The full world states too, ghosts included.
    mine, theirs = in_process.unwrapped.state, daemon.unwrapped.state
    assert [b.name for b in mine.bodies] == [b.name for b in theirs.bodies]
    assert mine.bodies == theirs.bodies and mine.step == theirs.step
    # A start elsewhere, through the reset's set_pose.
    start = {"actuator": (0.2, -0.1)}
    a, _ = in_process.reset(seed=4, options=start)
    b, _ = daemon.reset(seed=4, options=start)
    assert all(a[key].tobytes() == b[key].tobytes() for key in b)


def test_the_world_moves_the_actuator_at_the_thesis_speed(
    make: Callable[..., Any],
) -> None:
    env = make(latency_max=None)
    env.reset(seed=0)
    for _ in range(20):
        observation, *_ = env.step(np.array([1.0, 0.0], dtype=np.float32))
    actuator = observation["observation"]
    # The world sets the velocity before each step; what it reports is after
    # the step's integration (a 1e-4 relative loss).
    assert actuator[2] == pytest.approx(ACTUATOR_SPEED, rel=1e-3)
    assert actuator[3] == pytest.approx(0.0, abs=1e-9)
    # 20 messages of 10 ms at 0.5 m/s; each Move is in force for its whole message.
    assert actuator[0] == pytest.approx(20 * 0.01 * ACTUATOR_SPEED, rel=1e-3)
    # Out-of-box actions are clipped, and the world caps a diagonal at 0.5 m/s.
    observation, *_ = env.step(np.array([5.0, 5.0], dtype=np.float32))
    speed = math.hypot(*observation["observation"][2:4])
    assert speed == pytest.approx(ACTUATOR_SPEED, rel=1e-3)


def test_a_reached_target_is_a_success_with_the_sparse_and_dense_rewards(
    make: Callable[..., Any],
) -> None:
    sparse = make(latency_max=None)
    observation, info = sparse.reset(seed=0)
    start = observation["achieved_goal"].copy()
    # A target within the criterion of the block's start: reached at once.
    near = start + np.array([0.006, 0.0, 0.006])
    observation, info = sparse.reset(options={"target": near})
    assert info["is_success"] and info["distance"] < REACHED
    _, reward, terminated, truncated, info = sparse.step(np.zeros(2, dtype=np.float32))
    assert (reward, terminated, truncated, info["is_success"]) == (
        0.0,
        True,
        False,
        True,
    )
    # Just outside it: −1 per step, and no end.
    far = start + np.array([0.008, 0.0, 0.008])
    sparse.reset(options={"target": far})
    _, reward, terminated, _, info = sparse.step(np.zeros(2, dtype=np.float32))
    assert (reward, terminated, info["is_success"]) == (-1.0, False, False)
    dense = make(latency_max=None, reward_type="dense")
    dense.reset(options={"target": far})
    _, reward, _, _, info = dense.step(np.zeros(2, dtype=np.float32))
    assert reward == pytest.approx(-math.hypot(0.008, 0.008), rel=1e-6)
    assert reward == -info["distance"]
    kept_going = make(latency_max=None, terminate_on_success=False)
    kept_going.reset(options={"target": near})
    _, reward, terminated, _, _ = kept_going.step(np.zeros(2, dtype=np.float32))
    assert (reward, terminated) == (0.0, False)


@pytest.mark.parametrize("reward_type", ["sparse", "dense"])
def test_compute_reward_on_a_batch_gives_the_steps_rewards(
    reward_type: str, make: Callable[..., Any]
) -> None:
    env = make("pushlearn/PushTwoBlocks-v0", reward_type=reward_type)
    observation, _ = env.reset(seed=3)
    achieved, desired, rewards = [], [], []
    rng = np.random.default_rng(0)
    for _ in range(200):
        observation, reward, *_ = env.step(rng.uniform(-1, 1, 2).astype(np.float32))
        achieved.append(observation["achieved_goal"])
        desired.append(observation["desired_goal"])
        rewards.append(reward)
    batch = env.unwrapped.compute_reward(np.array(achieved), np.array(desired), {})
    assert batch.shape == (200,)
    assert batch.tolist() == rewards


def test_the_one_goal_distance_is_the_batch_distance_bit_for_bit() -> None:
    rng = np.random.default_rng(11)
    achieved = rng.uniform(-4, 4, (2000, 6))
    desired = rng.uniform(-4, 4, (2000, 6))
    batch = goal_distances(achieved, desired)
    one = [
        _goal_distances_one(a.tolist(), d.tolist())
        for a, d in zip(achieved, desired, strict=True)
    ]
    assert batch.tolist() == one
    # The native batch (the vector environment's) is the harness's: the same bits.
    assert pushlearn.native().goal_distances(achieved, desired).tolist() == one
    with pytest.raises(ValueError, match="one shape"):
        pushlearn.native().goal_distances(achieved, desired[:, :5])
    # A yaw of π and one of −π are the same pose.
    assert goal_distances([0.0, 0.0, math.pi], [0.0, 0.0, -math.pi])[0] < 1e-12
    with pytest.raises(ValueError, match="one shape"):
        goal_distances([0.0, 0.0, 0.0], [0.0, 0.0])


def test_the_environments_judge_success_as_the_harness_does_bit_for_bit() -> None:
    native = pushlearn.native()
    assert native.GOAL_TOLERANCE == REACHED
    rng = np.random.default_rng(12)
    for _ in range(2000):
        pose = rng.uniform([-1, -1, -math.pi], [1, 1, math.pi])
        target = rng.uniform([-1, -1, -math.pi], [1, 1, math.pi])
        # Near the target too, where success is decided.
        if rng.random() < 0.5:
            pose = target + rng.uniform(-0.01, 0.01, 3)
        ours = _goal_distances_one(pose.tolist(), target.tolist())[0]
        theirs = native.goal_distance(tuple(pose.tolist()), tuple(target.tolist()))
        assert ours == theirs, (pose, target)


def test_targets_come_from_the_thesis_or_the_region(make: Callable[..., Any]) -> None:
    thesis = make()
    seen = set()
    for seed in range(40):
        observation, _ = thesis.reset(seed=seed)
        seen.add(tuple(observation["desired_goal"].tolist()))
    assert seen == set(THESIS_TARGETS)
    region = TargetRegion()
    sampled = make("pushlearn/PushTwoBlocks-v0")
    for seed in range(30):
        goal = sampled.reset(seed=seed)[0]["desired_goal"]
        (ax, ay, at), (bx, by, bt) = goal[:3], goal[3:]
        for x, y, theta, start in (
            (ax, ay, at, (0.0, 0.25)),
            (bx, by, bt, (-0.6, 0.35)),
        ):
            assert region.x[0] <= x <= region.x[1] and region.y[0] <= y <= region.y[1]
            assert -math.pi <= theta <= math.pi
            assert math.hypot(x - start[0], y - start[1]) >= region.min_travel
        assert math.hypot(ax - bx, ay - by) >= region.min_apart
    fixed = make(targets=[(0.1, 0.2, 0.3)])
    assert fixed.reset(seed=0)[0]["desired_goal"].tolist() == [0.1, 0.2, 0.3]


def test_the_actuator_can_start_elsewhere(make: Callable[..., Any]) -> None:
    env = make()
    observation, _ = env.reset(seed=0, options={"actuator": (0.24, 0.5)})
    assert observation["observation"][:2].tolist() == pytest.approx([0.24, 0.5])
    observation, _ = env.reset(seed=0)
    assert observation["observation"][:2].tolist() == [0.0, 0.0]


def test_rgb_array_draws_the_bodies_and_the_target_like_the_viewer(
    make: Callable[..., Any],
) -> None:
    env = make(render_mode="rgb_array", latency_max=None)
    env.reset(options={"target": (-0.6, -0.7, 0.0)})
    image = env.render()
    assert image.shape == (480, 480, 3) and image.dtype == np.uint8
    canvas = env.unwrapped._canvas
    # The block (0.5 × 0.1 m at (0, 0.25)) filled: its centre and near its ends.
    for x in (0.0, 0.22, -0.22):
        assert tuple(image[canvas.pixel(x, 0.25)]) == BLUE
    assert tuple(image[canvas.pixel(0.0, 0.33)]) != BLUE  # beyond its 0.05 m half-width
    assert tuple(image[canvas.pixel(0.0, 0.0)]) == GREY  # the actuator
    # The target only outlined: its edge blue, its centre not.
    assert tuple(image[canvas.pixel(-0.6, -0.7 + 0.05)]) == BLUE
    assert tuple(image[canvas.pixel(-0.6, -0.7)]) != BLUE
    # A fresh picture each call, drawn after the block moved.
    for _ in range(30):
        env.step(np.array([0.0, 1.0], dtype=np.float32))
    moved = env.render()
    assert moved is not image and not np.array_equal(moved, image)


def test_close_is_idempotent_and_stops_the_world(
    make: Callable[..., Any], sim_bin: Path
) -> None:
    env = make(sim="daemon", sim_bin=str(sim_bin))
    pid = env.unwrapped.world_pid
    env.reset(seed=0)
    env.close()
    env.close()
    assert process_gone(pid)
    with pytest.raises(RuntimeError, match="closed"):
        env.unwrapped.reset()


def test_a_closed_in_process_env_says_so(make: Callable[..., Any]) -> None:
    env = make()
    env.reset(seed=0)
    env.step(np.zeros(2, dtype=np.float32))
    env.close()
    env.close()
    with pytest.raises(RuntimeError, match="closed"):
        env.unwrapped.reset()
    with pytest.raises(RuntimeError, match="closed"):
        env.unwrapped.step(np.zeros(2))
    with pytest.raises(RuntimeError, match="closed"):
        _ = env.unwrapped.state


def test_a_garbage_collected_env_stops_its_world(sim_bin: Path) -> None:
    env = gym.make("pushlearn/PushBlock-v0", sim_bin=str(sim_bin))
    env.reset(seed=0)
    pid = cast(PushBlockEnv, env.unwrapped).world_pid
    assert pid is not None
    del env
    gc.collect()
    assert process_gone(pid)


def test_a_killed_python_process_leaves_no_world_behind(sim_bin: Path) -> None:
    script = (
        "import gymnasium as gym, pushlearn, sys, time\n"
        f"env = gym.make('pushlearn/PushBlock-v0', sim_bin={str(sim_bin)!r})\n"
        "env.reset(seed=0)\n"
        "print(env.unwrapped.world_pid, flush=True)\n"
        "time.sleep(60)\n"
    )
    child = subprocess.Popen(
        [sys.executable, "-c", script],
        stdout=subprocess.PIPE,
        env=python_env(),
        text=True,
    )
    try:
        assert child.stdout is not None
        world = int(child.stdout.readline())
        os.kill(world, 0)  # running
        child.send_signal(signal.SIGKILL)
        child.wait(LIMIT)
        assert process_gone(world), f"the world {world} outlived its killed owner"
    finally:
        child.kill()
        child.wait()


def test_a_vector_env_runs_one_world_per_env_and_stops_them_all(sim_bin: Path) -> None:
    envs = gym.vector.AsyncVectorEnv(
        [lambda: gym.make("pushlearn/PushBlock-v0", sim_bin=str(sim_bin))] * 2
    )
    try:
        observations, _ = envs.reset(seed=1)
        assert observations["observation"].shape == (2, 10)
        pids = envs.get_attr("world_pid")
        assert len(set(pids)) == 2
        down = np.array([[0.0, -1.0], [0.0, -1.0]], dtype=np.float32)
        for _ in range(50):
            observations, rewards, *_ = envs.step(down)
        assert rewards.shape == (2,)
        # Each world moved its actuator: 50 messages of 10 ms at 0.5 m/s.
        assert observations["observation"][:, 1] == pytest.approx(
            [-0.25, -0.25], rel=1e-2
        )
    finally:
        envs.close()
    assert all(process_gone(pid) for pid in pids)


@pytest.mark.parametrize("daemon", [False, True], ids=["in-process", "daemon"])
@pytest.mark.parametrize("env_id", ENV_IDS)
def test_the_native_vector_env_steps_as_gymnasiums_sync_vector_env_bit_for_bit(
    env_id: str, daemon: bool, request: pytest.FixtureRequest
) -> None:
    # A short time limit, so that truncation and the next step's autoreset happen.
    kwargs: dict[str, Any] = {"max_episode_steps": 25}
    if daemon:
        kwargs |= {"sim": "daemon", "sim_bin": str(request.getfixturevalue("sim_bin"))}
    native = gym.make_vec(env_id, num_envs=3, **kwargs)
    sync = gym.make_vec(env_id, num_envs=3, vectorization_mode="sync", **kwargs)
    try:
        assert type(native).__name__.endswith("VectorEnv") and native is not sync
        pids = cast(Any, native).world_pids
        assert len(set(pids)) == (3 if daemon else 1)
        rng = np.random.default_rng(2)
        first = native.reset(seed=4), sync.reset(seed=4)
        for (obs_native, _), (obs_sync, _) in [first]:
            for key in obs_sync:
                assert obs_native[key].tobytes() == obs_sync[key].tobytes()
        truncated_seen = 0
        for _ in range(60):
            actions = rng.uniform(-1, 1, (3, 2)).astype(np.float32)
            a = native.step(actions)
            b = sync.step(actions)
            for key in b[0]:
                assert a[0][key].tobytes() == b[0][key].tobytes(), key
                assert a[0][key].dtype == b[0][key].dtype, key
            for x, y in zip(a[1:4], b[1:4], strict=True):
                assert x.tolist() == y.tolist()
                assert x.dtype == y.dtype
            for key in b[4]:
                assert a[4][key].tobytes() == b[4][key].tobytes(), key
            truncated_seen += int(a[3].sum())
        assert truncated_seen == 6  # each env at steps 25 and 51
        with pytest.raises(ValueError, match="not finite"):
            native.step(np.array([[0, 0], [math.nan, 0], [0, 0]], dtype=np.float32))
        native.step(np.zeros((3, 2), dtype=np.float32))  # still serving
    finally:
        native.close()
        sync.close()
    assert all(pid is None or process_gone(pid) for pid in pids)


def test_a_running_world_can_be_used_when_it_fits(
    start_sim: Callable[..., Daemon], make: Callable[..., Any]
) -> None:
    daemon = start_sim("--mode", "lockstep", "--latency-max", "2")
    env = make(sim=f"127.0.0.1:{daemon.port}")
    assert env.unwrapped.world_pid is None
    observation, _ = env.reset(seed=0)
    assert observation["achieved_goal"][1] == pytest.approx(0.25)
    env.close()
    assert daemon.child.process.poll() is None  # a world it did not start keeps running
    with pytest.raises(
        ValueError, match="it has latency_max 2, this environment was asked for no"
    ):
        make(sim=f"127.0.0.1:{daemon.port}", latency_max=None).reset()
    with pytest.raises(ValueError, match="its scene is 'one_block'"):
        make("pushlearn/PushTwoBlocks-v0", sim=f"127.0.0.1:{daemon.port}")


def test_bad_arguments_are_refused_with_the_reason(make: Callable[..., Any]) -> None:
    with pytest.raises(ValueError, match="reward_type must be"):
        make(reward_type="shaped")
    with pytest.raises(ValueError, match="render_mode must be"):
        PushBlockEnv(render_mode="ansi")
    with pytest.raises(ValueError, match="must have 3 numbers"):
        make(targets=[(0.1, 0.2)])
    with pytest.raises(ValueError, match="one of"):
        make("pushlearn/PushTwoBlocks-v0", targets="thesis")
    with pytest.raises(ValueError, match="latency_max must be"):
        make(latency_max=-1)
    with pytest.raises(ValueError, match="sim must be None, 'daemon' or HOST:PORT"):
        make(sim="localhost")
    env = make()
    env.reset(seed=0)
    with pytest.raises(ValueError, match="must be finite"):
        env.unwrapped.step(np.array([math.nan, 0.0]))
    with pytest.raises(ValueError, match="shape"):
        env.unwrapped.step(np.zeros(3))
    with pytest.raises(ValueError, match="unknown reset options"):
        env.reset(options={"goal": (0, 0, 0)})
    with pytest.raises(ValueError, match="must be finite"):
        env.reset(options={"target": (0.0, math.inf, 0.0)})
    # After the refusals the env still works.
    observation, *_ = env.step(np.zeros(2, dtype=np.float32))
    assert observation["observation"].shape == (10,)


def test_a_missing_binary_says_where_it_looked(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    with pytest.raises(SimNotFound, match="is not a file"):
        find_sim_binary(tmp_path / "nothing")
    monkeypatch.setenv("PUSHLEARN_SIM_BIN", str(tmp_path / "nothing"))
    with pytest.raises(SimNotFound, match="PUSHLEARN_SIM_BIN is"):
        find_sim_binary()


def test_the_binary_the_package_carries_comes_before_path(
    monkeypatch: pytest.MonkeyPatch, tmp_path: Path
) -> None:
    carried = tmp_path / "_bin" / "pushlearn-sim"
    carried.parent.mkdir()
    carried.write_text("")
    on_path = tmp_path / "bin" / "pushlearn-sim"
    on_path.parent.mkdir()
    on_path.write_text("#!/bin/sh\n")
    on_path.chmod(0o755)
    monkeypatch.delenv("PUSHLEARN_SIM_BIN", raising=False)
    monkeypatch.setenv("PATH", str(on_path.parent))
    monkeypatch.setattr(local_world, "packaged", lambda name: tmp_path / "_bin" / name)
    assert find_sim_binary() == carried
    carried.unlink()
    monkeypatch.setattr(sys, "executable", str(tmp_path / "python"))
    assert find_sim_binary() == on_path


def test_without_a_binary_on_path_the_checkout_the_package_was_built_from_is_used(
    monkeypatch: pytest.MonkeyPatch, tmp_path: Path
) -> None:
    native = pytest.importorskip("pushlearn._native")
    monkeypatch.delenv("PUSHLEARN_SIM_BIN", raising=False)
    monkeypatch.delenv("CARGO_TARGET_DIR", raising=False)
    monkeypatch.setenv("PATH", str(tmp_path))
    # Neither the package's own binary (an installed wheel's) nor the console
    # script beside the venv's Python that runs it.
    monkeypatch.setattr(local_world, "packaged", lambda name: tmp_path / "_bin" / name)
    monkeypatch.setattr(sys, "executable", str(tmp_path / "python"))
    expected = (
        Path(native.SOURCE_CHECKOUT).resolve() / "target" / "release" / "pushlearn-sim"
    )
    if not expected.is_file():
        with pytest.raises(SimNotFound, match=str(expected)):
            find_sim_binary()
    else:
        assert find_sim_binary() == expected
    # Where cargo put the build when CARGO_TARGET_DIR says so.
    built = tmp_path / "target-dir" / "release" / "pushlearn-sim"
    built.parent.mkdir(parents=True)
    built.write_text("")
    monkeypatch.setenv("CARGO_TARGET_DIR", str(tmp_path / "target-dir"))
    assert find_sim_binary() == built


def test_a_world_that_does_not_start_is_reported_with_its_message(
    sim_bin: Path,
) -> None:
    with pytest.raises(RuntimeError, match="no_such_scene"):
        LocalWorld(scene="no_such_scene", sim_bin=sim_bin)


def test_bad_reset_options_and_regions_are_refused_not_looped_on(
    make: Callable[..., Any],
) -> None:
    """Issue 49, item 8: an unsatisfiable region looped forever in ``reset``;
    an actuator placed at (999, 999) was accepted and never moved again; a
    target of (1e300, 1e300) was accepted."""
    env = make(targets="region", region=TargetRegion(x=(0.0, 0.1), y=(0.2, 0.3)))
    with pytest.raises(ValueError, match="has no room for a target"):
        env.reset(seed=0)
    env = make()
    with pytest.raises(ValueError, match="outside its drive bound"):
        env.reset(seed=0, options={"actuator": (999.0, 999.0)})
    with pytest.raises(ValueError, match="must lie in the world"):
        env.reset(seed=0, options={"target": (1e300, 1e300, 0.0)})
    # The environment is still usable after each refusal.
    observation, _ = env.reset(seed=0, options={"actuator": (0.24, 0.5)})
    assert observation["observation"][:2].tolist() == pytest.approx([0.24, 0.5])
    bad_regions: list[dict[str, Any]] = [
        {"x": (0.5, 0.1)},
        {"y": (math.nan, 1.0)},
        {"x": (-1e300, 0.0)},
        {"min_travel": -1.0},
    ]
    for bad in bad_regions:
        with pytest.raises(ValueError, match="TargetRegion"):
            TargetRegion(**bad)


def test_the_step_in_rust_refuses_what_the_python_step_refused() -> None:
    world = pushlearn.World("one_block", latency_max=2)
    task = pushlearn.native().GoalTask(
        [world], 0, [1], speed=ACTUATOR_SPEED, dense=False, terminate_on_success=True
    )
    with pytest.raises(RuntimeError, match=r"call reset\(\) before step\(\)"):
        task.step(np.zeros(2, dtype=np.float32))
    world.advance()
    task.restart(0, (0.6, 0.7, -2.1))
    with pytest.raises(ValueError, match=r"an action has shape \(2,\), got \(3,\)"):
        task.step(np.zeros(3))
    with pytest.raises(ValueError, match=r"must be finite, got \[inf, 0\]"):
        task.step([math.inf, 0.0])
    with pytest.raises(ValueError, match="use step_all"):
        pushlearn.native().GoalTask(
            [world, pushlearn.World("one_block")],
            0,
            [1],
            speed=ACTUATOR_SPEED,
            dense=False,
            terminate_on_success=True,
        ).step(np.zeros(2))
    with pytest.raises(ValueError, match="row 5 is not a body"):
        pushlearn.native().GoalTask(
            [world],
            0,
            [5],
            speed=ACTUATOR_SPEED,
            dense=False,
            terminate_on_success=True,
        )
    with pytest.raises(ValueError, match="desired must have 3 numbers"):
        task.restart(0, (0.0, 0.0))
    # A float32 array (read as it is), the same numbers as float64 and as a
    # list (converted by numpy) are one action.
    action32 = np.array([0.3, -0.2], dtype=np.float32)
    observed = []
    for action in (action32, action32.astype(np.float64), action32.tolist()):
        fresh = pushlearn.World("one_block", latency_max=2)
        fresh.advance()
        one = pushlearn.native().GoalTask(
            [fresh], 0, [1], speed=ACTUATOR_SPEED, dense=True, terminate_on_success=True
        )
        one.restart(0, (0.6, 0.7, -2.1))
        observed.append(
            [one.step(action)[0]["observation"].tobytes() for _ in range(5)]
        )
    assert observed[0] == observed[1] == observed[2]
