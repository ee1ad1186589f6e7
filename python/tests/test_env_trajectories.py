"""Recorded episodes of the Gymnasium environments, replayed bit for bit.

``data/env_trajectories.json`` was recorded from the environments as they
were before their step moved into Rust (issue 53): ``python
python/tests/test_env_trajectories.py --record`` writes it again. Every
observation, reward, flag and info of the same seeds and actions must stay
what it was, so a faster step cannot have changed what a learner sees.
"""

from __future__ import annotations

import json
import sys
from pathlib import Path
from typing import Any

import gymnasium as gym
import numpy as np
import pushlearn
import pytest

gym.register_envs(pushlearn)

RECORDED = Path(__file__).parent / "data" / "env_trajectories.json"

# (name, id, gymnasium.make keywords, seed, steps): short time limits so
# that truncations and the resets after them are recorded; a target at the
# block's start so that a success, its reward and its termination are too.
SINGLE: list[tuple[str, str, dict[str, Any], int, int]] = [
    ("block-sparse", "pushlearn/PushBlock-v0", {"max_episode_steps": 40}, 7, 100),
    (
        "two-blocks-dense",
        "pushlearn/PushTwoBlocks-v0",
        {"max_episode_steps": 30, "reward_type": "dense"},
        11,
        70,
    ),
    (
        "block-reached",
        "pushlearn/PushBlock-v0",
        {"targets": [(0.0, 0.25, 0.0)], "reward_type": "sparse"},
        3,
        6,
    ),
    (
        "block-no-latency-region",
        "pushlearn/PushBlock-v0",
        {"latency_max": None, "targets": "region", "max_episode_steps": 20},
        5,
        45,
    ),
]

VECTOR: list[tuple[str, str, dict[str, Any], int, int, int]] = [
    ("vector-block", "pushlearn/PushBlock-v0", {"max_episode_steps": 25}, 2, 4, 60),
    (
        "vector-two-blocks-dense",
        "pushlearn/PushTwoBlocks-v0",
        {"max_episode_steps": 15, "reward_type": "dense"},
        3,
        3,
        35,
    ),
    ("vector-one", "pushlearn/PushBlock-v0", {"max_episode_steps": 10}, 1, 1, 25),
]


def _plain(value: Any) -> Any:
    """JSON's form of an observation, flag or info (floats keep every bit: repr round-trips)."""
    if isinstance(value, dict):
        return {key: _plain(v) for key, v in value.items()}
    if isinstance(value, tuple | list):
        return [_plain(v) for v in value]
    if isinstance(value, np.ndarray):
        return {"dtype": str(value.dtype), "values": value.tolist()}
    if isinstance(value, np.generic):
        return {"numpy": type(value).__name__, "value": value.item()}
    return {"type": type(value).__name__, "value": value}


def _actions(seed: int, shape: tuple[int, ...]) -> np.ndarray:
    return np.random.default_rng(seed).uniform(-1.0, 1.0, shape).astype(np.float32)


def run_single(env_id: str, kwargs: dict[str, Any], seed: int, steps: int) -> list[Any]:
    """One environment's reset and ``steps`` steps, reset again whenever an episode ends."""
    env = gym.make(env_id, **kwargs)
    try:
        record: list[Any] = [_plain(env.reset(seed=seed))]
        for action in _actions(seed, (steps, 2)):
            result = env.step(action)
            record.append(_plain(result))
            if result[2] or result[3]:
                record.append(_plain(env.reset()))
        return record
    finally:
        env.close()


def run_vector(
    env_id: str, kwargs: dict[str, Any], seed: int, envs: int, steps: int
) -> list[Any]:
    """A native vector environment's reset and ``steps`` steps (autoreset included)."""
    vector = gym.make_vec(env_id, num_envs=envs, **kwargs)
    try:
        record: list[Any] = [_plain(vector.reset(seed=seed))]
        for actions in _actions(seed, (steps, envs, 2)):
            record.append(_plain(vector.step(actions)))
        return record
    finally:
        vector.close()


def record_all() -> dict[str, Any]:
    """Every episode of :data:`SINGLE` and :data:`VECTOR`, by name."""
    episodes: dict[str, Any] = {}
    for name, env_id, kwargs, seed, steps in SINGLE:
        episodes[name] = run_single(env_id, kwargs, seed, steps)
    for name, env_id, kwargs, seed, envs, steps in VECTOR:
        episodes[name] = run_vector(env_id, kwargs, seed, envs, steps)
    return episodes


@pytest.fixture(scope="module")
def recorded() -> dict[str, Any]:
    loaded: dict[str, Any] = json.loads(RECORDED.read_text(encoding="utf-8"))
    return loaded


@pytest.mark.parametrize(("name", "env_id", "kwargs", "seed", "steps"), SINGLE)
def test_an_environment_replays_its_recorded_episodes_bit_for_bit(
    recorded: dict[str, Any],
    name: str,
    env_id: str,
    kwargs: dict[str, Any],
    seed: int,
    steps: int,
) -> None:
    replayed = json.loads(json.dumps(run_single(env_id, kwargs, seed, steps)))
    expected = recorded[name]
    assert len(replayed) == len(expected)
    for i, (now, then) in enumerate(zip(replayed, expected, strict=True)):
        assert now == then, f"{name}, entry {i}"


@pytest.mark.parametrize(("name", "env_id", "kwargs", "seed", "envs", "steps"), VECTOR)
def test_a_native_vector_environment_replays_its_recorded_episodes_bit_for_bit(
    recorded: dict[str, Any],
    name: str,
    env_id: str,
    kwargs: dict[str, Any],
    seed: int,
    envs: int,
    steps: int,
) -> None:
    replayed = json.loads(json.dumps(run_vector(env_id, kwargs, seed, envs, steps)))
    expected = recorded[name]
    assert len(replayed) == len(expected)
    for i, (now, then) in enumerate(zip(replayed, expected, strict=True)):
        assert now == then, f"{name}, entry {i}"


def test_the_recording_holds_successes_truncations_and_resets(
    recorded: dict[str, Any],
) -> None:
    # The replay tests are only as strong as what was recorded: every kind
    # of step result must be in it.
    steps = [e for e in recorded["block-reached"] if len(e) == 5]
    assert any(s[2]["value"] for s in steps), "no termination recorded"
    assert any(s[1]["value"] == 0.0 for s in steps), "no success reward recorded"
    truncated = [e for e in recorded["block-sparse"] if len(e) == 5 and e[3]["value"]]
    assert len(truncated) == 2
    vector_truncations = sum(
        sum(e[3]["values"]) for e in recorded["vector-block"] if len(e) == 5
    )
    assert vector_truncations == 8  # each of 4 envs at steps 25 and 51


if __name__ == "__main__":
    if sys.argv[1:] != ["--record"]:
        sys.exit("usage: python python/tests/test_env_trajectories.py --record")
    RECORDED.parent.mkdir(exist_ok=True)
    RECORDED.write_text(json.dumps(record_all(), indent=None) + "\n", encoding="utf-8")
