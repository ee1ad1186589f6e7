"""A stand-in for ``pushlearn._native`` with the bindings' API, recording every call.

It lets the tests check what :mod:`pushlearn.models` does with the native
models (parse once, pass the predicted world back, copy and seed per fold)
without the Rust extension. Its "model" predicts the actuator moving by
action / rate and the blocks staying put.
"""

from __future__ import annotations

import itertools
import math
import types
from typing import Any

import numpy as np

_ids = itertools.count(1)


class FakeWorld:
    """A parsed or predicted world: rows [id, x, y, theta]."""

    def __init__(self, rows: list[list[float]], origin: str) -> None:
        self.rows = rows
        self.origin = origin
        self.serial = next(_ids)

    def poses(self) -> Any:
        return np.asarray(self.rows, dtype=np.float64).reshape(-1, 4)


class FakeModel:
    """Records calls; ``log`` is shared by a template and its copies."""

    kind = "gate"

    def __init__(
        self,
        config: int = 0,
        eta: float = 0.0,
        publish_rate_hz: int = 100,
        **extra: Any,
    ) -> None:
        self.params = {
            "config": config,
            "eta": eta,
            "publish_rate_hz": publish_rate_hz,
            **extra,
        }
        self.log: list[tuple[Any, ...]] = [("new", self.kind, dict(self.params))]
        self.is_training = True
        self.has_target = False
        self.seeded: int | None = None
        self.copy_of: FakeModel | None = None

    @property
    def name(self) -> str:
        return self.kind

    @property
    def ignores_actuator_yaw(self) -> bool:
        """As the native models say it: the gate model's rule, not the others'."""
        return self.kind == "gate"

    def copy(self) -> FakeModel:
        twin = type(self)(**self.params)
        twin.log = self.log
        twin.copy_of = self
        self.log.append(("copy",))
        return twin

    def seed(self, seed: int) -> None:
        self.seeded = seed
        self.log.append(("seed", seed))

    def parse(
        self,
        bodies: list[tuple[str, int, tuple[float, ...], tuple[float, ...], Any]],
    ) -> FakeWorld:
        rows = []
        for name, id_, position, q, _shape in bodies:
            if name == "ground_plane" or "Shadow" in name or "wall" in name:
                continue
            x, y, z, w = q
            rows.append(
                [
                    float(id_),
                    position[0],
                    position[1],
                    math.atan2(2 * (w * z + x * y), 1 - 2 * (y * y + z * z)),
                ]
            )
        world = FakeWorld(rows, "parsed")
        self.log.append(("parse", world.serial))
        return world

    def reset_objects(self, world: FakeWorld) -> None:
        self.log.append(("reset_objects", world.serial))

    def update(self, world: FakeWorld, vx: float, vy: float) -> None:
        self.log.append(("update", world.serial, vx, vy, self.is_training))

    def predict(self, world: FakeWorld, vx: float, vy: float) -> FakeWorld:
        dt = 1.0 / self.params["publish_rate_hz"]
        rows = [
            [r[0], r[1] + vx * dt, r[2] + vy * dt, r[3]] if r[0] == 8 else list(r)
            for r in world.rows
        ]
        predicted = FakeWorld(rows, "predicted")
        self.log.append(("predict", world.serial, predicted.serial))
        return predicted

    def set_training(self, on: bool) -> None:
        self.is_training = on

    def set_target(self, id_: int, x: float, y: float, theta: float) -> None:
        if id_ == 8:
            raise ValueError("the actuator cannot be a target")
        self.has_target = True
        self.log.append(("set_target", id_, x, y, theta))

    def clear_target(self) -> None:
        self.has_target = False
        self.log.append(("clear_target",))

    def act(self) -> tuple[float, float]:
        return (0.25, -0.125) if self.has_target else (0.0, 0.0)

    def stats(self) -> dict[str, Any]:
        updates = sum(1 for entry in self.log if entry[0] == "update" and entry[4])
        return {
            # A map of its own name: the built-in names are reserved for the
            # built-in models' complete statistics (docs/learner-protocol.md §7).
            "maps": {"stand-in": {"update_calls": updates, "inserts": 0, "nodes": 0}},
            "extra": {},
            "labels": {},
        }


class FakeInteractionModel(FakeModel):
    kind = "interaction"


def module() -> types.ModuleType:
    """A module object standing in for ``pushlearn._native``."""
    # The statistics rule is the driver's own code, not a model's: the real one
    # checks what the stand-in models report.
    from pushlearn import _native as real

    fake = types.ModuleType("pushlearn._native")
    fake.check_stats = real.check_stats  # type: ignore[attr-defined]
    fake.GateModel = FakeModel  # type: ignore[attr-defined]
    fake.InteractionModel = FakeInteractionModel  # type: ignore[attr-defined]
    fake.Aitm = object  # type: ignore[attr-defined]
    return fake
