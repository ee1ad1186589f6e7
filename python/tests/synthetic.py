"""Synthetic pushes for the learners' tests: a block pushed straight while in contact."""

from __future__ import annotations

import math

from pushlearn import Body, State

PUSH = (0.0, 0.5)
"""The push tasks' action, m/s."""
STEP = 0.005
"""The actuator's travel per message: 0.5 m/s for 1/100 s."""
MESSAGES = 150
"""Messages per run."""


def synthetic_state(
    actuator: tuple[float, float], block: tuple[float, float, float]
) -> State:
    """A world state with the actuator and the blue block (and a ghost to ignore)."""

    def q(theta: float) -> tuple[float, float, float, float]:
        return (0.0, 0.0, math.sin(theta / 2), math.cos(theta / 2))

    return State(
        [
            Body("actuator", 8, (*actuator, 0.03), q(0.0)),
            Body("blockA", 15, (block[0], block[1], 0.05), q(block[2])),
            Body("blockAShadow", 15, (5.0, 5.0, 0.05), q(0.0)),
        ]
    )


def synthetic_run(x0: float, messages: int = MESSAGES) -> list[State]:
    """A straight push from (x0, 0): the block moves with the actuator while in contact.

    Contact: the actuator within 0.06 of the block's centre line and its
    front 0.05 behind the block's centre. Then the block's Δy equals the
    actuator's; it never turns.
    """
    ax, ay = x0, 0.0
    bx, by = 0.0, 0.25
    states = [synthetic_state((ax, ay), (bx, by, 0.0))]
    for _ in range(messages):
        ay += STEP
        if abs(ax - bx) < 0.06 and by - ay <= 0.05:
            by = ay + 0.05
        states.append(synthetic_state((ax, ay), (bx, by, 0.0)))
    return states
