"""The learner SDK: write a pushlearn learner in Python and serve it.

The experiment driver (``pushlearn experiment … --learner CMD``) runs an
external learner as a child process and talks to it over its stdin and
stdout with the *learner protocol* (``proto/learner.proto``): 4-byte
big-endian length-prefixed protobuf frames (:mod:`pushlearn.framing`), one
``Request`` per call of the driver on its model, a ``Reply`` for the calls
that need an answer. This module turns that protocol into method calls on a
:class:`Learner`::

    from pushlearn import Learner, Prediction, serve

    class Still(Learner):
        name = "still"
        version = "1"

        def new_fold(self, seed):
            pass

        def predict(self, state, action):
            # Blocks stay put; the actuator moves with the action for one
            # message (1 / publish_rate_hz seconds).
            x, y, theta = state.actuator
            dt = 1.0 / self.publish_rate_hz
            return Prediction({**state.poses(),
                               8: (x + action[0] * dt, y + action[1] * dt, theta)})

    if __name__ == "__main__":
        raise SystemExit(serve(Still))

How states reach a learner
--------------------------
Every call that is about a world state (``reset``, ``update``, ``predict``)
gets either a :class:`State` (a world state the driver observed) or one of
the learner's own earlier :class:`Prediction` objects: the push task's test
runs chain predictions, calling ``update(p, a)`` and ``predict(p, a)`` with
the previous prediction ``p`` instead of an observation. On the wire the
driver sends a state in full once and refers to it afterwards
(``StateRef.recent``); :func:`serve` resolves those references to **the very
same Python objects**: the last observed :class:`State` it built and the
last :class:`Prediction` your ``predict`` returned. A learner can therefore
keep whatever it needs in them (``State.handle``, ``Prediction.handle``, or
a subclass of :class:`Prediction`), for instance a native world object that
must not be rebuilt from the poses. Both types offer the same read-only
view: ``poses()``, ``actuator`` and ``blocks``.

Rules :func:`serve` enforces
----------------------------
* The first request is ``Start``; its task and publish rate are handed to
  :meth:`Learner.start`, then a ``Hello`` with the learner's name, version and
  capabilities answers it.
* One-way calls (``NewFold``, ``Reset``, ``Update``, ``SetTraining``) get no
  reply. Answered calls (``Predict``, ``SetTarget``, ``Act``, ``GetStats``)
  get a ``Reply`` with the request's ``seq``.
* An exception raised by learner code is answered with
  ``Reply{seq, error: "<ExceptionType>: <text>"}`` for the request that
  raised it, its traceback goes to stderr, and serving stops (the driver
  ends the fold's job). So does a request that breaks the protocol.
* ``Bye``, or the end of the input, ends serving normally.
* Replies are validated before they are sent: a prediction must hold a
  finite pose for exactly the actuator and the blocks of the state it was
  predicted from, an action two finite numbers, statistics the documented
  shape. Every computed number is sent with presence (the schema's
  ``optional double``), so a −0.0 keeps its sign. A violation is sent as an ``Error`` naming the problem (for a
  prediction, the body), so the driver never receives a malformed reply.
* While serving on the process's own stdout, nothing but frames may reach
  it: :func:`serve` points file descriptor 1 at stderr for the duration (and
  ``sys.stdout`` with it), writing the frames to a private duplicate of the
  original stdout. A stray ``print`` in learner code, or output of native
  code, lands in stderr instead of corrupting the stream.
"""

from __future__ import annotations

import argparse
import enum
import math
import os
import socket
import socketserver
import sys
import threading
import traceback
from collections.abc import Callable, Iterable, Mapping
from dataclasses import dataclass
from typing import IO, Any, ClassVar, NamedTuple, NoReturn, TypeAlias

from . import framing
from ._pb import learner_pb2, pushlearn_pb2
from .framing import ProtocolError

__all__ = [
    "ACTUATOR_ID",
    "ACTUATOR_NAME",
    "BLUE_ID",
    "RED_ID",
    "Action",
    "ArgumentParser",
    "Body",
    "Capability",
    "Learner",
    "LearnerFactory",
    "LearnerServer",
    "Pose",
    "Prediction",
    "Shape",
    "State",
    "StateLike",
    "Target",
    "TargetRefused",
    "UsageError",
    "is_skipped",
    "quaternion_to_yaw",
    "serve",
    "serve_tcp",
]

ACTUATOR_ID = 8
"""The actuator's body id (``docs/protocol.md`` §3)."""
ACTUATOR_NAME = "actuator"
"""The actuator's body name."""
BLUE_ID = 15
"""The blue block's id (``blockA``)."""
RED_ID = 27
"""The red block's id (``blockB``, two-block scene only)."""
MAX_POSITION = 1000.0
"""No body of a world is farther than this from the origin on any axis, in
metres: the world refuses a pose beyond it, and so do targets and predictions."""

PROTOCOL_VERSION = 1
"""The learner protocol version this SDK speaks (``learner.ProtocolVersion``)."""

Action: TypeAlias = tuple[float, float]
"""An actuator velocity ``(vx, vy)`` in m/s, world frame."""


class Pose(NamedTuple):
    """A body's planar pose: position in metres, yaw ``theta`` in radians."""

    x: float
    y: float
    theta: float


class Capability(enum.IntEnum):
    """What a learner can do (``learner.Capability``; the values are the wire's)."""

    FORWARD = 1
    """Predicts the next world state (the push tasks)."""
    INVERSE = 2
    """Chooses actions towards a target (Move to Target)."""


@dataclass(frozen=True)
class Target:
    """A Move-to-Target goal: body ``id`` (15: the blue block) at ``(x, y, theta)``."""

    id: int
    x: float
    y: float
    theta: float


class TargetRefused(Exception):
    """Raised by :meth:`Learner.set_target` to refuse a target; the argument says why.

    The driver receives ``TargetReply{accepted: false, refusal: reason}``
    and the previous target stays in place. Any other exception is an error
    that ends serving.
    """

    def __init__(self, reason: str) -> None:
        super().__init__(reason)
        self.reason = reason
        """Why the target was refused, for people."""


def is_skipped(name: str) -> bool:
    """Whether a body is not part of the learner's world.

    As the Rust learner's ``is_skipped``: the ``ground_plane``, walls and the
    visualisation ghosts (names containing ``Shadow``).
    """
    return name == "ground_plane" or "wall" in name or "Shadow" in name


def _is_normal(value: float) -> bool:
    return value != 0.0 and math.isfinite(value) and abs(value) >= sys.float_info.min


def quaternion_to_yaw(x: float, y: float, z: float, w: float) -> float:
    """The yaw (rotation about z) of the quaternion ``(x, y, z, w)``, in (−π, π].

    Bit for bit the Rust learner's ``quaternion_to_yaw``: the quaternion is
    normalised first (pre-scaled by its largest component when the squares
    would overflow or underflow), the zero quaternion has yaw 0, and
    ``yaw = atan2(2(xy + wz), w² + x² − y² − z²)``. Unrounded.
    """
    largest = max(abs(x), abs(y), abs(z), abs(w))
    if largest == 0.0:
        return 0.0
    norm = math.sqrt(x * x + y * y + z * z + w * w)
    if not _is_normal(norm):
        x, y, z, w = x / largest, y / largest, z / largest, w / largest
        norm = math.sqrt(x * x + y * y + z * z + w * w)
    x, y, z, w = x / norm, y / norm, z / norm, w / norm
    return math.atan2(2.0 * (x * y + w * z), w * w + x * x - y * y - z * z)


@dataclass(frozen=True)
class Shape:
    """A body's collision shape, centred on its pose (``Hello.shapes``, ``State.shapes``).

    At most one of ``sphere_radius`` (metres), ``box_size`` (full edge
    lengths along the body's x, y, z, metres) and ``cylinder`` (radius and
    length, metres; upright, its axis the body's z) is set; none for a shape
    this SDK does not know.
    """

    name: str
    sphere_radius: float | None = None
    box_size: tuple[float, float, float] | None = None
    cylinder: tuple[float, float] | None = None

    @classmethod
    def from_proto(cls, shape: Any) -> Shape:
        """A shape from a ``pushlearn.Shape`` message."""
        geometry = shape.WhichOneof("geometry")
        if geometry == "sphere_radius":
            return cls(shape.name, sphere_radius=shape.sphere_radius)
        if geometry == "box_size":
            b = shape.box_size
            return cls(shape.name, box_size=(b.x, b.y, b.z))
        if geometry == "cylinder":
            c = shape.cylinder
            return cls(shape.name, cylinder=(c.radius, c.length))
        return cls(shape.name)

    def to_proto(self, name: str | None = None) -> Any:
        """This shape as a ``pushlearn.Shape`` message, for the body ``name``
        (default: :attr:`name`)."""
        body = self.name if name is None else name
        if self.sphere_radius is not None:
            return pushlearn_pb2.Shape(name=body, sphere_radius=self.sphere_radius)
        if self.box_size is not None:
            x, y, z = self.box_size
            return pushlearn_pb2.Shape(
                name=body, box_size=pushlearn_pb2.Vector3d(x=x, y=y, z=z)
            )
        if self.cylinder is not None:
            radius, length = self.cylinder
            return pushlearn_pb2.Shape(
                name=body,
                cylinder=pushlearn_pb2.Cylinder(radius=radius, length=length),
            )
        return pushlearn_pb2.Shape(name=body)

    def outline(self) -> tuple[float, float] | float | None:
        """The shape seen from above: a box's half-lengths ``(hx, hy)`` along
        the body's x and y, a cylinder's or sphere's radius, ``None`` for an
        unknown shape."""
        if self.box_size is not None:
            return (self.box_size[0] / 2.0, self.box_size[1] / 2.0)
        if self.cylinder is not None:
            return self.cylinder[0]
        return self.sphere_radius


@dataclass(frozen=True)
class Body:
    """One body of a world state, as the world sent it.

    ``position`` is ``(x, y, z)`` in metres, ``orientation`` the unit
    quaternion ``(x, y, z, w)``; both in the world frame. Velocities are
    present in states read from the world (:class:`pushlearn.SimClient`),
    ``None`` in states the learner protocol delivers (it does not send them).
    """

    name: str
    id: int
    position: tuple[float, float, float]
    orientation: tuple[float, float, float, float]
    lin_vel: tuple[float, float, float] | None = None
    ang_vel: tuple[float, float, float] | None = None
    shape: Shape | None = None
    """The body's shape as the world described it (the learner protocol's
    ``State.shapes``, or the world's Hello for states a :class:`pushlearn.SimClient`
    reads); ``None`` where none was given."""

    @property
    def yaw(self) -> float:
        """The yaw of :attr:`orientation` (:func:`quaternion_to_yaw`)."""
        return quaternion_to_yaw(*self.orientation)

    @classmethod
    def from_proto(
        cls, model: Any, *, velocities: bool = False, shape: Shape | None = None
    ) -> Body:
        """A body from a ``pushlearn.ModelState`` message, with its ``shape`` if known."""
        p, q = model.pose.position, model.pose.orientation
        lin = ang = None
        if velocities:
            lin = (model.lin_vel.x, model.lin_vel.y, model.lin_vel.z)
            ang = (model.ang_vel.x, model.ang_vel.y, model.ang_vel.z)
        return cls(
            name=model.name,
            id=model.id,
            position=(p.x, p.y, p.z),
            orientation=(q.x, q.y, q.z, q.w),
            lin_vel=lin,
            ang_vel=ang,
            shape=shape,
        )

    def to_proto(self) -> Any:
        """This body as a ``pushlearn.ModelState`` message (name, id, pose)."""
        x, y, z = self.position
        qx, qy, qz, qw = self.orientation
        return pushlearn_pb2.ModelState(
            name=self.name,
            id=self.id,
            pose=pushlearn_pb2.Pose(
                position=pushlearn_pb2.Vector3d(x=x, y=y, z=z),
                orientation=pushlearn_pb2.Quaternion(x=qx, y=qy, z=qz, w=qw),
            ),
        )


def _check_finite(where: str, values: Iterable[tuple[str, float]]) -> None:
    for field, value in values:
        if not math.isfinite(value):
            raise ValueError(f"{where}: {field} is not a finite number ({value})")


class _PosesView:
    """The read-only view :class:`State` and :class:`Prediction` share."""

    def poses(self) -> dict[int, Pose]:
        """Every body's planar pose by id: the actuator (8) and the blocks."""
        raise NotImplementedError

    @property
    def actuator(self) -> Pose:
        """The actuator's pose (id 8)."""
        poses = self.poses()
        if ACTUATOR_ID not in poses:
            raise ValueError(
                f"the {type(self).__name__} has no actuator (id {ACTUATOR_ID})"
            )
        return poses[ACTUATOR_ID]

    @property
    def blocks(self) -> dict[int, Pose]:
        """The blocks' poses by id (every body but the actuator)."""
        return {id_: pose for id_, pose in self.poses().items() if id_ != ACTUATOR_ID}


class State(_PosesView):
    """A world state: every body as received, plus planar poses.

    ``bodies`` holds the bodies exactly as the world (or the driver) sent
    them, ghosts and ground plane included. :meth:`poses` is the learner's
    view: the body named ``actuator`` (which must carry id 8) and every other
    body that is not skipped (:func:`is_skipped`) as a block keyed by its id,
    each as ``(x, y, theta)`` with the yaw computed as the Rust learner does
    (:func:`quaternion_to_yaw`; positions and yaw are not rounded).

    The counters ``step``, ``sim_time``, ``publish_seq`` and ``applied_seq``
    are those of the world's ``WorldState`` when the state was read from the
    world (:class:`pushlearn.SimClient`); states from the learner protocol do
    not carry them (``None``).

    ``handle`` is free for the learner's own use (``None`` at first):
    :func:`serve` hands the same :class:`State` object back whenever the
    driver refers to it again, so whatever is stored there comes back too.
    """

    def __init__(
        self,
        bodies: Iterable[Body],
        *,
        step: int | None = None,
        sim_time: float | None = None,
        publish_seq: int | None = None,
        applied_seq: int | None = None,
    ) -> None:
        self.bodies: tuple[Body, ...] = tuple(bodies)
        """The bodies as received."""
        self.step = step
        """Physics steps since the world's last reset (world states only)."""
        self.sim_time = sim_time
        """Seconds since the world's last reset (world states only)."""
        self.publish_seq = publish_seq
        """The world's publish counter (world states only)."""
        self.applied_seq = applied_seq
        """The seq of the last command applied before this state (world states only)."""
        self.handle: Any = None
        """Free for the learner (see the class documentation)."""
        self._poses: dict[int, Pose] | None = None

    @classmethod
    def from_proto(cls, state: Any) -> State:
        """A state from a ``learner.State`` message, each body with its shape."""
        shapes: dict[str, Shape] = {}
        for message in state.shapes:
            shapes.setdefault(message.name, Shape.from_proto(message))
        return cls(
            Body.from_proto(model, shape=shapes.get(model.name))
            for model in state.bodies
        )

    @classmethod
    def from_world_state(
        cls, world_state: Any, shapes: Mapping[str, Shape] | None = None
    ) -> State:
        """A state from a world's ``pushlearn.WorldState`` message, with its counters;
        each body with its shape from ``shapes`` (the world's Hello's, by name)."""
        known = shapes or {}
        return cls(
            (
                Body.from_proto(m, velocities=True, shape=known.get(m.name))
                for m in world_state.model_v.models
            ),
            step=world_state.step,
            sim_time=world_state.sim_time,
            publish_seq=world_state.publish_seq,
            applied_seq=world_state.applied_seq,
        )

    def to_proto(self) -> Any:
        """This state as a ``learner.State`` message."""
        return learner_pb2.State(
            bodies=[body.to_proto() for body in self.bodies],
            shapes=[
                body.shape.to_proto(name=body.name)
                for body in self.bodies
                if body.shape is not None
            ],
        )

    def shapes(self) -> dict[int, Shape]:
        """The shapes of the bodies :meth:`poses` lists (the actuator and the blocks),
        by id, where the state gives one: the learner protocol sends each body's
        shape, and in the new-object experiments the run's object is shown under
        the blue block's id with its own shape."""
        return {
            body.id: body.shape
            for body in self.bodies
            if body.shape is not None and not is_skipped(body.name)
        }

    def body(self, name: str) -> Body:
        """The body called ``name``; ``KeyError`` naming the bodies there are if none is."""
        for body in self.bodies:
            if body.name == name:
                return body
        names = ", ".join(b.name for b in self.bodies) or "none"
        raise KeyError(f"the state has no body named {name!r} (it has: {names})")

    def poses(self) -> dict[int, Pose]:
        """The planar poses by id (see the class documentation); a fresh dict each call.

        Raises ``ValueError`` naming the problem when the state has no
        actuator, an actuator with another id than 8, two bodies with one
        id, or a non-finite position or orientation.
        """
        if self._poses is None:
            self._poses = self._compute_poses()
        return dict(self._poses)

    def _compute_poses(self) -> dict[int, Pose]:
        poses: dict[int, Pose] = {}
        names: dict[int, str] = {}
        for body in self.bodies:
            if is_skipped(body.name):
                continue
            if body.name == ACTUATOR_NAME and body.id != ACTUATOR_ID:
                raise ValueError(
                    f"the actuator has id {body.id}, expected {ACTUATOR_ID}"
                )
            if body.name != ACTUATOR_NAME and body.id == ACTUATOR_ID:
                raise ValueError(
                    f"body {body.name!r} has the actuator's id {ACTUATOR_ID} but is not named "
                    f"{ACTUATOR_NAME!r}"
                )
            if body.id in poses:
                raise ValueError(
                    f"bodies {names[body.id]!r} and {body.name!r} share the id {body.id}"
                )
            _check_finite(
                f"body {body.name!r}",
                zip(("position.x", "position.y"), body.position[:2], strict=True),
            )
            _check_finite(
                f"body {body.name!r}",
                zip(
                    (
                        "orientation.x",
                        "orientation.y",
                        "orientation.z",
                        "orientation.w",
                    ),
                    body.orientation,
                    strict=True,
                ),
            )
            poses[body.id] = Pose(body.position[0], body.position[1], body.yaw)
            names[body.id] = body.name
        if ACTUATOR_ID not in poses:
            raise ValueError(f"the state has no body named {ACTUATOR_NAME!r}")
        return poses

    def __repr__(self) -> str:
        names = ", ".join(f"{b.name}({b.id})" for b in self.bodies)
        return f"State([{names}])"


class Prediction(_PosesView):
    """A predicted world: planar poses by id, the actuator's and every block's.

    A prediction must hold exactly the bodies of the state it was predicted
    from (the actuator and its blocks; :func:`serve` checks this, and that
    every number is finite). ``handle`` is free for the learner's own use:
    when the driver chains predictions, :func:`serve` passes this very
    object back to ``update``/``predict``, so a learner can keep, for
    instance, a native world object in it. Subclassing works as well.
    """

    def __init__(
        self, poses: Mapping[int, tuple[float, float, float]], *, handle: Any = None
    ) -> None:
        self._poses: dict[int, Pose] = {
            int(id_): Pose(float(p[0]), float(p[1]), float(p[2]))
            for id_, p in poses.items()
        }
        self.handle: Any = handle
        """Free for the learner (see the class documentation)."""

    def poses(self) -> dict[int, Pose]:
        """The predicted poses by id; a fresh dict each call."""
        return dict(self._poses)

    def to_proto(self) -> Any:
        """This prediction as a ``learner.Prediction`` message, bodies by increasing id."""
        return learner_pb2.Prediction(
            bodies=[
                learner_pb2.BodyPose(id=id_, x=p.x, y=p.y, theta=p.theta)
                for id_, p in sorted(self._poses.items())
            ]
        )

    def __repr__(self) -> str:
        return f"Prediction({self._poses!r})"


StateLike: TypeAlias = State | Prediction
"""What a learner's state argument can be: an observation or its own prediction."""


class Learner:
    """The base class of a learner served by :func:`serve`.

    Set the class attributes :attr:`name` (it goes into every report as the
    model's name), :attr:`version` and :attr:`capabilities`, and override
    the methods your learner needs. The driver calls them in the order of
    its built-in models (``docs/spec/experiments.md`` §2): :meth:`start`
    once, then per fold :meth:`new_fold`, and per run :meth:`reset` on the
    first message, :meth:`update` on every later one, :meth:`predict` after
    each; :meth:`set_training` between the phases; for Move to Target
    :meth:`set_target` and :meth:`act`; :meth:`stats` when training ends and
    after test runs.

    Every ``state`` argument is a :class:`State` or one of this learner's own
    :class:`Prediction` objects (see the module documentation).

    **Construction.** The base class has no ``__init__`` of its own and
    keeps no state in instances: a subclass may define any ``__init__`` and
    need not call ``super().__init__()`` (it is harmless). :func:`serve`
    makes the learner before the driver's Start arrives (from the class, a
    factory, or :meth:`from_args`), so a constructor that fails is reported
    to the driver as the answer to its Start.

    **Attributes.** :attr:`task`, :attr:`publish_rate_hz` and
    :attr:`training` exist from the start as class defaults (``""``, 100,
    true); the default :meth:`start` sets the first two from the driver's
    Start and the default :meth:`set_training` keeps the third, so an
    override of either should call the base method.

    **Which calls set the stored state.** :meth:`reset` and :meth:`update`
    make their ``state`` the learner's stored state; :meth:`predict` never
    changes it (nor anything learned). :meth:`act` plans from the stored
    state. ``docs/learner-protocol.md`` is the whole contract.
    """

    name: ClassVar[str] = ""
    """The learner's name in reports, e.g. ``"knn"``; empty means the class name."""
    version: ClassVar[str] = "0"
    """The learner's version, recorded in reports."""
    capabilities: ClassVar[frozenset[Capability]] = frozenset({Capability.FORWARD})
    """``{FORWARD}``, or ``{FORWARD, INVERSE}`` for a learner that implements :meth:`act`."""
    ignores_actuator_yaw: ClassVar[bool] = False
    """Whether the driver should read the actuator's yaw as 0 in its start-position
    check and the poses it records (``Hello.ignores_actuator_yaw``), as the
    thesis's gate model does; by default it uses the reported yaw."""

    task: str = ""
    """The task of the driver's Start (``"push-task"``, ``"constant-feedback"``,
    ``"move-to-target"``); empty until :meth:`start`."""
    publish_rate_hz: int = 100
    """The world's publish rate from Start, in Hz (100, or 10); one message lasts
    ``1 / publish_rate_hz`` seconds. 100 (the class default) until :meth:`start`."""
    training: bool = True
    """Whether :meth:`update` should learn (kept by the default :meth:`set_training`)."""

    @classmethod
    def from_args(cls, argv: list[str]) -> Learner:
        """Builds the learner from command-line arguments (``python -m pushlearn.serve``).

        The default accepts none and calls the class without arguments;
        override it to parse options (e.g. with ``argparse``).
        """
        if argv:
            raise UsageError(
                f"{cls.__name__} takes no command-line arguments (got {' '.join(argv)}); "
                "define a from_args(argv) classmethod to accept some"
            )
        return cls()

    def start(self, task: str, publish_rate_hz: int) -> None:
        """Called once, on the driver's Start, before the Hello is sent.

        The default stores both in :attr:`task` and :attr:`publish_rate_hz`;
        an override should call it (``super().start(task, publish_rate_hz)``).
        """
        self.task = task
        self.publish_rate_hz = publish_rate_hz

    def new_fold(self, seed: int) -> None:
        """Forget everything learned and start a fold: training on, no target, no stored state.

        ``seed`` is the fold's seed (the driver seeds its own exploration
        generator with it, ChaCha8 ``seed_from_u64``); a learner that draws
        random numbers should seed itself from it. Must be overridden: only
        the learner knows what it has to forget.
        """
        raise NotImplementedError(
            f"{type(self).__name__} does not implement new_fold(seed) (forget everything learned)"
        )

    def reset(self, state: StateLike) -> None:
        """The first message of a run: re-synchronise with ``state`` without learning.

        The default does nothing.
        """

    def update(self, state: StateLike, action: Action) -> None:
        """Learn the transition from the stored state into ``state`` under ``action``.

        ``action`` is the actuator velocity that was in force meanwhile. With
        training off (:attr:`training`), only move the stored state forward.
        In a push-task test ``state`` is the learner's own last prediction.
        The default does nothing.
        """

    def predict(self, state: StateLike, action: Action) -> Prediction:
        """The state one message after ``state`` if ``action`` is in force.

        Must return a :class:`Prediction` of the actuator and every block of
        ``state``. Must not change what the learner has learned.
        """
        raise NotImplementedError(f"{type(self).__name__} does not implement predict()")

    def set_training(self, on: bool) -> None:
        """Turn training on or off; the default stores it in :attr:`training`."""
        self.training = on

    def set_target(self, target: Target | None) -> None:
        """Set (a :class:`Target`) or clear (``None``) the Move-to-Target goal.

        Raise :class:`TargetRefused` to refuse a target. The default accepts
        clearing and refuses every target (a learner without an inverse model).
        """
        if target is not None:
            raise TargetRefused(f"{self.display_name} has no inverse model")

    def act(self) -> tuple[Action, bool]:
        """The next action towards the target from the stored state, and whether a target remains.

        Return ``((vx, vy), has_target)``; ``has_target`` is false once the
        learner found the target reached. Only learners with
        :attr:`Capability.INVERSE` implement it.
        """
        raise NotImplementedError(
            f"{type(self).__name__} does not implement act(): it did not declare Capability.INVERSE"
        )

    def stats(self) -> dict[str, Any]:
        """The learner's statistics in the reports' form.

        ``{"maps": {name: {"update_calls": int, "inserts": int, "nodes": int}},
        "extra": {name: float}, "labels": {name: str}}``; every part may be
        missing. The default reports nothing.

        Report any maps under your own names, any finite numbers in
        ``extra`` and any text in ``labels``: the reports keep them and the
        node table shows them. Only the built-in models' map names
        (``actuator``, ``gate``, ``predictor/ID``, ``acs``, ``ac/K``) are
        reserved: statistics that use one of them are read as that model's,
        which must then be complete and consistent (as
        :class:`pushlearn.GateModel` served from Python sends them), and
        :func:`serve` checks that with the driver's own code before sending
        (``docs/learner-protocol.md`` §7, "Statistics").
        """
        return {"maps": {}, "extra": {}, "labels": {}}

    @property
    def display_name(self) -> str:
        """:attr:`name`, or the class name when it is empty."""
        return self.name or type(self).__name__


class UsageError(Exception):
    """A command line that cannot be used (unknown learner, bad option); the text says why."""


class ArgumentParser(argparse.ArgumentParser):
    """An ``argparse`` parser for :meth:`Learner.from_args` that raises instead of exiting.

    A wrong option raises :class:`UsageError` (``python -m pushlearn.serve``
    prints it with the usage and exits with status 2).
    """

    def error(self, message: str) -> NoReturn:
        """Raises :class:`UsageError` with ``message``."""
        raise UsageError(f"{self.prog}: {message}")


LearnerFactory: TypeAlias = Callable[[], Learner]
"""Something that makes a fresh learner: a :class:`Learner` subclass or a function."""


# --------------------------------------------------------------------------
# Serving


class _Stop(Exception):
    """Ends a session after a reply was sent (internal)."""

    def __init__(self, status: int) -> None:
        super().__init__(status)
        self.status = status


_CALL_NAMES = {
    "start": "Start",
    "new_fold": "NewFold",
    "reset": "Reset",
    "update": "Update",
    "predict": "Predict",
    "set_training": "SetTraining",
    "set_target": "SetTarget",
    "act": "Act",
    "get_stats": "GetStats",
    "bye": "Bye",
}


def _log(text: str) -> None:
    sys.stderr.write(f"pushlearn.serve: {text}\n")
    sys.stderr.flush()


def _finite_number(value: Any, what: str) -> float:
    if isinstance(value, bool) or not isinstance(value, int | float):
        try:
            value = float(value)  # numpy scalars and the like
        except (TypeError, ValueError):
            raise ValueError(f"{what} is {value!r}, not a number") from None
    number = float(value)
    if not math.isfinite(number):
        raise ValueError(f"{what} is not a finite number ({number})")
    return number


def _count(value: Any, what: str) -> int:
    if isinstance(value, bool):
        raise TypeError(f"{what} is {value!r}, not a count")
    try:
        count = int(value)
    except (TypeError, ValueError):
        raise ValueError(f"{what} is {value!r}, not a count") from None
    if count != value or count < 0:
        raise ValueError(f"{what} is {value!r}, not a count (a non-negative integer)")
    return count


def _stats_to_proto(stats: Any) -> Any:
    if not isinstance(stats, Mapping):
        raise TypeError(f"stats() returned {type(stats).__name__}, expected a dict")
    unknown = set(stats) - {"maps", "extra", "labels"}
    if unknown:
        raise ValueError(
            f"stats() returned unknown keys {sorted(map(str, unknown))} "
            "(expected maps, extra, labels)"
        )
    reply = learner_pb2.Stats()
    for name, counters in dict(stats.get("maps") or {}).items():
        where = f"stats()['maps'][{name!r}]"
        if not isinstance(counters, Mapping):
            raise TypeError(f"{where} is {counters!r}, expected a dict of counters")
        extra_keys = set(counters) - {"update_calls", "inserts", "nodes"}
        if extra_keys:
            raise ValueError(
                f"{where} has unknown counters {sorted(map(str, extra_keys))} "
                "(expected update_calls, inserts, nodes)"
            )
        entry = reply.maps[str(name)]
        for key in ("update_calls", "inserts", "nodes"):
            setattr(entry, key, _count(counters.get(key, 0), f"{where}[{key!r}]"))
    for name, value in dict(stats.get("extra") or {}).items():
        reply.extra[str(name)] = _finite_number(value, f"stats()['extra'][{name!r}]")
    for name, label in dict(stats.get("labels") or {}).items():
        if not isinstance(label, str):
            raise TypeError(f"stats()['labels'][{name!r}] is {label!r}, expected a str")
        reply.labels[str(name)] = label
    if any(_is_reserved_map(name) for name in reply.maps):
        _check_reserved_stats(reply)
    return reply


_RESERVED_MAPS = ("actuator", "gate", "acs")
_RESERVED_PREFIXES = ("predictor/", "ac/")


def _is_reserved_map(name: str) -> bool:
    """Whether ``name`` is one of the built-in models' map names."""
    return name in _RESERVED_MAPS or name.startswith(_RESERVED_PREFIXES)


def _check_reserved_stats(reply: Any) -> None:
    """Statistics under the built-in models' names, read by the driver's own code.

    Raises ``ValueError`` with the driver's reason when they are not a
    built-in model's complete statistics; needs the native extension (which
    a learner that reports a built-in model's maps has).
    """
    import json

    from . import native

    document = {
        "maps": {
            name: {
                "update_calls": m.update_calls,
                "inserts": m.inserts,
                "nodes": m.nodes,
            }
            for name, m in reply.maps.items()
        },
        "extra": dict(reply.extra),
        "labels": dict(reply.labels),
    }
    try:
        native().check_stats(json.dumps(document))
    except ValueError as err:
        raise ValueError(f"stats() are not the driver's statistics: {err}") from None


def _check_prediction(prediction: Any, source: StateLike) -> Any:
    """The prediction's message, or ValueError naming what is wrong with it."""
    _checked_poses(prediction, source)
    return prediction.to_proto()


def _checked_poses(prediction: Any, source: StateLike) -> dict[int, Pose]:
    """The prediction's poses, or ValueError naming what is wrong with it.

    A prediction must hold a finite pose for exactly the actuator and the
    blocks of the state it was predicted from.
    """
    if not isinstance(prediction, Prediction):
        raise TypeError(
            f"predict() returned {type(prediction).__name__}, expected a pushlearn.Prediction"
        )
    poses = prediction.poses()
    expected = source.poses()
    names = (
        {b.id: b.name for b in source.bodies if not is_skipped(b.name)}
        if isinstance(source, State)
        else {}
    )

    def label(id_: int) -> str:
        return f"body {id_} ({names[id_]})" if id_ in names else f"body {id_}"

    for id_, pose in sorted(poses.items()):
        if id_ not in expected:
            raise ValueError(
                f"predict() returned a pose for {label(id_)}, which is not in the state it "
                f"predicts from (ids {sorted(expected)})"
            )
        for field, value in zip(("x", "y", "theta"), pose, strict=True):
            if not math.isfinite(value):
                raise ValueError(
                    f"predict() returned a non-finite {field} ({value}) for {label(id_)}"
                )
    missing = sorted(set(expected) - set(poses))
    if missing:
        raise ValueError(
            "predict() returned no pose for " + ", ".join(label(id_) for id_ in missing)
        )
    return poses


def _check_act(result: Any) -> Any:
    try:
        action, has_target = result
        vx, vy = action
    except (TypeError, ValueError):
        raise ValueError(
            f"act() returned {result!r}, expected ((vx, vy), has_target)"
        ) from None
    numpy = sys.modules.get("numpy")  # a numpy bool can only come from a loaded numpy
    if numpy is not None and isinstance(has_target, numpy.bool_):
        has_target = bool(has_target)
    if not isinstance(has_target, bool):
        raise TypeError(f"act() returned has_target = {has_target!r}, expected a bool")
    return learner_pb2.ActionReply(
        action=learner_pb2.Action(
            vx=_finite_number(vx, "act()'s vx"), vy=_finite_number(vy, "act()'s vy")
        ),
        has_target=has_target,
    )


class _Session:
    """One connection's worth of the learner protocol."""

    def __init__(
        self,
        learner: Learner | LearnerFactory,
        reader: framing.Readable,
        writer: framing.Writable,
        refusal: str | None = None,
    ) -> None:
        self._source = learner
        # Set when the session must not start (a daemon at its connection
        # cap): the driver gets this as the Error answering its Start.
        self._refusal = refusal
        self._learner: Learner | None = None
        self._reader = reader
        self._writer = writer
        self._last_seq = 0
        self._last_observed: State | None = None
        self._last_prediction: Prediction | None = None

    # -- replies -----------------------------------------------------------

    def _send(self, reply: Any) -> None:
        try:
            framing.write_frame(self._writer, reply)
        except (BrokenPipeError, ConnectionError) as err:
            _log(
                f"the driver closed the connection before the reply to seq {reply.seq}: {err}"
            )
            raise _Stop(1) from err

    def _fail(self, seq: int, message: str) -> _Stop:
        """Sends an Error reply and returns the exception that ends the session."""
        _log(f"stopping after request {seq}: {message}")
        self._send(learner_pb2.Reply(seq=seq, error=learner_pb2.Error(message=message)))
        return _Stop(1)

    # -- the loop ----------------------------------------------------------

    def run(self) -> int:
        try:
            while True:
                try:
                    request = framing.read_frame(self._reader, learner_pb2.Request)
                except ProtocolError as err:
                    raise self._fail(0, f"ProtocolError: {err}") from err
                except (ConnectionError, OSError) as err:
                    _log(f"reading the next request failed: {err}")
                    return 1
                if request is None:
                    return 0
                if self._handle(request):
                    return 0
        except _Stop as stop:
            return stop.status

    def _resolve(self, ref: Any, call: str, seq: int) -> StateLike:
        kind = ref.WhichOneof("state")
        if kind == "observed":
            state = State.from_proto(ref.observed)
            self._last_observed = state
            return state
        if kind == "recent":
            if ref.recent == learner_pb2.LAST_OBSERVED:
                if self._last_observed is None:
                    raise self._fail(
                        seq,
                        f"ProtocolError: {call} refers to LAST_OBSERVED, but no state was sent yet",
                    )
                return self._last_observed
            if ref.recent == learner_pb2.LAST_PREDICTION:
                if self._last_prediction is None:
                    raise self._fail(
                        seq,
                        f"ProtocolError: {call} refers to LAST_PREDICTION, but the learner has "
                        "made no prediction yet",
                    )
                return self._last_prediction
            raise self._fail(
                seq, f"ProtocolError: {call} refers to an unknown Recent ({ref.recent})"
            )
        raise self._fail(seq, f"ProtocolError: {call} carries no state")

    def _handle(self, request: Any) -> bool:
        """Handles one request; true when serving should end normally."""
        seq = request.seq
        call = request.WhichOneof("call")
        if seq <= self._last_seq:
            raise self._fail(
                seq,
                f"ProtocolError: request seq {seq} is not greater than the previous one "
                f"({self._last_seq}): seqs start at 1 and increase",
            )
        self._last_seq = seq
        if call is None:
            raise self._fail(
                seq,
                f"ProtocolError: request {seq} carries no call this learner knows (a newer driver?)",
            )
        if call == "bye":
            return True
        if self._learner is None and call != "start":
            raise self._fail(
                seq,
                f"ProtocolError: the first request must be Start, not {_CALL_NAMES[call]}",
            )
        try:
            reply = self._dispatch(call, getattr(request, call), seq)
        except _Stop:
            raise
        except Exception as err:  # learner code failed: report, log, stop
            _log(f"{_CALL_NAMES[call]} (seq {seq}) raised:")
            traceback.print_exc(file=sys.stderr)
            sys.stderr.flush()
            raise self._fail(seq, f"{type(err).__name__}: {err}") from err
        if reply is not None:
            self._send(learner_pb2.Reply(seq=seq, **reply))
        return False

    def _dispatch(self, call: str, body: Any, seq: int) -> dict[str, Any] | None:
        if call == "start":
            return self._start(body, seq)
        learner = self._learner
        assert learner is not None
        if call == "new_fold":
            learner.new_fold(int(body.seed))
        elif call == "reset":
            learner.reset(self._resolve(body.state, "Reset", seq))
        elif call == "update":
            state = self._resolve(body.state, "Update", seq)
            learner.update(state, (body.action.vx, body.action.vy))
        elif call == "set_training":
            learner.set_training(bool(body.on))
        elif call == "predict":
            source = self._resolve(getattr(body, "from"), "Predict", seq)
            prediction = learner.predict(source, (body.action.vx, body.action.vy))
            try:
                message = _check_prediction(prediction, source)
            except (TypeError, ValueError) as err:
                raise self._fail(seq, f"InvalidPrediction: {err}") from err
            self._last_prediction = prediction
            return {"prediction": message}
        elif call == "set_target":
            target = None if body.clear else Target(body.id, body.x, body.y, body.theta)
            try:
                learner.set_target(target)
            except TargetRefused as refused:
                return {
                    "target": learner_pb2.TargetReply(
                        accepted=False, refusal=refused.reason
                    )
                }
            return {"target": learner_pb2.TargetReply(accepted=True)}
        elif call == "act":
            result = learner.act()
            try:
                return {"action": _check_act(result)}
            except (TypeError, ValueError) as err:
                raise self._fail(seq, f"InvalidAction: {err}") from err
        elif call == "get_stats":
            stats = learner.stats()
            try:
                return {"stats": _stats_to_proto(stats)}
            except (TypeError, ValueError) as err:
                raise self._fail(seq, f"InvalidStats: {err}") from err
        else:  # a second Start
            raise self._fail(
                seq, f"ProtocolError: unexpected {_CALL_NAMES.get(call, call)}"
            )
        return None

    def _start(self, start: Any, seq: int) -> dict[str, Any]:
        if self._refusal is not None:
            raise self._fail(seq, self._refusal)
        if self._learner is not None:
            raise self._fail(seq, "ProtocolError: Start was sent twice")
        if start.protocol_version != PROTOCOL_VERSION:
            raise self._fail(
                seq,
                f"ProtocolError: the driver speaks learner protocol version "
                f"{start.protocol_version}, this learner (pushlearn Python SDK) version "
                f"{PROTOCOL_VERSION}",
            )
        learner = _started(self._source, start.task, int(start.publish_rate_hz))
        self._learner = learner
        capabilities = sorted(int(Capability(c)) for c in learner.capabilities)
        return {
            "hello": learner_pb2.Hello(
                protocol_version=PROTOCOL_VERSION,
                name=learner.display_name,
                version=str(learner.version),
                capabilities=capabilities,
                ignores_actuator_yaw=bool(learner.ignores_actuator_yaw),
            )
        }


def _started(
    source: Learner | LearnerFactory, task: str, publish_rate_hz: int
) -> Learner:
    """The learner ``source`` is or makes, started for ``task``: what a Start does."""
    learner = source if isinstance(source, Learner) else source()
    if not isinstance(learner, Learner):
        raise TypeError(
            f"the learner factory returned {type(learner).__name__}, not a pushlearn.Learner"
        )
    learner.start(task, publish_rate_hz)
    return learner


def _serve_on_streams(
    learner: Learner | LearnerFactory,
    reader: framing.Readable,
    writer: framing.Writable,
) -> int:
    return _Session(learner, reader, writer).run()


def serve(
    learner: Learner | LearnerFactory,
    *,
    stdin: framing.Readable | None = None,
    stdout: framing.Writable | None = None,
) -> int:
    """Serves the learner protocol until ``Bye``, the end of the input, or an error.

    ``learner`` is a :class:`Learner` or something that makes one (the class
    itself, a function), called when the driver's Start arrives, so that an
    error in the constructor reaches the driver as an ``Error`` reply.
    ``stdin`` and ``stdout`` default to the process's binary stdin and
    stdout; pass binary streams (pipes, ``socket.makefile`` files,
    ``io.BytesIO``) to serve elsewhere.

    When serving on the process's stdout (``stdout`` not given), file
    descriptor 1 and ``sys.stdout`` are redirected to stderr for the
    duration and the frames go to a private duplicate of the original
    stdout, so that nothing else can corrupt the stream.

    Returns the process exit status to use: 0 when the driver ended the
    session (Bye or end of input), 1 after an error was reported (its
    traceback, if any, is on stderr). Typical use:
    ``raise SystemExit(serve(MyLearner))``.
    """
    if isinstance(learner, type) and not issubclass(learner, Learner):
        raise TypeError(
            f"serve() needs a pushlearn.Learner subclass, got the class {learner.__name__}"
        )
    if not isinstance(learner, Learner) and not callable(learner):
        raise TypeError(
            f"serve() needs a pushlearn.Learner or a factory making one, got {type(learner).__name__}"
        )
    reader: framing.Readable = stdin if stdin is not None else sys.stdin.buffer
    if stdout is not None:
        return _serve_on_streams(learner, reader, stdout)
    with _FramesToRealStdout() as writer:
        return _serve_on_streams(learner, reader, writer)


class _FramesToRealStdout:
    """Context manager: fd 1 → stderr, yields a writer on the original stdout."""

    def __enter__(self) -> IO[bytes]:
        sys.stdout.flush()
        self._saved_fd = os.dup(1)
        self._saved_stdout = sys.stdout
        os.dup2(2, 1)
        sys.stdout = sys.stderr
        self._writer = os.fdopen(os.dup(self._saved_fd), "wb")
        return self._writer

    def __exit__(self, *exc: object) -> None:
        try:
            self._writer.flush()
        except OSError:
            pass
        finally:
            try:
                self._writer.close()
            except OSError:
                pass
            sys.stdout = self._saved_stdout
            os.dup2(self._saved_fd, 1)
            os.close(self._saved_fd)


# --------------------------------------------------------------------------
# TCP


class _Handler(socketserver.StreamRequestHandler):
    server: LearnerServer

    def setup(self) -> None:
        super().setup()
        self.connection.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)

    def handle(self) -> None:
        peer = "{}:{}".format(*self.client_address[:2])
        if not self.server.slots.acquire(blocking=False):
            limit = self.server.max_connections
            _Session(
                self.server.factory,
                self.rfile,
                self.wfile,
                refusal=f"too many connections: this learner daemon serves at most {limit} at once",
            ).run()
            return
        try:
            status = _serve_on_streams(self.server.factory, self.rfile, self.wfile)
        finally:
            self.server.slots.release()
        if status != 0:
            _log(f"the session with {peer} ended with an error")


class LearnerServer(socketserver.ThreadingTCPServer):
    """A TCP daemon serving the learner protocol: one fresh learner per connection.

    Each connection runs in its own (daemon) thread with a learner made by
    ``factory``. :func:`serve_tcp` is the usual entry; use the class directly
    to run the server in the background (``serve_forever`` in a thread,
    ``shutdown`` and ``server_close`` to stop).
    """

    daemon_threads = True
    allow_reuse_address = True

    def __init__(
        self,
        factory: LearnerFactory,
        host: str = "127.0.0.1",
        port: int = 0,
        max_connections: int = 64,
    ) -> None:
        if max_connections < 1:
            raise ValueError(
                f"max_connections must be at least 1, got {max_connections}"
            )
        if isinstance(factory, Learner):
            raise TypeError(
                "a TCP learner daemon needs a factory (e.g. the Learner class), not a learner "
                "instance: every connection gets a fresh learner"
            )
        if not callable(factory):
            raise TypeError(
                f"the learner factory must be callable, got {type(factory).__name__}"
            )
        self.factory = factory
        """Makes each connection's learner."""
        self.max_connections = max_connections
        """Sessions served at once; one more gets an ``Error`` answering its Start."""
        self.slots = threading.BoundedSemaphore(max_connections)
        self.address_family = socket.AF_INET6 if ":" in host else socket.AF_INET
        super().__init__((host, port), _Handler)

    @property
    def address(self) -> tuple[str, int]:
        """The bound ``(host, port)`` (the real port when 0 was asked for)."""
        host, port = self.server_address[:2]
        return str(host), int(port)

    @property
    def address_text(self) -> str:
        """The bound address as ``HOST:PORT`` (``[HOST]:PORT`` for IPv6)."""
        host, port = self.address
        return f"[{host}]:{port}" if ":" in host else f"{host}:{port}"


def serve_tcp(
    factory: LearnerFactory,
    host: str = "127.0.0.1",
    port: int = 0,
    max_connections: int = 64,
) -> None:
    """Runs a learner daemon on ``host:port`` until interrupted.

    Every connection is one driver session with a fresh learner from
    ``factory`` (a :class:`Learner` subclass or a function returning a
    learner), in its own thread. Once bound, prints ``listening on
    HOST:PORT`` (the real port when ``port`` is 0) to **stdout** and
    flushes it, as ``pushlearn-sim`` does; logs go to stderr. Binds the
    loopback address by default: the protocol has no authentication. At
    most ``max_connections`` sessions run at once; one more is answered
    with an ``Error`` (``too many connections: …``) and closed.
    """
    with LearnerServer(factory, host, port, max_connections) as server:
        print(f"listening on {server.address_text}", flush=True)
        try:
            server.serve_forever()
        except KeyboardInterrupt:
            pass
