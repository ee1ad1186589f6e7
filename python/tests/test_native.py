"""Tests of pushlearn._native, the Rust models' Python bindings (crates/python).

Build first: ``maturin develop --release`` in a virtual environment with
numpy and pytest (see pyproject.toml).
"""

import ast
import math
import pathlib
import threading
from collections.abc import Callable
from typing import Required, TypeAlias, TypedDict, TypeVar, overload

import numpy as np
import numpy.typing as npt
import pytest
from pushlearn import _native
from pushlearn._native import (
    Aitm,
    GateModel,
    GateWorld,
    HybridModel,
    HybridWorld,
    InteractionModel,
    InteractionWorld,
)

Model = TypeVar("Model", GateModel, InteractionModel)
"""Either learner; a test taking ``type[Model]`` is checked for each."""
Body: TypeAlias = tuple[
    str, int, tuple[float, float, float], tuple[float, float, float, float]
]
"""One body of a world-state message: (name, id, (x, y, z), (qx, qy, qz, qw))."""

MODELS: list[type[GateModel] | type[InteractionModel]] = [GateModel, InteractionModel]
STEP = 0.005  # the actuator's displacement per message under (0, 0.5) at 100 Hz
ACTION = (0.0, 0.5)
TARGET = (15, 0.45, 0.65, 0.6)


class GateKwargs(TypedDict, total=False):
    config: int
    eta: float
    publish_rate_hz: int
    no_angular_velocity: bool
    improve: list[str]


class InteractionKwargs(TypedDict, total=False):
    config: int
    eta: float
    publish_rate_hz: int
    selector: str


class ThreadResult(TypedDict, total=False):
    poses: npt.NDArray[np.float64]
    error: Exception


class AitmKwargs(TypedDict, total=False):
    mode: Required[str]
    sigma: float
    eps_max: float
    eta_in: float
    eta_out: float
    eta_a: float
    classifier: bool


def frame(actuator_y: float, block: tuple[float, float] = (0.0, 0.25)) -> list[Body]:
    """A world-state message: the actuator and the blue block."""
    return [
        ("actuator", 8, (0.0, actuator_y, 0.03), (0.0, 0.0, 0.0, 1.0)),
        ("blockA", 15, (block[0], block[1], 0.05), (0.0, 0.0, 0.0, 1.0)),
    ]


@overload
def drive(model: GateModel, updates: int = ..., start: float = ...) -> GateWorld: ...
@overload
def drive(
    model: InteractionModel, updates: int = ..., start: float = ...
) -> InteractionWorld: ...
def drive(
    model: Model, updates: int = 5, start: float = 0.1
) -> GateWorld | InteractionWorld:
    """The driver's calling pattern: reset on the first message, then one
    update per message under ACTION with the actuator moving STEP each time.
    Returns the last parsed world."""
    world = model.parse(frame(start))
    model.reset_objects(world)
    for k in range(1, updates + 1):
        world = model.parse(frame(start + STEP * k))
        model.update(world, *ACTION)
    return world


def actions(
    model: GateModel | InteractionModel, count: int = 8
) -> list[tuple[float, float]]:
    return [model.act() for _ in range(count)]


# --- construction and its refusals -------------------------------------------


def test_defaults_and_repr() -> None:
    assert repr(GateModel()) == (
        "GateModel(config=0, eta=0.0, publish_rate_hz=100, no_angular_velocity=False)"
    )
    assert repr(InteractionModel(selector="tree", publish_rate_hz=10, eta=0.1)) == (
        "InteractionModel(config=0, eta=0.1, publish_rate_hz=10, selector='tree')"
    )
    m = GateModel(config=1 | 16 | 32 | 64, eta=0.2, no_angular_velocity=True)
    assert m.is_training and not m.has_target
    for name in ("aitm", "tree", "incremental-tree", "nearest"):
        InteractionModel(selector=name)
    # Both models accept the driver-only bits.
    GateModel(config=4 | 8)
    InteractionModel(config=2 | 4 | 8)
    assert repr(GateModel(improve=["average-outputs", "unrounded"])) == (
        "GateModel(config=0, eta=0.0, publish_rate_hz=100, no_angular_velocity=False, "
        "improve=['average-outputs', 'unrounded'])"
    )


def test_models_are_named_as_reports_name_them() -> None:
    assert GateModel().name == "gate"
    assert InteractionModel(selector="tree").name == "interaction"
    # The order of the reports, whatever the arguments'.
    changes = ["forward-check", "unrounded"]
    assert GateModel(improve=changes).name == "gate+unrounded+forward-check"
    # `all` is the command line's gate+.
    assert GateModel(improve=["all"]).name == "gate+"
    assert GateModel(improve=("unrounded", "all")).name == "gate+"


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        ({"config": 128}, "gate model: configuration number 128: unknown bits 0x80"),
        ({"config": -1}, "-1 is out of range: expected an integer in 0..=4294967295"),
        ({"config": 2**40}, "is out of range"),
        ({"eta": -1.0}, "eta -1 is not a finite, non-negative number"),
        ({"eta": float("nan")}, "eta NaN is not a finite, non-negative number"),
        ({"eta": float("inf")}, "eta inf is not a finite, non-negative number"),
        (
            {"no_angular_velocity": True},
            (
                "--no-angular-velocity needs velocity features "
                "(--flag use-dyns or bit 1 of --config)"
            ),
        ),
        ({"publish_rate_hz": -10}, "-10 is out of range"),
        (
            {"improve": ["average-outputs", "turbo"]},
            (
                "unknown change 'turbo' to improve; one of: unrounded, interpolate, "
                "forward-check, shared-blocks, adapt-actuator, average-outputs, all"
            ),
        ),
        ({"improve": ["Unrounded"]}, "unknown change 'Unrounded' to improve"),
    ],
)
def test_gate_model_refusals(kwargs: GateKwargs, message: str) -> None:
    with pytest.raises(ValueError) as e:
        GateModel(**kwargs)
    assert message in str(e.value)


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        (
            {"config": 16},
            (
                "interaction model: configuration number 16: bits 0x10 do not apply "
                "to the interaction model"
            ),
        ),
        ({"config": 1 | 2}, "configuration number 3: bits 0x1 do not apply"),
        ({"eta": -0.1}, "eta -0.1 is not a finite, non-negative number"),
        (
            {"selector": "forest"},
            "unknown selector 'forest'; one of: aitm, tree, incremental-tree, nearest",
        ),
    ],
)
def test_interaction_model_refusals(kwargs: InteractionKwargs, message: str) -> None:
    with pytest.raises(ValueError) as e:
        InteractionModel(**kwargs)
    assert message in str(e.value)


def test_wrong_argument_types_are_type_errors() -> None:
    with pytest.raises(TypeError):
        GateModel(config="1")  # type: ignore[arg-type]
    with pytest.raises(TypeError):
        InteractionModel(selector=3)  # type: ignore[arg-type]
    with pytest.raises(TypeError):
        GateModel(improve="unrounded")  # a list of names, not one
    with pytest.raises(TypeError):
        InteractionModel(improve=["unrounded"])  # type: ignore[call-arg]
    with pytest.raises(TypeError):
        GateWorld()  # worlds come from parse and predict only


# --- parsing ---------------------------------------------------------------


@pytest.mark.parametrize("model_class", MODELS)
def test_parse_refusals_carry_the_parsers_text(model_class: type[Model]) -> None:
    m = model_class()
    cases: list[tuple[list[Body], str]] = [
        (frame(0.1)[1:], 'the frame has no model named "actuator"'),
        (frame(0.1) + frame(0.1)[:1], 'more than one model named "actuator"'),
        (
            [("actuator", 9, (0, 0, 0), (0, 0, 0, 1))],
            "the actuator has id 9, expected 8",
        ),
        (
            frame(0.1) + [("blockZ", 3, (0, 0, 0), (0, 0, 0, 1))],
            "has id 3, which is not a block id",
        ),
        (
            [("actuator", 8, (0.0, float("nan"), 0.0), (0, 0, 0, 1))],
            "is not a finite number",
        ),
    ]
    for bodies, message in cases:
        with pytest.raises(ValueError) as e:
            m.parse(bodies)
        assert message in str(e.value), bodies
    with pytest.raises(ValueError):
        m.parse([("actuator", 8, (0.0, 0.1), (0, 0, 0, 1))])  # a 2-component position
    with pytest.raises(ValueError):
        m.parse([("actuator", -8, (0.0, 0.1, 0.0), (0, 0, 0, 1))])


@pytest.mark.parametrize("model_class", MODELS)
def test_parse_accepts_any_sequences_of_numbers(model_class: type[Model]) -> None:
    m = model_class()
    bodies = (
        ("actuator", 8, np.array([0.0, 0.1, 0.03]), [0.0, 0.0, 0.0, 1.0]),
        ("blockA", np.uint32(15), [0, 0.25, 0.05], np.array([0.0, 0.0, 0.0, 1.0])),
    )
    # Wider than the stub's Sequence[float] positions and int ids, on purpose.
    poses = m.parse(bodies).poses()  # type: ignore[arg-type]
    np.testing.assert_array_equal(poses, [[8, 0.0, 0.1, 0.0], [15, 0.0, 0.25, 0.0]])
    with pytest.raises((TypeError, ValueError), match="a body is a tuple"):
        m.parse(
            [("actuator", 8, (0.0, 0.1, 0.03))]  # type: ignore[list-item]
        )  # four or five elements
    with pytest.raises((TypeError, ValueError), match="not a pushlearn.Shape|no world"):
        m.parse(
            [("actuator", 8, (0.0, 0.1, 0.03), (0.0, 0.0, 0.0, 1.0), "sphere")]  # type: ignore[list-item]
        )


def test_parsed_poses_are_rounded_and_the_actuator_comes_first() -> None:
    # A yaw of 0.3 rad about z, position off the 3-decimal grid; the block
    # listed before the actuator.
    q = (0.0, 0.0, math.sin(0.15), math.cos(0.15))
    bodies = [
        ("blockB", 27, (-0.6, 0.35, 0.15), (0, 0, 0, 1)),
        ("blockA", 15, (0.12345, 0.2501, 0.05), q),
        ("actuator", 8, (0.0, 0.1, 0.03), q),
    ]
    gate = GateModel().parse(bodies).poses()
    assert gate.dtype == np.float64 and gate.shape == (3, 4)
    np.testing.assert_array_equal(gate[:, 0], [8, 15, 27])
    np.testing.assert_allclose(gate[1], [15, 0.123, 0.25, 0.3])
    assert gate[0, 3] == 0.0  # the gate model parses the actuator's yaw as 0
    inter = InteractionModel().parse(bodies).poses()
    np.testing.assert_array_equal(inter[:, 0], [8, 15, 27])
    assert repr(GateModel().parse(bodies)).startswith(
        "GateWorld(actuator=(0.0, 0.1, 0.0), blocks={15: "
    )


def test_the_hybrid_model_is_the_registrys() -> None:
    assert repr(HybridModel()) == "HybridModel(publish_rate_hz=100, parts='full')"
    assert HybridModel().name == "hybrid"
    assert HybridModel(parts="mechanics").name == "hybrid-mechanics"
    with pytest.raises(ValueError, match="unknown parts 'most'; one of: mechanics"):
        HybridModel(parts="most")


def test_the_hybrid_model_pushes_the_block_it_meets() -> None:
    m = HybridModel(parts="mechanics")
    # The actuator's surface 1 mm below the block's, moving 5 mm a message.
    world = m.parse(frame(0.174))
    m.reset_objects(world)
    assert isinstance(world, HybridWorld)
    p = m.predict(world, *ACTION).poses()
    np.testing.assert_allclose(p[0, 1:3], [0.0, 0.174 + STEP], atol=1e-12)
    # Pushed centrally, the block advances the 4 mm the actuator overlaps it.
    np.testing.assert_allclose(p[1, 1:], [0.0, 0.254, 0.0], atol=1e-9)
    assert m.stats()["labels"] == {"parts": "mechanics"}


# --- the driver's calling pattern ------------------------------------------


@pytest.mark.parametrize("model_class", MODELS)
def test_scripted_sequence(model_class: type[Model]) -> None:
    m = model_class()
    updates = 6
    last = drive(m, updates)
    p = m.predict(last, *ACTION)
    assert isinstance(p, GateWorld if model_class is GateModel else InteractionWorld)
    poses = p.poses()
    assert poses.shape == (2, 4) and poses.dtype == np.float64
    assert np.isfinite(poses).all()
    np.testing.assert_array_equal(poses[:, 0], [8, 15])
    # The actuator's learned step: one more STEP along y; the block untouched.
    np.testing.assert_allclose(
        poses[0, 1:3], [0.0, 0.1 + STEP * (updates + 1)], atol=1e-9
    )
    np.testing.assert_allclose(poses[1, 1:], [0.0, 0.25, 0.0], atol=1e-12)
    # Chained predictions continue from the previous prediction.
    p2 = m.predict(p, *ACTION)
    np.testing.assert_allclose(p2.poses()[0, 2], 0.1 + STEP * (updates + 2), atol=1e-9)

    stats = m.stats()
    assert set(stats) == {"maps", "extra", "labels"}
    first = "actuator" if model_class is GateModel else "acs"
    for name, counters in stats["maps"].items():
        assert set(counters) == {"update_calls", "inserts", "nodes"}, name
        assert counters["nodes"] <= counters["inserts"] <= counters["update_calls"]
    assert stats["maps"][first]["update_calls"] == updates
    if model_class is GateModel:
        assert stats["maps"]["gate"]["update_calls"] == updates
    else:
        assert stats["extra"]["ac_count"] == len(
            [k for k in stats["maps"] if k.startswith("ac/")]
        )


@pytest.mark.parametrize("model_class", MODELS)
def test_training_off_learns_nothing(model_class: type[Model]) -> None:
    m = model_class()
    drive(m, 3)
    before = m.stats()
    m.set_training(False)
    assert not m.is_training
    drive(m, 4, start=0.2)
    assert m.stats() == before
    m.set_training(True)
    assert m.is_training


@pytest.mark.parametrize("model_class", MODELS)
def test_non_finite_actions_are_refused(model_class: type[Model]) -> None:
    m = model_class()
    world = drive(m, 2)
    before = m.stats()
    for bad in [(float("nan"), 0.0), (0.0, float("inf"))]:
        with pytest.raises(ValueError, match="is not finite"):
            m.update(world, *bad)
        with pytest.raises(ValueError, match="is not finite"):
            m.predict(world, *bad)
    assert m.stats() == before


def test_worlds_belong_to_their_model_kind() -> None:
    gate_world = GateModel().parse(frame(0.1))
    with pytest.raises(TypeError):
        InteractionModel().reset_objects(gate_world)  # type: ignore[arg-type]
    with pytest.raises(TypeError):
        InteractionModel().predict(gate_world, 0.0, 0.0)  # type: ignore[arg-type]


# --- copies ------------------------------------------------------------------


@pytest.mark.parametrize("model_class", MODELS)
def test_copy_is_independent(model_class: type[Model]) -> None:
    template = model_class()
    trained = template.copy()
    last = drive(trained, 5)
    # The template learned nothing from its copy's training.
    assert all(c["update_calls"] == 0 for c in template.stats()["maps"].values())

    twin = trained.copy()
    assert twin.stats() == trained.stats()
    np.testing.assert_array_equal(
        twin.predict(last, *ACTION).poses(), trained.predict(last, *ACTION).poses()
    )
    # Training the twin further changes neither the original's memory nor
    # its predictions.
    before = trained.predict(last, *ACTION).poses()
    stats = trained.stats()
    world = twin.parse(frame(0.2, block=(0.0, 0.3)))
    twin.reset_objects(world)
    for k in range(1, 8):
        twin.update(twin.parse(frame(0.2 - STEP * k, block=(0.0, 0.3))), 0.0, -0.5)
    assert twin.stats() != stats
    assert trained.stats() == stats
    np.testing.assert_array_equal(trained.predict(last, *ACTION).poses(), before)
    twin.set_training(False)
    assert trained.is_training


# --- targets, seeds and actions -------------------------------------------


@pytest.mark.parametrize("model_class", MODELS)
def test_targets(model_class: type[Model]) -> None:
    m = model_class()
    assert m.act() == (0.0, 0.0)  # no target
    drive(m, 3)
    with pytest.raises(
        ValueError, match=r"targets for the actuator \(id 8\) are not supported"
    ):
        m.set_target(8, 0.0, 0.0, 0.0)
    with pytest.raises(ValueError, match="is not finite"):
        m.set_target(15, float("nan"), 0.0, 0.0)
    with pytest.raises(ValueError):
        m.set_target(-15, 0.0, 0.0, 0.0)
    assert not m.has_target
    m.set_target(*TARGET)
    assert m.has_target
    with pytest.raises(ValueError):
        m.set_target(8, 0.0, 0.0, 0.0)
    assert m.has_target  # a refused target leaves the previous one in place
    m.clear_target()
    assert not m.has_target
    assert m.act() == (0.0, 0.0)


def test_gate_model_refuses_targets_for_unknown_blocks() -> None:
    m = GateModel()
    drive(m, 2)
    with pytest.raises(ValueError, match="the model cannot plan for object 27"):
        m.set_target(27, 0.0, 0.0, 0.0)


@pytest.mark.parametrize("model_class", MODELS)
def test_seeded_actions_are_reproducible(model_class: type[Model]) -> None:
    def run(seed: int | None) -> list[tuple[float, float]]:
        m = model_class()
        drive(m, 4)
        m.set_target(*TARGET)
        if seed is not None:
            m.seed(seed)
        return actions(m)

    a = run(11)
    assert a == run(11)
    assert a != run(12)
    assert run(None) == run(0)  # never seeded: seed 0
    for vx, vy in a:
        assert math.isfinite(vx) and math.isfinite(vy)
    assert any(v != (0.0, 0.0) for v in a)
    # The largest seed is accepted, one more or a negative one is not.
    m = model_class()
    m.seed(2**64 - 1)
    for bad in (2**64, -1):
        with pytest.raises(ValueError, match="out of range"):
            m.seed(bad)


# The first actions after drive(model, 5), TARGET and seed(7), printed by the
# same sequence run in-process in Rust (learner's Model with
# ChaCha8Rng::seed_from_u64(7), as crates/drive/src/experiment/move_to_target.rs
# seeds a job): the bindings draw the experiment driver's stream bit for bit.
# The untrained inverse models of both learners fall back to exploration.
IN_PROCESS_ACTIONS = [
    (-0.2566874900133887, -0.15527888610698642),
    (0.1506623019777488, 0.25942411368792534),
    (0.2964862400675815, -0.04578110364100457),
]


@pytest.mark.parametrize("model_class", MODELS)
def test_act_draws_the_experiment_drivers_stream(model_class: type[Model]) -> None:
    m = model_class()
    drive(m, 5)
    m.set_target(*TARGET)
    m.seed(7)
    assert actions(m, 3) == IN_PROCESS_ACTIONS


@pytest.mark.parametrize("model_class", MODELS)
def test_seeding_resets_the_stream_and_copies_keep_it(model_class: type[Model]) -> None:
    m = model_class()
    drive(m, 4)
    m.set_target(*TARGET)
    m.seed(5)
    first = actions(m, 3)
    twin = m.copy()  # copies the generator's state too
    assert actions(twin, 3) == actions(m, 3)
    m.seed(5)
    assert actions(m, 3) == first


# --- threads -------------------------------------------------------------


@pytest.mark.parametrize("model_class", MODELS)
def test_a_model_is_usable_from_another_thread(model_class: type[Model]) -> None:
    m = model_class()
    result: ThreadResult = {}

    def work() -> None:
        try:
            last = drive(m, 3)
            result["poses"] = m.predict(last, *ACTION).poses()
        except Exception as e:  # noqa: BLE001 - reported below
            result["error"] = e

    t = threading.Thread(target=work)
    t.start()
    t.join()
    assert "error" not in result, result
    assert result["poses"].shape == (2, 4)
    assert (
        m.stats()["maps"]["actuator" if model_class is GateModel else "acs"][
            "update_calls"
        ]
        == 3
    )


# --- Aitm ------------------------------------------------------------------


def linear(x: npt.ArrayLike) -> npt.NDArray[np.float64]:
    """The function the map learns: y = 0.3 x0 - 0.2 x1 + 0.1, in [-0.1, 0.4]."""
    x = np.atleast_2d(x)
    return (0.3 * x[:, 0] - 0.2 * x[:, 1] + 0.1)[:, None]


def grid_samples(n: int = 20) -> npt.NDArray[np.float64]:
    """A deterministic scattered order over an n × n grid on [0, 1]²."""
    points = np.array([(i / (n - 1), j / (n - 1)) for i in range(n) for j in range(n)])
    order = [(k * 7919) % len(points) for k in range(len(points))]
    return points[order]


@pytest.mark.parametrize("mode", ["winner", "besttwo", "neighbour", "BESTTWO"])
def test_aitm_learns_a_linear_function(mode: str) -> None:
    a = Aitm(2, 1, mode=mode)
    assert a.node_count == 0 and (a.input_dim, a.output_dim) == (2, 1)
    np.testing.assert_array_equal(a.predict([0.5, 0.5]), [0.0])  # untrained: zeros
    samples = grid_samples()
    for x in samples:
        a.update(x, linear(x)[0])
    assert a.stats() == {
        "update_calls": len(samples),
        "inserts": a.stats()["inserts"],
        "nodes": a.node_count,
    }
    assert 2 <= a.node_count <= a.stats()["inserts"] <= len(samples)

    test = np.array(
        [(0.05 + 0.9 * i / 9, 0.95 - 0.9 * j / 9) for i in range(10) for j in range(10)]
    )
    predicted = a.predict(test)
    assert predicted.shape == (100, 1) and predicted.dtype == np.float64
    error = np.abs(predicted - linear(test))
    baseline = np.abs(linear(test) - linear(test).mean())
    # Output-driven insertion stops refining once a sample's error is below
    # ε_out = 10^⌊log10 |y|⌋ (docs/spec/aitm.md §4), so "close" is coarse.
    assert error.mean() < 0.04
    assert error.mean() < 0.5 * baseline.mean()
    # The batch answers are the single ones.
    for x, row in zip(test[:10], predicted[:10]):
        np.testing.assert_array_equal(a.predict(x), row)


def test_aitm_eta_a_learns_the_slope() -> None:
    a = Aitm(1, 1, mode="winner", eta_a=0.5)
    xs = [(k * 37 % 50) / 50 for k in range(200)]
    for x in xs:
        a.update([x], [2.0 * x])
    assert abs(a.predict([0.31])[0] - 0.62) < 0.1


def test_aitm_accepts_array_likes_and_any_float_dtype() -> None:
    a = Aitm(3, 2, mode="winner")
    a.update([1, 2, 3], (0.5, -0.5))  # ints and tuples
    a.update(
        np.array([1.0, 2.0, 4.0], dtype=np.float32), np.array([1, 2], dtype=np.int64)
    )
    a.update(np.arange(6.0)[::2], [0, 0])  # a strided, non-contiguous view
    np.testing.assert_array_equal(a.predict(np.array([1.0, 2.0, 3.0])), [0.5, -0.5])
    rows = np.array([[1.0, 2.0, 3.0], [1.0, 2.0, 4.0], [0.0, 2.0, 4.0]])
    expected = [[0.5, -0.5], [1.0, 2.0], [0.0, 0.0]]
    strided = np.repeat(rows, 2, axis=1)[:, ::2]  # neither C- nor F-contiguous
    assert not (strided.flags.c_contiguous or strided.flags.f_contiguous)
    for layout, want in [
        (rows, expected),
        (np.asfortranarray(rows), expected),
        (strided, expected),
        (rows[::-1], expected[::-1]),
    ]:
        np.testing.assert_array_equal(a.predict(layout), want)
    np.testing.assert_array_equal(a.predict(rows.tolist()), expected)
    assert a.predict(np.empty((0, 3))).shape == (0, 2)


def test_aitm_refusals() -> None:
    a = Aitm(2, 1, mode="besttwo")
    cases: list[tuple[Callable[[], object], str]] = [
        (
            lambda: a.update([1.0], [0.0]),
            "x has 1 components, but the map's input_dim is 2",
        ),
        (
            lambda: a.update([1.0, 2.0], [0.0, 1.0]),
            "y has 2 components, but the map's output_dim is 1",
        ),
        (lambda: a.update([1.0, float("nan")], [0.0]), r"x\[1\] is not finite \(NaN\)"),
        (
            lambda: a.update([1.0, 2.0], [float("-inf")]),
            r"y\[0\] is not finite \(-inf\)",
        ),
        (
            lambda: a.update([[1.0, 2.0]], [0.0]),
            r"x must be a 1-D array, not one of shape \(1, 2\)",
        ),
        (lambda: a.predict([1.0, 2.0, 3.0]), "x has 3 components"),
        (
            lambda: a.predict([[1.0, 2.0], [3.0, float("nan")]]),
            r"x\[1, 1\] is not finite",
        ),
        (lambda: a.predict([[1.0, 2.0, 3.0]]), "x has rows of 3 components"),
        (
            lambda: a.predict(np.zeros((2, 2, 2))),
            r"1-D or 2-D array, not one of shape \(2, 2, 2\)",
        ),
        (lambda: a.predict(1.0), r"not one of shape \(\)"),
        (lambda: a.classify([0.0]), "x has 1 components"),
    ]
    for call, message in cases:
        with pytest.raises(ValueError, match=message):
            call()
    assert a.stats()["update_calls"] == 0  # nothing refused was learned
    a.update_label([0.0, 0.0], 1)  # a one-output map takes labels
    with pytest.raises(ValueError, match=r"one-output map \(output_dim is 2\)"):
        Aitm(2, 2, mode="winner").update_label([0.0, 0.0], 1)
    assert a.stats()["update_calls"] == 1


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        (
            {"mode": "best"},
            "unknown AITM mode 'best'; one of: winner, besttwo, neighbour",
        ),
        ({"mode": "winner", "sigma": 0.0}, "sigma must be finite and positive"),
        (
            {"mode": "winner", "sigma": float("nan")},
            "sigma must be finite and positive",
        ),
        (
            {"mode": "winner", "eps_max": -1.0},
            r"eps_max must be finite and non-negative \(got -1\)",
        ),
        (
            {"mode": "winner", "eta_out": -0.5},
            "learning rate eta_out must be finite and non-negative",
        ),
        (
            {"mode": "winner", "eta_a": float("inf")},
            "learning rate eta_a must be finite",
        ),
    ],
)
def test_aitm_parameter_refusals(kwargs: AitmKwargs, message: str) -> None:
    with pytest.raises(ValueError, match=message):
        Aitm(2, 1, **kwargs)


def test_aitm_dimension_refusals() -> None:
    with pytest.raises(TypeError):
        Aitm(2, 1)  # type: ignore[call-arg]  # mode has no default
    with pytest.raises(ValueError, match="out of range"):
        Aitm(-1, 1, mode="winner")
    with pytest.raises(ValueError, match="too large"):
        Aitm(1 << 13, 1 << 12, mode="winner")
    Aitm(0, 1, mode="winner").predict([])


def test_aitm_classifier() -> None:
    c = Aitm(2, 1, mode="winner", classifier=True)
    assert c.classify([0.0, 0.0]) is None  # never trained
    c.update_label([0.0, 0.0], 1)
    c.update_label([1.0, 1.0], -3)
    assert c.classify([0.1, 0.0]) == 1
    assert c.classify([0.9, 1.2]) == -3
    assert c.stats() == {"update_calls": 2, "inserts": 2, "nodes": 2}
    assert repr(c) == (
        "Aitm(input_dim=2, output_dim=1, mode='winner', sigma=0.05, eps_max=0.001, "
        "eta_in=0.0, eta_out=0.0, eta_a=0.0, classifier=True; nodes=2)"
    )


def test_aitm_copy_is_independent() -> None:
    a = Aitm(1, 1, mode="winner")
    a.update([0.0], [1.0])
    b = a.copy()
    b.update([1.0], [5.0])
    b.update([0.5], [-5.0])
    assert a.stats() == {"update_calls": 1, "inserts": 1, "nodes": 1}
    np.testing.assert_array_equal(a.predict([0.9]), [1.0])
    assert b.stats()["update_calls"] == 3


# --- the stub and the docstrings -------------------------------------------


STUB = pathlib.Path(__file__).resolve().parents[1] / "pushlearn" / "_native.pyi"


def stub_classes() -> dict[str, set[str]]:
    tree = ast.parse(STUB.read_text(encoding="utf-8"))
    return {
        node.name: {
            item.name for item in node.body if isinstance(item, ast.FunctionDef)
        }
        for node in tree.body
        if isinstance(node, ast.ClassDef)
    }


def stub_constants() -> set[str]:
    tree = ast.parse(STUB.read_text(encoding="utf-8"))
    return {
        node.target.id
        for node in tree.body
        if isinstance(node, ast.AnnAssign)
        and isinstance(node.target, ast.Name)
        and not node.target.id.startswith("_")
    }


def stub_functions() -> set[str]:
    tree = ast.parse(STUB.read_text(encoding="utf-8"))
    return {node.name for node in tree.body if isinstance(node, ast.FunctionDef)}


def test_the_stub_matches_the_module() -> None:
    stub = stub_classes()
    exported = {name for name in dir(_native) if not name.startswith("_")}
    assert set(stub) | stub_constants() | stub_functions() == exported
    assert pathlib.Path(
        _native.SOURCE_CHECKOUT, "crates", "python", "Cargo.toml"
    ).is_file()
    for name, methods in stub.items():
        cls = getattr(_native, name)
        public = {m for m in vars(cls) if not m.startswith("_")}
        assert public == {m for m in methods if not m.startswith("_")}, name
        for m in methods:
            assert hasattr(cls, m), (name, m)


def test_every_class_and_method_is_documented() -> None:
    assert _native.__doc__
    for name in stub_classes():
        cls = getattr(_native, name)
        assert cls.__doc__ and len(cls.__doc__) > 40, name
        assert cls.__module__ == "pushlearn._native"
        for m, member in vars(cls).items():
            if not m.startswith("_"):
                assert member.__doc__, (name, m)


def test_the_sdks_vocabulary_is_the_extensions() -> None:
    """The pure-Python SDK repeats the ids, the skip rule and the yaw so that it
    works without the extension; the extension's come from the Rust vocabulary
    (crates/core), and the two must agree bit for bit."""
    from pushlearn import learner

    assert (learner.ACTUATOR_ID, learner.ACTUATOR_NAME) == (
        _native.ACTUATOR_ID,
        _native.ACTUATOR_NAME,
    )
    assert (learner.BLUE_ID, learner.RED_ID) == (_native.BLUE_ID, _native.RED_ID)
    assert learner.MAX_POSITION == _native.MAX_POSITION
    for name in [
        "actuator",
        "blockA",
        "ground_plane",
        "north_wall",
        "blockAShadow",
        "shadow",
    ]:
        assert learner.is_skipped(name) == _native.is_skipped(name), name
    quaternions = [
        (0.0, 0.0, 0.0, 0.0),
        (0.0, 0.0, 1e-300, 1e-300),
        (1e300, -1e300, 1e300, 1e300),
        *(_native.yaw_to_quaternion(t / 7.0) for t in range(-30, 31)),
        (0.1, -0.2, 0.3, 0.9),
    ]
    for q in quaternions:
        ours, theirs = learner.quaternion_to_yaw(*q), _native.quaternion_to_yaw(*q)
        assert ours == theirs or (math.isnan(ours) and math.isnan(theirs)), q
