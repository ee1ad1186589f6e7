"""A learner written against the protocol alone (no SDK), that breaks one rule on purpose.

``python raw_learner.py MODE``: it answers like a careful learner that predicts
no motion and acts towards +x, except for the one thing ``MODE`` names
(``ok`` breaks nothing; ``liar`` breaks no rule but claims every
Move-to-Target run reached at once). The driver and ``pushlearn learner-check`` must name
each broken rule (``docs/learner-protocol.md`` §8); ``test_rules.py`` runs it.
"""

from __future__ import annotations

import math
import sys
from typing import Any

from pushlearn._pb import learner_pb2 as lp
from pushlearn.framing import read_frame, write_frame

MODES = (
    "ok",
    "old-version",
    "no-name",
    "no-forward",
    "answer-one-way",
    "wrong-seq",
    "miss-block",
    "extra-body",
    "twice",
    "error",
    "refuse-target",
    "nan-action",
    "reserved-stats",
    "liar",
)

SKIPPED = ("ground_plane",)


def is_skipped(name: str) -> bool:
    return name in SKIPPED or "wall" in name or "Shadow" in name


def yaw(q: Any) -> float:
    n = math.sqrt(q.x * q.x + q.y * q.y + q.z * q.z + q.w * q.w)
    if n == 0.0:
        return 0.0
    x, y, z, w = q.x / n, q.y / n, q.z / n, q.w / n
    return math.atan2(2.0 * (x * y + w * z), w * w + x * x - y * y - z * z)


def poses_of(state: Any) -> dict[int, tuple[float, float, float]]:
    return {
        b.id: (b.pose.position.x, b.pose.position.y, yaw(b.pose.orientation))
        for b in state.bodies
        if not is_skipped(b.name)
    }


def main() -> int:
    mode = sys.argv[1] if len(sys.argv) > 1 else "ok"
    if mode not in MODES:
        print(
            f"raw_learner: unknown mode {mode!r}; one of {', '.join(MODES)}",
            file=sys.stderr,
        )
        return 2
    stdin, stdout = sys.stdin.buffer, sys.stdout.buffer
    observed: dict[int, tuple[float, float, float]] = {}
    predicted: dict[int, tuple[float, float, float]] = {}

    def resolve(ref: Any) -> dict[int, tuple[float, float, float]]:
        nonlocal observed
        if ref.WhichOneof("state") == "observed":
            observed = poses_of(ref.observed)
            return observed
        return observed if ref.recent == lp.LAST_OBSERVED else predicted

    def reply(seq: int, **answer: Any) -> None:
        write_frame(stdout, lp.Reply(seq=seq, **answer))
        stdout.flush()

    while True:
        request = read_frame(stdin, lp.Request)
        if request is None:
            return 0
        call = request.WhichOneof("call")
        seq = request.seq
        if call == "start":
            capabilities = [] if mode == "no-forward" else [lp.FORWARD, lp.INVERSE]
            reply(
                seq,
                hello=lp.Hello(
                    protocol_version=2 if mode == "old-version" else 1,
                    name="" if mode == "no-name" else "raw",
                    version="1",
                    capabilities=capabilities,
                ),
            )
        elif call == "new_fold":
            observed, predicted = {}, {}
            if mode == "answer-one-way":
                reply(seq, stats=lp.Stats())
        elif call == "reset":
            resolve(request.reset.state)  # predicts no motion: keeps only what it saw
        elif call == "update":
            resolve(request.update.state)
        elif call == "predict":
            source = resolve(getattr(request.predict, "from"))
            if mode == "error":
                reply(seq, error=lp.Error(message="ValueError: raw"))
                return 1
            bodies = []
            for body_id, (x, y, theta) in source.items():
                if mode == "miss-block" and body_id != 8:
                    continue
                pose = lp.BodyPose(id=body_id)
                pose.x, pose.y, pose.theta = x, y, theta
                bodies.append(pose)
                if mode == "twice" and body_id == 8:
                    bodies.append(pose)
            if mode == "extra-body":
                pose = lp.BodyPose(id=99)
                pose.x, pose.y, pose.theta = 0.0, 0.0, 0.0
                bodies.append(pose)
            predicted = {b.id: (b.x, b.y, b.theta) for b in bodies}
            reply(
                seq + 1 if mode == "wrong-seq" else seq,
                prediction=lp.Prediction(bodies=bodies),
            )
        elif call == "set_target":
            refused = mode == "refuse-target"
            reply(
                seq,
                target=lp.TargetReply(
                    accepted=not refused, refusal="no" if refused else ""
                ),
            )
        elif call == "act":
            action = lp.Action()
            action.vx, action.vy = (
                (math.nan, 0.0) if mode == "nan-action" else (0.1, 0.0)
            )
            # A liar claims the target reached on its first Act: a rule it
            # keeps, but the world, not its word, decides the run.
            has_target = mode != "liar"
            reply(seq, action=lp.ActionReply(action=action, has_target=has_target))
        elif call == "get_stats":
            stats = lp.Stats()
            if mode == "reserved-stats":
                stats.maps["gate"].nodes = 1
            reply(seq, stats=stats)
        elif call == "bye":
            return 0
        else:
            # set_training: nothing to do.
            pass


if __name__ == "__main__":
    sys.exit(main())
