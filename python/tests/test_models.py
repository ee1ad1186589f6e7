"""The Rust models served through the native bindings (skipped without ``pushlearn._native``).

The central check: a learner served over the protocol gives bit for bit the
predictions of the native model driven directly with the same calls, in
training and in a chained test run. Build the extension first
(``maturin develop`` or ``pip install .`` at the repository root).
"""

from __future__ import annotations

from typing import Any

import pytest
from driver import LAST_OBSERVED, LAST_PREDICTION, Script, action, observed, recent, run
from pushlearn import Capability, State
from pushlearn._pb import learner_pb2
from pushlearn.learner import UsageError, _stats_to_proto
from pushlearn.models import GateLearner, InteractionLearner, NativeLearner
from synthetic import synthetic_run

native = pytest.importorskip("pushlearn._native")

PUSH = (0.0, 0.5)
SEED = 1234


def bodies(state: State) -> list[tuple[str, int, tuple[float, ...], tuple[float, ...]]]:
    return [(b.name, b.id, b.position, b.orientation) for b in state.bodies]


def rows(world: Any) -> list[tuple[int, float, float, float]]:
    return [(int(r[0]), float(r[1]), float(r[2]), float(r[3])) for r in world.poses()]


def reply_rows(prediction: Any) -> list[tuple[int, float, float, float]]:
    return [(b.id, b.x, b.y, b.theta) for b in prediction.bodies]


def direct(
    model_factory: Any, train_starts: list[float], test_start: float
) -> list[Any]:
    """The driver's push-task calls on a native model, in-process: every prediction's rows."""
    template = model_factory()
    model = template.copy()
    model.seed(SEED)
    out = []
    for x0 in train_starts:
        run_states = synthetic_run(x0, 20)
        w = model.parse(bodies(run_states[0]))
        model.reset_objects(w)
        out.append(rows(model.predict(w, *PUSH)))
        for state in run_states[1:]:
            w = model.parse(bodies(state))
            model.update(w, *PUSH)
            out.append(rows(model.predict(w, *PUSH)))
    model.set_training(False)
    first = synthetic_run(test_start, 1)[0]
    w = model.parse(bodies(first))
    model.reset_objects(w)
    model.update(w, *PUSH)
    p = model.predict(w, *PUSH)
    out.append(rows(p))
    for _ in range(30):
        model.update(p, *PUSH)
        p = model.predict(p, *PUSH)
        out.append(rows(p))
    return out


def served(
    learner: NativeLearner, train_starts: list[float], test_start: float
) -> list[Any]:
    """The same calls as the driver sends them over the protocol."""
    s = Script()
    s.start()
    s.add(new_fold=learner_pb2.NewFold(seed=SEED))
    for x0 in train_starts:
        run_states = synthetic_run(x0, 20)
        s.add(reset=learner_pb2.Reset(state=observed(run_states[0].to_proto())))
        s.add(
            predict=learner_pb2.Predict(
                **{"from": recent(LAST_OBSERVED), "action": action(*PUSH)}
            )
        )
        for state in run_states[1:]:
            s.add(
                update=learner_pb2.Update(
                    state=observed(state.to_proto()), action=action(*PUSH)
                )
            )
            s.add(
                predict=learner_pb2.Predict(
                    **{"from": recent(LAST_OBSERVED), "action": action(*PUSH)}
                )
            )
    s.add(set_training=learner_pb2.SetTraining(on=False))
    first = synthetic_run(test_start, 1)[0]
    s.add(reset=learner_pb2.Reset(state=observed(first.to_proto())))
    s.add(update=learner_pb2.Update(state=recent(LAST_OBSERVED), action=action(*PUSH)))
    s.add(
        predict=learner_pb2.Predict(
            **{"from": recent(LAST_OBSERVED), "action": action(*PUSH)}
        )
    )
    for _ in range(30):
        s.add(
            update=learner_pb2.Update(
                state=recent(LAST_PREDICTION), action=action(*PUSH)
            )
        )
        s.add(
            predict=learner_pb2.Predict(
                **{"from": recent(LAST_PREDICTION), "action": action(*PUSH)}
            )
        )
    status, replies = run(learner, s)
    assert status == 0, replies[-1]
    return [
        reply_rows(r.prediction)
        for r in replies
        if r.WhichOneof("answer") == "prediction"
    ]


@pytest.mark.parametrize(
    ("learner", "factory"),
    [
        (GateLearner, lambda: native.GateModel(config=0, eta=0.0, publish_rate_hz=100)),
        (
            InteractionLearner,
            lambda: native.InteractionModel(config=0, eta=0.0, publish_rate_hz=100),
        ),
    ],
)
def test_served_predictions_are_the_native_models_bit_for_bit(
    learner: Any, factory: Any
) -> None:
    starts = [-0.03, 0.0, 0.03]
    expected = direct(factory, starts, 0.01)
    got = served(learner(), starts, 0.01)
    # synthetic_run(x0, 20) has 21 states: one prediction on each.
    assert len(got) == len(expected) == 3 * 21 + 31
    assert got == expected  # exact float equality, not approx


def test_improvements_are_the_command_lines() -> None:
    assert GateLearner().display_name == "gate"
    assert GateLearner(improve=["all"]).display_name == "gate+"
    learner = GateLearner.from_args(["--improve", "shared-blocks,unrounded"])
    assert learner.display_name == "gate+unrounded+shared-blocks"
    assert InteractionLearner().display_name == "interaction"
    with pytest.raises(UsageError) as e:
        GateLearner.from_args(["--improve", "unrounded,turbo"])
    assert str(e.value) == (
        "gate: unknown change 'turbo' to improve; one of: unrounded, interpolate, "
        "forward-check, shared-blocks, adapt-actuator, average-outputs, all"
    )


@pytest.mark.parametrize("improve", [["average-outputs"], ["all"]])
def test_served_improved_gate_models_are_the_native_ones(improve: list[str]) -> None:
    starts = [-0.03, 0.0, 0.03]
    expected = direct(lambda: native.GateModel(improve=improve), starts, 0.01)
    assert served(GateLearner(improve=improve), starts, 0.01) == expected


def test_the_same_fold_seed_gives_the_same_predictions() -> None:
    a = served(GateLearner(), [0.0], 0.0)
    b = served(GateLearner(), [0.0], 0.0)
    assert a == b


def test_capabilities_and_stats() -> None:
    learner = GateLearner()
    assert learner.capabilities == {Capability.FORWARD, Capability.INVERSE}
    learner.start("push-task", 100)
    learner.new_fold(SEED)
    run_states = synthetic_run(0.0, 10)
    learner.reset(run_states[0])
    for state in run_states[1:]:
        learner.update(state, PUSH)
    message = _stats_to_proto(learner.stats())  # the reports' form, or this raises
    assert len(message.maps) > 0


def test_move_to_target_calls() -> None:
    s = Script()
    s.start(task="move-to-target")
    s.add(new_fold=learner_pb2.NewFold(seed=SEED))
    s.add(reset=learner_pb2.Reset(state=observed(synthetic_run(0.0, 1)[0].to_proto())))
    refused = s.add(set_target=learner_pb2.SetTarget(id=8, x=0.1, y=0.2, theta=0.0))
    accepted = s.add(set_target=learner_pb2.SetTarget(id=15, x=0.45, y=0.65, theta=0.6))
    act = s.add(act=learner_pb2.Act())
    status, replies = run(GateLearner(), s)
    assert status == 0, replies[-1]
    by_seq = {r.seq: r for r in replies}
    assert not by_seq[refused].target.accepted and by_seq[refused].target.refusal
    assert by_seq[accepted].target.accepted
    assert by_seq[act].WhichOneof("answer") == "action"


def test_a_ten_hertz_start_builds_a_ten_hertz_model() -> None:
    learner = GateLearner()
    learner.start("constant-feedback", 10)
    learner.new_fold(SEED)
    state = synthetic_run(0.0, 1)[0]
    learner.reset(state)
    expected_model = native.GateModel(config=0, eta=0.0, publish_rate_hz=10).copy()
    expected_model.seed(SEED)
    w = expected_model.parse(bodies(state))
    expected_model.reset_objects(w)
    assert rows(learner.predict(state, PUSH).handle) == rows(
        expected_model.predict(w, *PUSH)
    )
