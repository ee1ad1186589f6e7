#!/usr/bin/env python3
"""The thesis's gate model as a policy in ``pushlearn/PushBlock-v0``.

Move to Target through the Gymnasium environment, as ``pushlearn experiment
move-to-target`` runs it: for every target and repetition a fresh gate model
(the Rust model, through the bindings) learns from the thesis's eight fixed
training pushes, each made as an episode of the environment, then plans
every action towards the target, learning on, until the environment reports
success or truncates the episode at 3000 steps. Prints each target's reached
count and mean steps, then the success rate.

    pip install '.[gym]'
    python3 examples/python/gym_gate.py [--repetitions 5] [--seed 1]

The model learns from the environment's world states (``env.unwrapped.state``,
every body as the world sent it), not from the observation vector: the gate
model parses the world itself, as it does in the experiments. The episodes
differ from the experiment's in small ways (the experiment checks each run's
start positions and drops the first message after a reset; the environment
starts every episode at rest in the reset world), so the step counts come
close to the experiment's table without being the same numbers.
"""

from __future__ import annotations

import argparse
import math
import sys
from typing import Any

try:
    import gymnasium as gym
    import pushlearn
    from pushlearn import Target
    from pushlearn.envs.push import ACTUATOR_SPEED, THESIS_TARGETS
    from pushlearn.models import GateLearner
except ImportError as missing:
    sys.exit(f"error: {missing} (install the package with `pip install '.[gym]'`)")

gym.register_envs(pushlearn)

TRAINING_PUSHES = (
    ((0.24, 0.0), (0.0, 0.5)),
    ((0.3, 0.25), (-0.5, 0.0)),
    ((0.24, 0.5), (0.0, -0.5)),
    ((0.0, 0.5), (0.0, -0.5)),
    ((-0.24, 0.5), (0.0, -0.5)),
    ((-0.3, 0.25), (0.5, 0.0)),
    ((-0.24, 0.0), (0.0, 0.5)),
    ((0.0, 0.0), (0.0, 0.5)),
)
"""The thesis's training runs: the actuator's start (m) and its velocity (m/s)."""

TRAINING_MESSAGES = 150
"""Messages per training push, the first only re-synchronising the model."""


def _action(velocity: tuple[float, float]) -> list[float]:
    return [velocity[0] / ACTUATOR_SPEED, velocity[1] / ACTUATOR_SPEED]


def train(env: Any, learner: GateLearner) -> None:
    """The eight training pushes, one episode each; a push ends early when the
    actuator leaves the 1 m circle, as the thesis's runs do."""
    world = env.unwrapped
    for start, velocity in TRAINING_PUSHES:
        env.reset(options={"actuator": start})
        learner.reset(world.state)
        for _ in range(TRAINING_MESSAGES - 1):
            observation, _, _, _, _ = env.step(_action(velocity))
            learner.update(world.state, velocity)
            if math.hypot(*observation["observation"][:2]) > 1.0:
                break


def run_to(
    env: Any, learner: GateLearner, target: tuple[float, float, float]
) -> tuple[bool, int]:
    """One test run towards ``target``: whether the environment reported success, and the steps."""
    world = env.unwrapped
    env.reset(options={"target": target})
    learner.set_target(Target(15, *target))
    learner.reset(world.state)
    steps = 0
    while True:
        velocity, has_target = learner.act()
        if not has_target:
            # The planner judges "reached" on its own rounded features; when the
            # world does not agree yet, it is given the target again.
            learner.set_target(Target(15, *target))
            velocity, _ = learner.act()
        _, _, terminated, truncated, info = env.step(_action(velocity))
        steps += 1
        learner.update(world.state, velocity)
        if terminated or truncated:
            return bool(info["is_success"]), steps


def main(argv: list[str] | None = None) -> int:
    """Runs every target and repetition; returns the exit status."""
    parser = argparse.ArgumentParser(description=(__doc__ or "").splitlines()[0])
    parser.add_argument(
        "--repetitions", type=int, default=5, help="test runs per target (default 5)"
    )
    parser.add_argument("--seed", type=int, default=1, help="first seed (default 1)")
    parser.add_argument(
        "--max-steps", type=int, default=3000, help="longest test run (default 3000)"
    )
    args = parser.parse_args(argv)
    if args.repetitions < 1 or args.max_steps < 1:
        parser.error("--repetitions and --max-steps must be at least 1")
    env = gym.make("pushlearn/PushBlock-v0", max_episode_steps=args.max_steps)
    reached_total = runs = 0
    try:
        print("target (x, y, θ)          reached  mean steps")
        for number, target in enumerate(THESIS_TARGETS, start=1):
            reached = 0
            steps_total = 0
            for repetition in range(args.repetitions):
                seed = args.seed + repetition
                env.reset(seed=seed)
                learner = GateLearner()
                learner.new_fold(seed)
                train(env, learner)
                success, steps = run_to(env, learner, target)
                reached += success
                steps_total += steps
            x, y, theta = target
            print(
                f"{number}: ({x:+.1f}, {y:+.1f}, {theta:+.2f})   "
                f"{reached} of {args.repetitions}   {steps_total / args.repetitions:.1f}"
            )
            reached_total += reached
            runs += args.repetitions
    finally:
        env.close()
    print(
        f"success rate: {reached_total} of {runs} ({100.0 * reached_total / runs:.0f} %)"
    )
    return 0


if __name__ == "__main__":
    sys.exit(main())
