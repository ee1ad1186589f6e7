"""State, Prediction and the yaw: the learner's view of a world state."""

from __future__ import annotations

import math

import pytest
from driver import body, world
from pushlearn import Body, Learner, Prediction, State, Target, TargetRefused
from pushlearn._pb import learner_pb2
from pushlearn.learner import quaternion_to_yaw


def yaw_q(theta: float) -> tuple[float, float, float, float]:
    return (0.0, 0.0, math.sin(theta / 2), math.cos(theta / 2))


@pytest.mark.parametrize("theta", [0.0, 0.3, -1.2, math.pi / 2, 3.0, -3.0])
def test_yaw_of_unit_quaternions(theta: float) -> None:
    assert quaternion_to_yaw(*yaw_q(theta)) == pytest.approx(theta, abs=1e-12)


def test_a_half_turn_is_plus_pi_and_the_zero_quaternion_has_yaw_zero() -> None:
    assert quaternion_to_yaw(0.0, 0.0, 1.0, 0.0) == pytest.approx(math.pi, abs=1e-15)
    assert quaternion_to_yaw(0.0, 0.0, 0.0, 0.0) == 0.0


def test_yaw_is_the_normalised_formula_bit_for_bit() -> None:
    # The Rust test's case: a non-planar quaternion.
    n = math.sqrt(0.01 + 0.04 + 0.09 + 0.81)
    x, y, z, w = 0.1 / n, 0.2 / n, 0.3 / n, 0.9 / n
    expected = math.atan2(2.0 * (x * y + w * z), w * w + x * x - y * y - z * z)
    assert quaternion_to_yaw(0.1, 0.2, 0.3, 0.9) == expected


@pytest.mark.parametrize("scale", [1e300, 1e-300])
def test_yaw_survives_extreme_scales(scale: float) -> None:
    q = (0.0, 0.0, scale * math.sin(0.35), scale * math.cos(0.35))
    assert quaternion_to_yaw(*q) == pytest.approx(0.7, abs=1e-12)


def test_poses_skip_ground_walls_and_ghosts() -> None:
    state = State.from_proto(world((0.1, 0.0), (0.0, 0.25, 0.4)))
    poses = state.poses()
    assert sorted(poses) == [8, 15]
    assert poses[8] == pytest.approx((0.1, 0.0, 0.0))
    assert poses[15] == pytest.approx((0.0, 0.25, 0.4))
    assert state.actuator == poses[8]
    assert state.blocks == {15: poses[15]}
    assert len(state.bodies) == 4  # the raw bodies are all kept
    assert state.body("blockAShadow").position == (9.0, 9.0, 0.03)


def test_poses_are_a_fresh_dict_each_time() -> None:
    state = State.from_proto(world((0.0, 0.0)))
    state.poses()[8] = (1.0, 1.0, 1.0)  # type: ignore[assignment]
    assert state.poses()[8].x == 0.0


def bad_state(*bodies: object) -> State:
    return State.from_proto(learner_pb2.State(bodies=list(bodies)))


@pytest.mark.parametrize(
    ("state", "message"),
    [
        (bad_state(body("blockA", 15, 0, 0)), "no body named 'actuator'"),
        (bad_state(body("actuator", 9, 0, 0)), "the actuator has id 9, expected 8"),
        (
            bad_state(
                body("actuator", 8, 0, 0),
                body("blockA", 15, 0, 0),
                body("blockB", 15, 1, 0),
            ),
            "'blockA' and 'blockB' share the id 15",
        ),
        (
            bad_state(body("actuator", 8, math.nan, 0)),
            r"body 'actuator': position.x is not a finite",
        ),
        (
            bad_state(body("actuator", 8, 0, 0), body("pusher", 8, 0, 0)),
            "'pusher' has the actuator's id 8",
        ),
    ],
)
def test_bad_states_raise_clear_errors(state: State, message: str) -> None:
    with pytest.raises(ValueError, match=message):
        state.poses()


def test_body_names_the_bodies_there_are() -> None:
    state = State.from_proto(world((0.0, 0.0)))
    with pytest.raises(KeyError, match="no body named 'blockB'.*actuator, blockA"):
        state.body("blockB")


def test_a_state_round_trips_through_its_message() -> None:
    message = world((0.1, 0.2), (0.3, 0.4, 0.5))
    assert State.from_proto(message).to_proto() == message


def test_a_prediction_is_a_poses_view_and_its_message_is_sorted_by_id() -> None:
    p = Prediction({27: (1.0, 2.0, 3.0), 8: (0.0, 0.1, 0.0)}, handle="native")
    assert p.actuator == (0.0, 0.1, 0.0)
    assert p.blocks == {27: (1.0, 2.0, 3.0)}
    assert [b.id for b in p.to_proto().bodies] == [8, 27]
    assert p.handle == "native"


def test_body_yaw() -> None:
    b = Body("blockA", 15, (0.0, 0.0, 0.05), yaw_q(0.25))
    assert b.yaw == pytest.approx(0.25)


class Minimal(Learner):
    def new_fold(self, seed: int) -> None:
        pass


def test_the_base_class_defaults() -> None:
    learner = Minimal()
    assert learner.display_name == "Minimal"
    learner.start("push-task", 10)
    assert (learner.task, learner.publish_rate_hz) == ("push-task", 10)
    learner.set_target(None)  # clearing is always accepted
    with pytest.raises(TargetRefused, match="no inverse model"):
        learner.set_target(Target(15, 0.0, 0.0, 0.0))
    with pytest.raises(NotImplementedError, match="did not declare Capability.INVERSE"):
        learner.act()
    with pytest.raises(NotImplementedError, match="predict"):
        learner.predict(State.from_proto(world((0, 0))), (0.0, 0.5))
    assert learner.stats() == {"maps": {}, "extra": {}, "labels": {}}
    learner.set_training(False)
    assert learner.training is False


def test_new_fold_must_be_implemented() -> None:
    with pytest.raises(NotImplementedError, match="new_fold"):
        Learner().new_fold(1)
