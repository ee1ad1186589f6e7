"""pushlearn.models with a stand-in native module: what the wrapper does with the models.

The real bindings are tested in test_models.py (skipped without them); these
tests pin the wrapper's own rules, which bit identity with the built-in
models depends on: one parse per observation, the predicted native world
passed back for chained calls, a fresh seeded copy of the template per fold.
"""

from __future__ import annotations

import sys
from collections.abc import Iterator

import fake_native
import pytest
from driver import (
    LAST_OBSERVED,
    LAST_PREDICTION,
    Script,
    action,
    observed,
    recent,
    run,
    world,
)
from pushlearn._pb import learner_pb2
from pushlearn.learner import UsageError


@pytest.fixture(autouse=True)
def native(monkeypatch: pytest.MonkeyPatch) -> Iterator[None]:
    monkeypatch.setitem(sys.modules, "pushlearn._native", fake_native.module())
    yield


def push_task_script() -> Script:
    """One training run of 3 messages and a chained test run, as the driver sends them."""
    s = Script()
    s.start(rate=100)
    s.add(new_fold=learner_pb2.NewFold(seed=17))
    # train_step: reset + predict on message 1, update + predict on the later ones
    s.add(reset=learner_pb2.Reset(state=observed(world((0.0, 0.0)))))
    s.add(
        predict=learner_pb2.Predict(
            **{"from": recent(LAST_OBSERVED), "action": action(0, 0.5)}
        )
    )
    for y in (0.005, 0.010):
        s.add(
            update=learner_pb2.Update(
                state=observed(world((0.0, y))), action=action(0, 0.5)
            )
        )
        s.add(
            predict=learner_pb2.Predict(
                **{"from": recent(LAST_OBSERVED), "action": action(0, 0.5)}
            )
        )
    s.add(set_training=learner_pb2.SetTraining(on=False))
    # test_step: reset, update and predict from the observation, then chained
    s.add(reset=learner_pb2.Reset(state=observed(world((0.1, 0.0)))))
    s.add(update=learner_pb2.Update(state=recent(LAST_OBSERVED), action=action(0, 0.5)))
    s.add(
        predict=learner_pb2.Predict(
            **{"from": recent(LAST_OBSERVED), "action": action(0, 0.5)}
        )
    )
    for _ in range(2):
        s.add(
            update=learner_pb2.Update(
                state=recent(LAST_PREDICTION), action=action(0, 0.5)
            )
        )
        s.add(
            predict=learner_pb2.Predict(
                **{"from": recent(LAST_PREDICTION), "action": action(0, 0.5)}
            )
        )
    s.add(get_stats=learner_pb2.GetStats())
    return s


def test_each_observation_is_parsed_once_and_predictions_are_passed_back() -> None:
    from pushlearn.models import GateLearner

    learner = GateLearner()
    status, replies = run(learner, push_task_script())
    assert status == 0, replies[-1]
    log = [
        entry for entry in learner.model.log if entry[0] not in ("new", "copy", "seed")
    ]
    parses = [entry[1] for entry in log if entry[0] == "parse"]
    assert len(parses) == 4  # four observations were sent, each parsed once
    w1, w2, w3, w4 = parses
    steps = [entry for entry in log if entry[0] != "parse"]
    # Training: the parsed world of each message is the one updated and predicted from.
    assert steps[0] == ("reset_objects", w1)
    assert steps[1][:2] == ("predict", w1)
    assert steps[2] == ("update", w2, 0.0, 0.5, True)
    assert steps[3][:2] == ("predict", w2)
    assert steps[4] == ("update", w3, 0.0, 0.5, True)
    # Test: reset, update and predict all use the one parse of the observation ...
    assert steps[6] == ("reset_objects", w4)
    assert steps[7] == ("update", w4, 0.0, 0.5, False)
    first = steps[8]
    assert first[:2] == ("predict", w4)
    # ... and the chain continues from the predicted native worlds themselves.
    assert steps[9] == ("update", first[2], 0.0, 0.5, False)
    second = steps[10]
    assert second[:2] == ("predict", first[2])
    assert steps[11] == ("update", second[2], 0.0, 0.5, False)
    assert steps[12][:2] == ("predict", second[2])
    predictions = [
        r.prediction for r in replies if r.WhichOneof("answer") == "prediction"
    ]
    assert [p.bodies[0].y for p in predictions[-3:]] == pytest.approx(
        [0.005, 0.010, 0.015]
    )
    assert replies[-1].stats.maps["stand-in"].update_calls == 2


def test_a_fold_is_a_seeded_copy_of_the_template() -> None:
    from pushlearn.models import GateLearner

    learner = GateLearner(config=8, eta=0.5, no_angular_velocity=True)
    template = learner.template
    assert template.params == {
        "config": 8,
        "eta": 0.5,
        "publish_rate_hz": 100,
        "no_angular_velocity": True,
        "improve": [],
    }
    learner.start("push-task", 100)
    assert learner.template is template  # same rate: not rebuilt
    learner.new_fold(5)
    first = learner.model
    learner.new_fold(6)
    assert learner.model is not first
    assert learner.model.copy_of is template and learner.model.seeded == 6
    assert first.copy_of is template and first.seeded == 5


def test_the_start_rate_rebuilds_the_template() -> None:
    from pushlearn.models import InteractionLearner

    learner = InteractionLearner(selector="tree")
    learner.start("constant-feedback", 10)
    assert learner.template.params == {
        "config": 0,
        "eta": 0.0,
        "publish_rate_hz": 10,
        "selector": "tree",
    }
    assert learner.template.kind == "interaction"
    learner.new_fold(1)
    assert learner.model.params["publish_rate_hz"] == 10


def test_a_state_parsed_in_an_earlier_fold_is_parsed_again() -> None:
    from pushlearn import State
    from pushlearn.models import GateLearner

    learner = GateLearner()
    learner.new_fold(1)
    state = State.from_proto(world((0.0, 0.0)))
    learner.reset(state)
    learner.update(state, (0.0, 0.5))
    learner.new_fold(2)
    learner.reset(state)
    assert sum(1 for entry in learner.model.log if entry[0] == "parse") == 2


def test_targets_and_actions() -> None:
    from pushlearn.models import GateLearner

    s = Script()
    s.start(task="move-to-target")
    refused = s.add(set_target=learner_pb2.SetTarget(id=8, x=0.1, y=0.2, theta=0.0))
    accepted = s.add(set_target=learner_pb2.SetTarget(id=15, x=0.45, y=0.65, theta=0.6))
    act = s.add(act=learner_pb2.Act())
    s.add(set_target=learner_pb2.SetTarget(clear=True))
    idle = s.add(act=learner_pb2.Act())
    learner = GateLearner()
    status, replies = run(learner, s)
    assert status == 0
    by_seq = {r.seq: r for r in replies}
    assert not by_seq[refused].target.accepted
    assert by_seq[refused].target.refusal == "the actuator cannot be a target"
    assert by_seq[accepted].target.accepted
    assert by_seq[act].action.action.vx == 0.25 and by_seq[act].action.has_target
    assert by_seq[idle].action.action.vx == 0.0 and not by_seq[idle].action.has_target
    assert list(replies[0].hello.capabilities) == [
        learner_pb2.FORWARD,
        learner_pb2.INVERSE,
    ]
    assert replies[0].hello.name == "gate"
    assert replies[
        0
    ].hello.ignores_actuator_yaw  # the gate model zeroes the actuator's yaw


def test_the_interaction_model_keeps_the_actuator_yaw() -> None:
    from pushlearn.models import InteractionLearner

    s = Script()
    s.start()
    status, replies = run(InteractionLearner(), s)
    assert status == 0
    assert replies[0].hello.name == "interaction"
    assert not replies[0].hello.ignores_actuator_yaw


def test_a_foreign_prediction_is_refused() -> None:
    from pushlearn import Prediction
    from pushlearn.models import GateLearner

    learner = GateLearner()
    with pytest.raises(ValueError, match="only continue from its own predictions"):
        learner.predict(Prediction({8: (0.0, 0.0, 0.0)}), (0.0, 0.5))


def test_command_line_options() -> None:
    from pushlearn.models import GateLearner, InteractionLearner

    gate = GateLearner.from_args(
        ["--config", "8", "--eta", "0.1", "--no-angular-velocity"]
    )
    assert (
        gate.template.params["config"] == 8
        and gate.template.params["no_angular_velocity"]
    )
    gate = GateLearner.from_args(
        ["--improve", "forward-check,unrounded", "--improve", "all"]
    )
    assert gate.template.params["improve"] == ["forward-check", "unrounded", "all"]
    interaction = InteractionLearner.from_args(["--selector", "tree"])
    assert interaction.template.params["selector"] == "tree"
    with pytest.raises(UsageError, match="unrecognized arguments: --selector"):
        GateLearner.from_args(["--selector", "tree"])


def test_without_the_extension_the_error_says_how_to_build_it(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    monkeypatch.setitem(sys.modules, "pushlearn._native", None)  # makes the import fail
    import pushlearn
    from pushlearn.models import GateLearner

    with pytest.raises(ImportError, match=r"pip install \.` .*maturin develop"):
        GateLearner()
    monkeypatch.delitem(pushlearn.__dict__, "GateModel", raising=False)
    with pytest.raises(ImportError, match="native extension"):
        pushlearn.GateModel  # noqa: B018
