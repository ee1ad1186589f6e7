"""How many environment steps per second this machine does (``docs/performance.md`` §6).

::

    python -m pushlearn.envs.throughput [--steps 20000] [--repeats 5] [--envs 1,2,8]

Measures, each ``--repeats`` times (the median is printed, with the range):

* **physics floor**: the same random actions sent ahead to a lock-step
  world, eight messages outstanding, so that the world never waits for
  the client: what stepping these messages costs (:func:`physics_floor`);
* **client**: :meth:`pushlearn.SimClient.move_and_observe` in a loop against
  a lock-step world, the socket round trip and the protobuf decoding but no
  environment;
* **env**: ``PushBlock-v0.step`` with pre-drawn random actions, as
  ``gymnasium.make`` wraps it (time limit, order enforcing, the passive
  checker), episodes reset as they end;
* **vector, N envs**: ``gymnasium.make_vec`` of N environments, steps of all
  N counted: pushlearn's native vector environment (one process, N worlds
  stepped together, :mod:`pushlearn.envs.vector`) and Gymnasium's
  ``AsyncVectorEnv`` (a process and a world per environment).

Every figure is steps (messages) per second and its ratio to the physics
floor. Machine-dependent: run it on an otherwise idle machine.
"""

from __future__ import annotations

import argparse
import statistics
import sys
import time
from collections.abc import Callable, Sequence
from functools import partial

import gymnasium as gym
import numpy as np

from ..local_world import LocalWorld
from . import register_envs
from .push import ACTUATOR_SPEED


def _median_of(
    repeats: int, measure: Callable[[], float]
) -> tuple[float, float, float]:
    values = [measure() for _ in range(repeats)]
    return statistics.median(values), min(values), max(values)


def physics_floor(steps: int, sim_bin: str | None) -> float:
    """Messages per second of a world that never waits for its client.

    The environment benchmark's actions, each a Move and an Advance sent
    ahead, eight messages outstanding, the states read as they come: the
    same physics as the environment's steps, with the round trip hidden
    behind the next messages' stepping.
    """
    actions = _actions(steps, 1)[:, 0] * ACTUATOR_SPEED
    ahead = 8
    with LocalWorld(latency_max=2, sim_bin=sim_bin) as world:
        client = world.connect()
        try:
            start = time.perf_counter()
            for i in range(steps + ahead):
                if i < steps:
                    client.move(float(actions[i, 0]), float(actions[i, 1]))
                    client.advance()
                if i >= ahead:
                    client.next_state(advance=False)
            return steps / (time.perf_counter() - start)
        finally:
            client.close()


def client_rate(steps: int, sim_bin: str | None) -> float:
    """Messages per second of a bare :class:`~pushlearn.SimClient` loop."""
    with LocalWorld(latency_max=2, sim_bin=sim_bin) as world:
        client = world.connect()
        try:
            start = time.perf_counter()
            for i in range(steps):
                client.move_and_observe(0.0, 0.3 if i % 2 else -0.3)
            return steps / (time.perf_counter() - start)
        finally:
            client.close()


def _actions(steps: int, envs: int) -> np.ndarray:
    rng = np.random.default_rng(0)
    return rng.uniform(-1.0, 1.0, (steps, envs, 2)).astype(np.float32)


def env_rate(steps: int, sim_bin: str | None) -> float:
    """Steps per second of one ``gymnasium.make``'d environment."""
    env = gym.make("pushlearn/PushBlock-v0", sim_bin=sim_bin)
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


def vector_rate(steps: int, envs: int, sim_bin: str | None, mode: str) -> float:
    """Steps per second of all environments of a vector environment together;
    ``mode`` is ``gymnasium.make_vec``'s (``"vector_entry_point"``: pushlearn's own)."""
    vector = gym.make_vec(
        "pushlearn/PushBlock-v0",
        num_envs=envs,
        vectorization_mode=mode,
        sim_bin=sim_bin,
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
    parser.add_argument("--sim-bin", default=None, help="the pushlearn-sim to run")
    args = parser.parse_args(argv)
    try:
        sizes = [int(n) for n in args.envs.split(",")]
    except ValueError:
        parser.error(f"--envs must be numbers separated by commas, got {args.envs!r}")
    if args.steps < 1 or args.repeats < 1 or any(n < 1 for n in sizes):
        parser.error("--steps, --repeats and every --envs size must be at least 1")
    register_envs()
    rows: list[tuple[str, tuple[float, float, float]]] = []
    measured = partial(_median_of, args.repeats)
    floor = measured(partial(physics_floor, args.steps, args.sim_bin))
    rows.append(("physics floor (Moves and Advances queued ahead)", floor))
    rows.append(
        (
            "client (SimClient.move_and_observe)",
            measured(partial(client_rate, args.steps, args.sim_bin)),
        )
    )
    rows.append(
        (
            "env (gymnasium.make, 1 env)",
            measured(partial(env_rate, args.steps, args.sim_bin)),
        )
    )
    for label, mode in (
        ("make_vec (native)", "vector_entry_point"),
        ("AsyncVectorEnv", "async"),
    ):
        for n in sizes:
            name = f"{label}, {n} env{'s' if n > 1 else ''}"
            rows.append(
                (
                    name,
                    measured(partial(vector_rate, args.steps, n, args.sim_bin, mode)),
                )
            )
    print(f"{args.steps} steps per measurement, median of {args.repeats} (range)")
    print()
    print("| what | steps/s | range | ratio to the floor |")
    print("|---|---|---|---|")
    for name, (median, low, high) in rows:
        print(
            f"| {name} | {median:.0f} | {low:.0f} – {high:.0f} | {median / floor[0]:.2f} |"
        )
    return 0


if __name__ == "__main__":
    sys.exit(main())
