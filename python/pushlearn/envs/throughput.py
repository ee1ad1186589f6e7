"""How many environment steps per second this machine does (``docs/performance.md`` §6).

::

    python -m pushlearn.envs.throughput [--steps 20000] [--repeats 5] [--envs 1,2,8]

Measures, each ``--repeats`` times (the median is printed, with the range):

* **physics floor**: the environment benchmark's actions stepped by the
  world library in Rust as Moves and Advances with nothing between them
  (:func:`pushlearn._native.step_messages`), the world reset where the
  environment's time limit resets it (every :data:`~pushlearn.envs.push.MAX_STEPS`
  messages): what stepping these messages costs; and, for comparison with
  figures measured before issue 53, the same messages without the resets
  (the actuator soon wanders off the block, which costs less);
* **env**: ``PushBlock-v0.step`` with pre-drawn random actions, as
  ``gymnasium.make`` wraps it (time limit, order enforcing, the passive
  checker), episodes reset as they end: on its in-process world (the
  default) and on a ``pushlearn-sim`` daemon of its own (``sim="daemon"``;
  left out when there is no binary);
* **vector, N envs**: ``gymnasium.make_vec`` of N environments, steps of all
  N counted: pushlearn's native vector environment (one process, N
  in-process worlds stepped in one call, :mod:`pushlearn.envs.vector`) and
  Gymnasium's ``AsyncVectorEnv`` (a process per environment, each with its
  in-process world).

Every figure is steps (messages) per second, its ratio to the physics
floor and to one environment, measured in the same run. Machine-dependent:
only the ratios of one run compare.
"""

from __future__ import annotations

import argparse
import os
import statistics
import sys
import time
from collections.abc import Callable, Sequence
from functools import partial
from typing import Any

import gymnasium as gym
import numpy as np

from .. import native
from ..local_world import SimNotFound, find_sim_binary
from . import register_envs
from .push import ACTUATOR_SPEED, MAX_STEPS


def _median_of(
    repeats: int, measure: Callable[[], float]
) -> tuple[float, float, float]:
    values = [measure() for _ in range(repeats)]
    return statistics.median(values), min(values), max(values)


def physics_floor(steps: int, episode_steps: int | None = MAX_STEPS) -> float:
    """Messages per second of the world library stepping the environment
    benchmark's actions in Rust, a Move and an Advance each, nothing between,
    reset where :func:`env_rate`'s time limit resets the environment: the
    states a push near the block's start reaches cost several times those
    of an actuator that has wandered off, so the floor steps the same ones.
    ``episode_steps=None``: no resets, the floor as measured before issue 53."""
    velocities = _actions(steps, 1)[:, 0].astype(np.float64) * ACTUATOR_SPEED
    seconds: float = native().step_messages(
        velocities, "one_block", latency_max=2, episode_steps=episode_steps
    )
    return steps / seconds


def _actions(steps: int, envs: int) -> np.ndarray:
    rng = np.random.default_rng(0)
    return rng.uniform(-1.0, 1.0, (steps, envs, 2)).astype(np.float32)


def env_rate(steps: int, **kwargs: Any) -> float:
    """Steps per second of one ``gymnasium.make``'d environment (``kwargs`` its options)."""
    env = gym.make("pushlearn/PushBlock-v0", **kwargs)
    actions = _actions(steps, 1)[:, 0]
    try:
        env.reset(seed=0)
        start = time.perf_counter()
        for action in actions:
            _, _, terminated, truncated, _ = env.step(action)
            if terminated or truncated:
                env.reset()
        return steps / (time.perf_counter() - start)
    finally:
        env.close()


def vector_rate(steps: int, envs: int, mode: str) -> float:
    """Steps per second of all environments of a vector environment together;
    ``mode`` is ``gymnasium.make_vec``'s (``"vector_entry_point"``: pushlearn's own)."""
    vector = gym.make_vec(
        "pushlearn/PushBlock-v0", num_envs=envs, vectorization_mode=mode
    )
    rounds = max(1, steps // envs)
    actions = _actions(rounds, envs)
    try:
        vector.reset(seed=0)
        start = time.perf_counter()
        for action in actions:
            vector.step(action)
        return rounds * envs / (time.perf_counter() - start)
    finally:
        vector.close()


def main(argv: Sequence[str] | None = None) -> int:
    """Runs the measurements and prints the table; returns the exit status."""
    parser = argparse.ArgumentParser(
        prog="python -m pushlearn.envs.throughput",
        description=(__doc__ or "").splitlines()[0],
    )
    parser.add_argument(
        "--steps", type=int, default=20000, help="steps per measurement"
    )
    parser.add_argument(
        "--repeats", type=int, default=5, help="measurements per row (median)"
    )
    parser.add_argument(
        "--envs", default="1,2,8", help="vector sizes, comma-separated (default 1,2,8)"
    )
    parser.add_argument(
        "--sim-bin", default=None, help="the pushlearn-sim for the daemon row"
    )
    args = parser.parse_args(argv)
    try:
        sizes = [int(n) for n in args.envs.split(",")]
    except ValueError:
        parser.error(f"--envs must be numbers separated by commas, got {args.envs!r}")
    if args.steps < 1 or args.repeats < 1 or any(n < 1 for n in sizes):
        parser.error("--steps, --repeats and every --envs size must be at least 1")
    register_envs()
    measured = partial(_median_of, args.repeats)
    rows: list[tuple[str, tuple[float, float, float]]] = []
    floor = measured(partial(physics_floor, args.steps))
    rows.append(("physics floor (world library, Moves and Advances in Rust)", floor))
    rows.append(
        (
            "physics floor without the resets (before issue 53)",
            measured(partial(physics_floor, args.steps, None)),
        )
    )
    one = measured(partial(env_rate, args.steps))
    rows.append(("env (gymnasium.make, 1 env, in-process world)", one))
    try:
        sim_bin = str(find_sim_binary(args.sim_bin))
    except SimNotFound as err:
        print(f"no daemon row: {err}", file=sys.stderr)
    else:
        rows.append(
            (
                'env (gymnasium.make, 1 env, sim="daemon")',
                measured(partial(env_rate, args.steps, sim="daemon", sim_bin=sim_bin)),
            )
        )
    for label, mode in (
        ("make_vec (native)", "vector_entry_point"),
        ("AsyncVectorEnv", "async"),
    ):
        for n in sizes:
            name = f"{label}, {n} env{'s' if n > 1 else ''}"
            rows.append((name, measured(partial(vector_rate, args.steps, n, mode))))
    print(
        f"{args.steps} steps per measurement, median of {args.repeats} (range), "
        f"{os.cpu_count()} cores"
    )
    print()
    print("| what | steps/s | range | ratio to the floor | ratio to 1 env |")
    print("|---|---|---|---|---|")
    for name, (median, low, high) in rows:
        print(
            f"| {name} | {median:.0f} | {low:.0f} – {high:.0f} "
            f"| {median / floor[0]:.2f} | {median / one[0]:.2f} |"
        )
    return 0


if __name__ == "__main__":
    sys.exit(main())
