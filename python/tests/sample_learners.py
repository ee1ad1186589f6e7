"""Learners the tests serve (in-process and through ``python -m pushlearn.serve``)."""

from __future__ import annotations

import itertools
import os
import sys
from typing import Any, ClassVar

from pushlearn import Capability, Learner, Pose, Prediction, Target, TargetRefused
from pushlearn.learner import Action, ArgumentParser, StateLike

_instances = itertools.count(1)


class Recorder(Learner):
    """Records every call; predicts the actuator moving by action / rate, blocks still."""

    name: ClassVar[str] = "recorder"
    version: ClassVar[str] = "1.2"
    capabilities: ClassVar[frozenset[Capability]] = frozenset(
        {Capability.FORWARD, Capability.INVERSE}
    )

    def __init__(self, step: float = 1.0) -> None:
        self.instance = next(_instances)
        self.step = step
        self.calls: list[tuple[Any, ...]] = []
        self.target: Target | None = None

    @classmethod
    def from_args(cls, argv: list[str]) -> Recorder:
        parser = ArgumentParser(prog="recorder")
        parser.add_argument("--step", type=float, default=1.0)
        return cls(step=parser.parse_args(argv).step)

    def start(self, task: str, publish_rate_hz: int) -> None:
        super().start(task, publish_rate_hz)
        self.calls.append(("start", task, publish_rate_hz))

    def new_fold(self, seed: int) -> None:
        self.calls.append(("new_fold", seed))

    def reset(self, state: StateLike) -> None:
        self.calls.append(("reset", state))

    def update(self, state: StateLike, action: Action) -> None:
        self.calls.append(("update", state, action))

    def predict(self, state: StateLike, action: Action) -> Prediction:
        self.calls.append(("predict", state, action))
        poses = state.poses()
        x, y, theta = poses[8]
        dt = self.step / self.publish_rate_hz
        poses[8] = Pose(x + action[0] * dt, y + action[1] * dt, theta)
        return Prediction(poses)

    def set_training(self, on: bool) -> None:
        super().set_training(on)
        self.calls.append(("set_training", on))

    def set_target(self, target: Target | None) -> None:
        if target is not None and target.id != 15:
            raise TargetRefused(f"cannot plan for body {target.id}")
        self.target = target
        self.calls.append(("set_target", target))

    def act(self) -> tuple[Action, bool]:
        return (0.1, -0.2), self.target is not None

    def stats(self) -> dict[str, Any]:
        updates = sum(1 for call in self.calls if call[0] == "update")
        return {
            "maps": {
                "memory": {"update_calls": updates, "inserts": updates, "nodes": 1}
            },
            "extra": {"instance": self.instance, "pid": os.getpid()},
            "labels": {"task": self.task},
        }


class Printer(Recorder):
    """Prints to stdout in every call, as careless learner code does."""

    name: ClassVar[str] = "printer"

    def start(self, task: str, publish_rate_hz: int) -> None:
        print("starting!")
        sys.stdout.write("more text on stdout\n")
        os.write(1, b"native code writing to fd 1\n")
        super().start(task, publish_rate_hz)

    def predict(self, state: StateLike, action: Action) -> Prediction:
        print("predicting", action)
        return super().predict(state, action)


class Broken(Recorder):
    """Fails in update."""

    name: ClassVar[str] = "broken"

    def update(self, state: StateLike, action: Action) -> None:
        raise ZeroDivisionError("the model divided by zero")


def make_recorder() -> Recorder:
    """A factory function (not a class)."""
    return Recorder(step=2.0)


class Unbuildable(Learner):
    """Cannot be made (a missing model file, a missing extension, ...)."""

    def __init__(self) -> None:
        raise RuntimeError("no model file at /nowhere")

    def new_fold(self, seed: int) -> None:
        pass
