#!/usr/bin/env python3
"""Push the blue block once, with pushlearn's Python client.

Connects to a running world daemon (``pushlearn-sim``), resets the world,
puts the actuator on the start line at x0 = 0, pushes it forward at 0.5 m/s
for 150 world states and prints the blue block's final pose. Works in both
timing modes: in lock-step mode ``next_state`` sends the Advance that makes
the world publish the state it waits for. In lock-step mode the result is
the calibration sweep's run from x0 = 0 (``pushlearn-sim sweep``), bit for bit.

    target/release/pushlearn-sim --mode lockstep &
    python3 examples/python/push.py --port 11345

Needs the ``pushlearn`` package (``pip install .`` from the repository root,
or ``PYTHONPATH=python``).
"""

from __future__ import annotations

import argparse
import sys

try:
    from pushlearn import ProtocolError, SimClient, SimError
except ImportError as missing:
    sys.exit(f"error: {missing}")

STATES = 150
"""World states to push for: 1.5 s at 100 Hz."""


def main(argv: list[str] | None = None) -> int:
    """Runs the push; returns the exit status."""
    parser = argparse.ArgumentParser(description=(__doc__ or "").splitlines()[0])
    parser.add_argument(
        "--host", default="127.0.0.1", help="world host (default 127.0.0.1)"
    )
    parser.add_argument(
        "--port", type=int, default=11345, help="world port (default 11345)"
    )
    parser.add_argument(
        "--timeout", type=float, default=10.0, help="seconds to wait for any message"
    )
    args = parser.parse_args(argv)

    try:
        with SimClient.connect(args.host, args.port, timeout=args.timeout) as world:
            hello = world.hello
            names = ", ".join(body.name for body in hello.bodies)
            print(
                f"scene {hello.scene}, {hello.timing_mode} mode, {hello.publish_rate} Hz, "
                f"bodies: {names}"
            )
            world.reset()
            world.set_pose("actuator", 0.0, 0.0, 0.03)
            push = world.move(0.0, 0.5)
            # States produced before the Move was in force (applied_seq < push)
            # are skipped; 150 states with the push in force are counted.
            for _ in range(STATES):
                state = world.next_state(after=push)
    except (
        SimError,
        ProtocolError,
        OSError,
    ) as err:  # OSError: refused, reset, timed out
        print(f"error: {err}", file=sys.stderr)
        return 1

    blue = state.body("blockA")
    x, y, z = blue.position
    print(
        f"blockA (blue block) after {STATES} states: x={x:.4f} y={y:.4f} z={z:.4f} "
        f"yaw={blue.yaw:.4f} (step {state.step}, t={state.sim_time:.3f} s)"
    )
    return 0


if __name__ == "__main__":
    sys.exit(main())
