#!/usr/bin/env python3
"""A random policy in ``pushlearn/PushBlock-v0`` (or any pushlearn environment).

Runs episodes of uniformly random actions, seeded, and prints each episode's
length, return and final distance to the target, then the success rate. The
environment steps the lock-step world of ``pushlearn-sim`` in this process.

    pip install '.[gym]'
    python3 examples/python/gym_random.py [--env pushlearn/PushTwoBlocks-v0] [--episodes 5]
"""

from __future__ import annotations

import argparse
import sys

try:
    import gymnasium as gym
    import pushlearn
except ImportError as missing:
    sys.exit(f"error: {missing} (install the package with `pip install '.[gym]'`)")

gym.register_envs(pushlearn)


def main(argv: list[str] | None = None) -> int:
    """Runs the episodes; returns the exit status."""
    parser = argparse.ArgumentParser(description=(__doc__ or "").splitlines()[0])
    parser.add_argument(
        "--env", default="pushlearn/PushBlock-v0", help="environment id"
    )
    parser.add_argument("--episodes", type=int, default=5, help="episodes (default 5)")
    parser.add_argument(
        "--max-steps",
        type=int,
        default=3000,
        help="steps before truncation (default 3000)",
    )
    parser.add_argument("--seed", type=int, default=0, help="seed (default 0)")
    parser.add_argument(
        "--reward", choices=("sparse", "dense"), default="sparse", help="reward type"
    )
    args = parser.parse_args(argv)
    if args.episodes < 1 or args.max_steps < 1:
        parser.error("--episodes and --max-steps must be at least 1")
    env = gym.make(args.env, max_episode_steps=args.max_steps, reward_type=args.reward)
    env.action_space.seed(args.seed)
    successes = 0
    try:
        for episode in range(args.episodes):
            _, info = env.reset(seed=args.seed + episode)
            total, steps, done = 0.0, 0, False
            while not done:
                _, reward, terminated, truncated, info = env.step(
                    env.action_space.sample()
                )
                total += float(reward)
                steps += 1
                done = terminated or truncated
            successes += bool(info["is_success"])
            print(
                f"episode {episode + 1}: {steps} steps, return {total:.2f}, "
                f"{info['distance']:.3f} from the target"
                + (", reached" if info["is_success"] else "")
            )
    finally:
        env.close()
    print(f"success rate: {successes} of {args.episodes}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
