"""The Rust models as learners: :class:`GateLearner`, :class:`InteractionLearner`
and :class:`HybridLearner`.

Each serves a model of the native extension (``pushlearn._native``,
``GateModel`` / ``InteractionModel`` / ``HybridModel``) over the learner
protocol, forward
*and* inverse (Move to Target), so that ``pushlearn experiment … --learner
"python -m pushlearn.serve pushlearn.models:GateLearner"`` runs the very
model the built-in ``--model gate`` runs, through the external-learner path,
and ``… GateLearner --improve all`` the one of ``--model gate+``. The
options, their checks and the names reports give the models are the
command line's: the extension builds its models with the same registry.

Bit identity with the in-process model depends on two rules, which this
module follows:

* **An observation is parsed once.** The gate model tracks its blocks by the
  identity of the parsed objects (a parsed block carries a token that its
  predictions keep), so the native world parsed for a :class:`~pushlearn.State`
  is cached in ``State.handle`` and reused by every later call about that
  state (``Reset`` then ``Update``/``Predict`` with ``LAST_OBSERVED``), as the
  Rust driver reuses its parsed world. A world is never rebuilt from poses.
* **A prediction is the native world.** :meth:`predict` returns a
  :class:`~pushlearn.Prediction` whose ``handle`` is the native world the
  model predicted; :func:`~pushlearn.serve` hands that very object back for
  chained calls (``LAST_PREDICTION``), and the learner passes its native
  world to the model.

The fold's model is a copy of an untrained template built from the
command-line parameters and the publish rate of the driver's Start
(:meth:`~pushlearn.Learner.start`); ``new_fold(seed)`` copies it afresh and
seeds the model's exploration generator with the fold's seed.

Needs the native extension: build the package with ``pip install .`` or
``maturin develop`` from the repository root.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any, ClassVar

from .learner import (
    Action,
    ArgumentParser,
    Capability,
    Learner,
    Prediction,
    StateLike,
    Target,
    TargetRefused,
    UsageError,
)

__all__ = ["GateLearner", "InteractionLearner", "NativeLearner"]


def _native() -> Any:
    from . import native

    return native()


def _version() -> str:
    from . import __version__

    return __version__


class _Observed:
    """What :class:`NativeLearner` keeps in ``State.handle``: the parsed world of one fold."""

    __slots__ = ("fold", "owner", "world")

    def __init__(self, owner: NativeLearner, fold: int, world: Any) -> None:
        self.owner = owner
        self.fold = fold
        self.world = world


class NativeLearner(Learner):
    """A learner serving one of the native models; see the module documentation.

    Subclasses set :attr:`name` and implement :meth:`_build` (the untrained
    model for a publish rate).
    """

    capabilities: ClassVar[frozenset[Capability]] = frozenset(
        {Capability.FORWARD, Capability.INVERSE}
    )

    def __init__(
        self, *, config: int = 0, eta: float = 0.0, publish_rate_hz: int = 100
    ) -> None:
        self.config = config
        """The configuration's bit flags (``docs/spec/experiments.md`` §1)."""
        self.eta = eta
        """The AITM's learning rate η (0: the thesis's setting)."""
        self.publish_rate_hz = publish_rate_hz
        self._fold = 0
        self.template: Any = self._build(publish_rate_hz)
        """The untrained model every fold starts from (a copy of it)."""
        self.model: Any = self.template.copy()
        """The current fold's model."""

    def _build(self, publish_rate_hz: int) -> Any:
        """The untrained native model for ``publish_rate_hz``."""
        raise NotImplementedError

    @property
    def ignores_actuator_yaw(self) -> bool:  # type: ignore[override]
        """The native model's rule: the driver reads the actuator's yaw as it
        would for the built-in model (``Hello.ignores_actuator_yaw``)."""
        return bool(self.template.ignores_actuator_yaw)

    @property
    def display_name(self) -> str:
        """The name ``pushlearn experiment`` gives the built-in model under these
        options (``"gate"``, ``"gate+"``, ``"gate+unrounded"``, ``"interaction"``)."""
        return str(self.template.name)

    # -- lifecycle -------------------------------------------------------------

    def start(self, task: str, publish_rate_hz: int) -> None:
        """Rebuilds the template for the driver's publish rate if it differs."""
        if publish_rate_hz != self.publish_rate_hz:
            self.template = self._build(publish_rate_hz)
            self.model = self.template.copy()
            self._fold += 1
        super().start(task, publish_rate_hz)

    def new_fold(self, seed: int) -> None:
        """A fresh copy of the template, its exploration generator seeded with ``seed``."""
        self.model = self.template.copy()
        self.model.seed(seed)
        self._fold += 1

    # -- worlds ----------------------------------------------------------------

    def world(self, state: StateLike) -> Any:
        """The native world of ``state``: parsed once per fold for an observation,
        the predicted world itself for one of this learner's predictions."""
        if isinstance(state, Prediction):
            handle = state.handle
            if handle is None or isinstance(handle, _Observed):
                raise ValueError(
                    f"{self.display_name} can only continue from its own predictions "
                    "(this Prediction carries no native world)"
                )
            return handle
        cached = state.handle
        if (
            isinstance(cached, _Observed)
            and cached.owner is self
            and cached.fold == self._fold
        ):
            return cached.world
        bodies = [
            (body.name, body.id, body.position, body.orientation, body.shape)
            for body in state.bodies
        ]
        world = self.model.parse(bodies)
        state.handle = _Observed(self, self._fold, world)
        return world

    # -- the protocol's calls --------------------------------------------------

    def reset(self, state: StateLike) -> None:
        """Re-synchronises the model with ``state`` (no learning)."""
        self.model.reset_objects(self.world(state))

    def update(self, state: StateLike, action: Action) -> None:
        """The model's update with ``state``'s native world and ``action``."""
        self.model.update(self.world(state), float(action[0]), float(action[1]))

    def predict(self, state: StateLike, action: Action) -> Prediction:
        """The model's prediction, carrying the predicted native world as ``handle``."""
        predicted = self.model.predict(
            self.world(state), float(action[0]), float(action[1])
        )
        rows = predicted.poses()
        poses = {
            int(row[0]): (float(row[1]), float(row[2]), float(row[3])) for row in rows
        }
        return Prediction(poses, handle=predicted)

    def set_training(self, on: bool) -> None:
        """Turns the model's training on or off."""
        super().set_training(on)
        self.model.set_training(on)

    def set_target(self, target: Target | None) -> None:
        """Sets or clears the model's target; its refusal becomes :class:`TargetRefused`."""
        if target is None:
            self.model.clear_target()
            return
        try:
            self.model.set_target(target.id, target.x, target.y, target.theta)
        except ValueError as err:
            raise TargetRefused(str(err)) from None

    def act(self) -> tuple[Action, bool]:
        """The model's next action towards the target, and whether the target remains."""
        vx, vy = self.model.act()
        return (float(vx), float(vy)), bool(self.model.has_target)

    def stats(self) -> dict[str, Any]:
        """The model's statistics (already in the reports' ``{maps, extra, labels}`` form)."""
        return dict(self.model.stats())


def _names(text: str) -> list[str]:
    """A comma-separated list of names (checked by the native model)."""
    return text.split(",")


def _common_options(parser: ArgumentParser) -> None:
    parser.add_argument(
        "--config", type=int, default=0, help="configuration bit flags (default 0)"
    )
    parser.add_argument(
        "--eta", type=float, default=0.0, help="AITM learning rate (default 0)"
    )


class GateLearner(NativeLearner):
    """The gate model (``docs/spec/gate-model.md``) as a learner."""

    name: ClassVar[str] = "gate"
    version: ClassVar[str] = _version()

    def __init__(
        self,
        *,
        config: int = 0,
        eta: float = 0.0,
        no_angular_velocity: bool = False,
        improve: Sequence[str] = (),
        publish_rate_hz: int = 100,
    ) -> None:
        self.no_angular_velocity = no_angular_velocity
        """The gate model's ablation without the angular-velocity feature."""
        self.improve = list(improve)
        """Changes beyond the thesis by the names of ``--improve`` (``["all"]``:
        the ``gate+`` model; ``docs/models.md``, "Beyond the thesis")."""
        super().__init__(config=config, eta=eta, publish_rate_hz=publish_rate_hz)

    def _build(self, publish_rate_hz: int) -> Any:
        return _native().GateModel(
            config=self.config,
            eta=self.eta,
            publish_rate_hz=publish_rate_hz,
            no_angular_velocity=self.no_angular_velocity,
            improve=self.improve,
        )

    @classmethod
    def from_args(cls, argv: list[str]) -> GateLearner:
        """``[--config N] [--eta E] [--no-angular-velocity] [--improve CHANGE,…]``."""
        parser = ArgumentParser(prog="gate", description="the gate model")
        _common_options(parser)
        parser.add_argument(
            "--no-angular-velocity",
            action="store_true",
            help="leave out the angular-velocity feature",
        )
        parser.add_argument(
            "--improve",
            metavar="CHANGE,…",
            action="extend",
            type=_names,
            default=[],
            help="changes beyond the thesis, comma-separated, as `pushlearn "
            "experiment --improve` takes them (all: the gate+ model)",
        )
        args = parser.parse_args(argv)
        try:
            return cls(
                config=args.config,
                eta=args.eta,
                no_angular_velocity=args.no_angular_velocity,
                improve=args.improve,
            )
        except ValueError as err:
            raise UsageError(f"gate: {err}") from None


class InteractionLearner(NativeLearner):
    """The interaction model (``docs/spec/interaction-model.md``) as a learner."""

    name: ClassVar[str] = "interaction"
    version: ClassVar[str] = _version()

    def __init__(
        self,
        *,
        config: int = 0,
        eta: float = 0.0,
        selector: str = "aitm",
        publish_rate_hz: int = 100,
    ) -> None:
        self.selector = selector
        """The Abstract Collection Selector (``"aitm"`` or another the native model knows)."""
        super().__init__(config=config, eta=eta, publish_rate_hz=publish_rate_hz)

    def _build(self, publish_rate_hz: int) -> Any:
        return _native().InteractionModel(
            config=self.config,
            eta=self.eta,
            publish_rate_hz=publish_rate_hz,
            selector=self.selector,
        )

    @classmethod
    def from_args(cls, argv: list[str]) -> InteractionLearner:
        """``[--config N] [--eta E] [--selector NAME]``."""
        parser = ArgumentParser(prog="interaction", description="the interaction model")
        _common_options(parser)
        parser.add_argument(
            "--selector", default="aitm", help="AC selector (default aitm)"
        )
        args = parser.parse_args(argv)
        try:
            return cls(config=args.config, eta=args.eta, selector=args.selector)
        except ValueError as err:
            raise UsageError(f"interaction: {err}") from None


class HybridLearner(NativeLearner):
    """The hybrid model (``docs/models.md``, "The hybrid model") as a learner."""

    name: ClassVar[str] = "hybrid"
    version: ClassVar[str] = _version()

    def __init__(self, *, parts: str = "full", publish_rate_hz: int = 100) -> None:
        self.parts = parts
        """The model's parts (``"mechanics"``, ``"identified"`` or ``"full"``)."""
        super().__init__(publish_rate_hz=publish_rate_hz)

    def _build(self, publish_rate_hz: int) -> Any:
        return _native().HybridModel(publish_rate_hz=publish_rate_hz, parts=self.parts)

    @classmethod
    def from_args(cls, argv: list[str]) -> HybridLearner:
        """``[--parts mechanics|identified|full]``."""
        parser = ArgumentParser(prog="hybrid", description="the hybrid model")
        parser.add_argument(
            "--parts", default="full", help="the model's parts (default full)"
        )
        args = parser.parse_args(argv)
        try:
            return cls(parts=args.parts)
        except ValueError as err:
            raise UsageError(f"hybrid: {err}") from None
