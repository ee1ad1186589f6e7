"""``pushlearn.Model``: every model of the registry by its name, with the
command line's options by keyword; and the typed classes checked against it,
so that a model added to the registry needs no binding of its own.

Build first: ``pip install .`` (see docs/python.md).
"""

from typing import Any

import numpy as np
import pytest
from pushlearn import _native
from pushlearn._native import Model, ModelWorld

Body = tuple[str, int, tuple[float, float, float], tuple[float, float, float, float]]
ACTION = (0.0, 0.5)


def frame(actuator_y: float) -> list[Body]:
    """A world-state message: the actuator below the blue block."""
    return [
        ("actuator", 8, (0.0, actuator_y, 0.03), (0.0, 0.0, 0.0, 1.0)),
        ("blockA", 15, (0.0, 0.25, 0.05), (0.0, 0.0, 0.0, 1.0)),
    ]


def run(model: Any, messages: int = 12) -> list[Any]:
    """Drives ``model`` over a straight push and returns its predictions'
    poses and its statistics: what two builds of one model must agree on."""
    world = model.parse(frame(0.12))
    model.reset_objects(world)
    seen = []
    for k in range(1, messages):
        world = model.parse(frame(0.12 + 0.005 * k))
        model.update(world, *ACTION)
        seen.append(model.predict(world, *ACTION).poses())
    seen.append(model.stats())
    return seen


def typed_class(name: str) -> Any:
    """The typed class of the registry's model ``name``, if there is one:
    ``GateModel`` for "gate" and so on."""
    return getattr(_native, f"{name.capitalize()}Model", None)


def test_every_model_of_the_registry_is_built_by_its_name() -> None:
    names = _native.model_names()
    assert "gate" in names and len(names) == len(set(names))
    for name in names:
        model = Model(name)
        assert model.kind == name
        assert model.name == name
        assert isinstance(model.parse(frame(0.12)), ModelWorld)
        # Each learns (or, a reference, leaves alone) without error.
        poses = run(model)[-2]
        assert poses.shape == (2, 4) and np.isfinite(poses).all()


def test_each_typed_class_is_the_registrys_model() -> None:
    typed = {
        n.removesuffix("Model").lower()
        for n in dir(_native)
        if n.endswith("Model") and n != "Model"
    }
    # No typed class for a model the registry does not know.
    assert typed <= set(_native.model_names())
    assert typed, "the typed classes went; drop this test"
    for name in typed:
        cls = typed_class(name)
        generic, own = run(Model(name)), run(cls())
        for a, b in zip(generic[:-1], own[:-1], strict=True):
            np.testing.assert_array_equal(a, b, err_msg=name)
        assert generic[-1] == own[-1], name
        assert Model(name).name == cls().name
        assert Model(name).ignores_actuator_yaw == cls().ignores_actuator_yaw


def test_options_are_the_command_lines() -> None:
    assert set(_native.model_options_names()) == {
        "config",
        "flags",
        "eta",
        "selector",
        "no_angular_velocity",
        "improve",
        "parts",
    }
    assert Model("gate", improve="forward-check,unrounded").name == (
        "gate+unrounded+forward-check"
    )
    assert Model("gate", improve=["all"]).name == "gate+"
    assert Model("hybrid", parts="mechanics").name == "hybrid-mechanics"
    assert Model("interaction", selector="tree", eta=0.1).options == (
        "config 0, eta 0.1, selector tree, no-angular-velocity false"
    )
    assert Model("gate", flags="use-dyns,low-freq", config=8).options.startswith(
        "config 11,"
    )
    gate_plus = run(Model("gate+"))
    assert gate_plus[-1] == run(Model("gate", improve="all"))[-1]


def test_bad_names_and_options_are_refused_by_name() -> None:
    with pytest.raises(ValueError, match="unknown model 'gait'; one of: gate"):
        Model("gait")
    with pytest.raises(TypeError, match="unknown model option 'etta'"):
        Model("gate", etta=0.1)
    with pytest.raises(ValueError, match="--eta configures the thesis's models"):
        Model("hybrid", eta=0.1)
    with pytest.raises(ValueError, match="eta -1"):
        Model("gate", eta=-1.0)
    with pytest.raises(ValueError, match="most"):
        Model("hybrid", parts="most")
    with pytest.raises(ValueError, match="turbo"):
        Model("gate", improve="turbo")
    with pytest.raises(ValueError, match="--improve adds changes"):
        Model("gate+", improve="unrounded")
    with pytest.raises(ValueError, match="--parts"):
        Model("gate", parts="mechanics")


def test_a_world_belongs_to_its_model_kind() -> None:
    gate, hybrid = Model("gate"), Model("hybrid")
    world = gate.parse(frame(0.12))
    assert world.model == "gate"
    with pytest.raises(
        TypeError, match="a world of the gate model given to the hybrid"
    ):
        hybrid.update(world, *ACTION)
    with pytest.raises(TypeError):
        hybrid.predict(world, *ACTION)
    # A copy learns on its own.
    copy = gate.copy()
    run(copy)
    assert copy.stats() != gate.stats()
