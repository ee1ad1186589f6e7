"""A minimal stand-in for the experiment driver: builds Requests, decodes Replies."""

from __future__ import annotations

import io
import math
from typing import Any

from pushlearn import Learner, serve
from pushlearn._pb import learner_pb2, pushlearn_pb2
from pushlearn.framing import encode_frame, read_frame

LAST_OBSERVED = learner_pb2.LAST_OBSERVED
LAST_PREDICTION = learner_pb2.LAST_PREDICTION


def body(
    name: str, id_: int, x: float, y: float, theta: float = 0.0, z: float = 0.03
) -> Any:
    """A ModelState at (x, y, z) with yaw theta."""
    return pushlearn_pb2.ModelState(
        name=name,
        id=id_,
        pose=pushlearn_pb2.Pose(
            position=pushlearn_pb2.Vector3d(x=x, y=y, z=z),
            orientation=pushlearn_pb2.Quaternion(
                z=math.sin(theta / 2), w=math.cos(theta / 2)
            ),
        ),
    )


def world(
    actuator: tuple[float, float], blue: tuple[float, float, float] = (0.0, 0.25, 0.0)
) -> Any:
    """A learner.State of the one-block scene (with a ground plane and a ghost to skip)."""
    return learner_pb2.State(
        bodies=[
            body("ground_plane", 0, 0.0, 0.0, z=0.0),
            body("actuator", 8, *actuator),
            body("blockA", 15, *blue, z=0.05),
            body("blockAShadow", 15, 9.0, 9.0),
        ]
    )


def observed(state: Any) -> Any:
    """A StateRef sending ``state`` in full."""
    return learner_pb2.StateRef(observed=state)


def recent(which: int) -> Any:
    """A StateRef to a state the learner holds."""
    return learner_pb2.StateRef(recent=which)


def action(vx: float, vy: float) -> Any:
    """An Action."""
    return learner_pb2.Action(vx=vx, vy=vy)


class Script:
    """Requests numbered 1, 2, 3, … as the driver numbers them."""

    def __init__(self) -> None:
        self.requests: list[Any] = []

    def add(self, **call: Any) -> int:
        """Appends a request with one call; returns its seq."""
        seq = len(self.requests) + 1
        self.requests.append(learner_pb2.Request(seq=seq, **call))
        return seq

    def start(self, task: str = "push-task", rate: int = 100) -> int:
        """Appends Start."""
        return self.add(
            start=learner_pb2.Start(
                protocol_version=learner_pb2.PROTOCOL_VERSION,
                task=task,
                publish_rate_hz=rate,
            )
        )

    def bytes(self) -> bytes:
        """Every request, framed."""
        return b"".join(encode_frame(r) for r in self.requests)


def decode_replies(data: bytes) -> list[Any]:
    """Every Reply in ``data``."""
    stream = io.BytesIO(data)
    replies = []
    while (reply := read_frame(stream, learner_pb2.Reply)) is not None:
        replies.append(reply)
    return replies


def run(learner: Learner | Any, script: Script) -> tuple[int, list[Any]]:
    """Serves ``script`` to ``learner`` in-process; the status and the replies."""
    out = io.BytesIO()
    status = serve(learner, stdin=io.BytesIO(script.bytes()), stdout=out)
    return status, decode_replies(out.getvalue())
