"""pushlearn: memory-based online learning of object manipulation, from Python.

The pure-Python part of the package needs only ``protobuf`` (and, for the
baselines, ``numpy`` and ``scikit-learn``):

* :class:`Learner`, :func:`serve`, :func:`serve_tcp`: write a learner and
  serve it to the experiment driver over the learner protocol
  (``proto/learner.proto``; :mod:`pushlearn.learner`, every public name of
  which is also here). ``pushlearn.serve`` stays the function even after
  ``import pushlearn.serve``: the module of that name is the command line
  ``python -m pushlearn.serve`` (``from pushlearn.serve import main``);
* :class:`SimClient`: a blocking client for the world daemon
  ``pushlearn-sim`` (:mod:`pushlearn.sim`);
* :mod:`pushlearn.baselines`: k-nearest-neighbour and Gaussian-process
  forward models as learners;
* :mod:`pushlearn.models`: the Rust gate and interaction models as learners;
* :mod:`pushlearn.envs`: the world as Gymnasium environments
  (``pushlearn/PushBlock-v0``, ``pushlearn/PushTwoBlocks-v0``), registered
  on import when Gymnasium is installed.

``Model`` (any model of the registry by name, e.g. ``Model("gate",
improve="all")``), the typed ``GateModel``, ``InteractionModel``,
``HybridModel``, and ``Aitm`` are the Rust models themselves, and ``World`` the world of ``pushlearn-sim`` in this
process (no daemon, no socket), from the native extension
``pushlearn._native``; they are imported only when first used, so everything
else works without it.
"""

from __future__ import annotations

import importlib
import sys
import types
from typing import TYPE_CHECKING, Any

from .framing import ProtocolError
from .learner import (
    ACTUATOR_ID,
    ACTUATOR_NAME,
    BLUE_ID,
    RED_ID,
    Action,
    ArgumentParser,
    Body,
    Capability,
    Learner,
    LearnerFactory,
    LearnerServer,
    Pose,
    Prediction,
    Shape,
    State,
    StateLike,
    Target,
    TargetRefused,
    UsageError,
    is_skipped,
    quaternion_to_yaw,
    serve,
    serve_tcp,
)
from .sim import SimClient, SimError, WorldHello

if TYPE_CHECKING:  # pragma: no cover
    from ._native import (
        Aitm,
        GateModel,
        HybridModel,
        InteractionModel,
        Model,
        World,
        model_names,
    )

__version__ = "0.1.0"
"""The package's version."""

__all__ = [
    "ACTUATOR_ID",
    "ACTUATOR_NAME",
    "BLUE_ID",
    "RED_ID",
    "Action",
    "Aitm",
    "ArgumentParser",
    "Body",
    "Capability",
    "GateModel",
    "HybridModel",
    "InteractionModel",
    "Learner",
    "LearnerFactory",
    "LearnerServer",
    "Model",
    "Pose",
    "Prediction",
    "ProtocolError",
    "Shape",
    "SimClient",
    "SimError",
    "State",
    "StateLike",
    "Target",
    "TargetRefused",
    "UsageError",
    "World",
    "WorldHello",
    "__version__",
    "is_skipped",
    "model_names",
    "quaternion_to_yaw",
    "serve",
    "serve_tcp",
]

_NATIVE = (
    "Model",
    "model_names",
    "GateModel",
    "InteractionModel",
    "HybridModel",
    "Aitm",
    "World",
)


def native() -> Any:
    """The native extension module ``pushlearn._native``, with a helpful error if it is missing."""
    try:
        # Through sys.modules, not the package's attribute: a test may stand
        # a module in for the extension there.
        _native = importlib.import_module("pushlearn._native")
    except ImportError as err:
        raise ImportError(
            "pushlearn's native extension (pushlearn._native, the Rust models) is not built: "
            "install the package with `pip install .` from the repository root, or run "
            f"`maturin develop` there ({err})"
        ) from err
    return _native


class _Package(types.ModuleType):
    """The package's module type: keeps ``pushlearn.serve`` the function.

    Importing the submodule ``pushlearn.serve`` (the ``python -m
    pushlearn.serve`` command line) would otherwise rebind the package's
    attribute ``serve`` to that module, and ``pushlearn.serve(MyLearner)``
    would stop working in any program that imported it. The submodule stays
    importable by name (``from pushlearn.serve import main``).
    """

    def __setattr__(self, name: str, value: Any) -> None:
        if name == "serve" and isinstance(value, types.ModuleType):
            return
        super().__setattr__(name, value)


sys.modules[__name__].__class__ = _Package


def _register_gymnasium_envs() -> None:
    # Gymnasium 1.x loads no plugins: a package registers its environments
    # when it is imported (``gymnasium.register_envs(pushlearn)`` documents it).
    try:
        import gymnasium  # noqa: F401
    except ImportError:
        return
    from .envs import register_envs

    register_envs()


_register_gymnasium_envs()


def __getattr__(name: str) -> Any:
    """Imports the native classes on first use (``pushlearn.GateModel``, …)."""
    if name in _NATIVE:
        value = getattr(native(), name)
        globals()[name] = value
        return value
    raise AttributeError(f"module 'pushlearn' has no attribute {name!r}")
