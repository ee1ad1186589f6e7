"""The pushlearn models, implemented in Rust (crates/python, PyO3).

Model is any model of the registry by its name, with the command line's
options by keyword. GateModel, InteractionModel and HybridModel are typed
classes of three of them, one method per method of the Rust
``learner::Model`` trait; GateWorld, InteractionWorld
and HybridWorld are their world states, returned by ``parse`` and
``predict``. Aitm is the memory-based regressor and classifier the thesis's
learners are built from.

World is the lock-step world of ``pushlearn-sim`` inside this process (the
daemon's own code: same scenes, checks, latency emulation and states, bit
for bit), Worlds several of them stepped in one call, and
:func:`step_messages` the physics floor of ``python -m
pushlearn.envs.throughput``.

Every class may be used from any thread. The models hold the GIL, so calls
on one object from several threads run one after another; World and Worlds
release it while the world steps, and worlds stepped from several threads
take turns in ODE (one process-wide lock) and stay bit-identical.
"""

from collections.abc import Callable, Sequence
from typing import Any, TypeAlias, final

import numpy as np
import numpy.typing as npt

from .learner import Shape

SOURCE_CHECKOUT: str
"""The repository checkout the extension was built from (its ``target/release``
holds the ``pushlearn-sim`` the Gymnasium environments look for last)."""

GOAL_TOLERANCE: float
"""A block has reached its target when :func:`goal_distance` is below this (0.01)."""

def goal_distance(
    pose: tuple[float, float, float], target: tuple[float, float, float]
) -> float:
    """The norm of ``(Δx, Δy, wrap(Δθ))`` from ``pose`` to ``target``: the one success
    criterion every task with a goal is judged by (``docs/spec/experiments.md`` §4.4)."""

def goal_distances(
    achieved: npt.NDArray[np.float64], desired: npt.NDArray[np.float64]
) -> npt.NDArray[np.float64]:
    """:func:`goal_distance` of every block of every row: ``achieved`` and ``desired``
    of shape ``(n, 3k)`` (x, y, θ per block), the result ``(n, k)``; ``ValueError``
    for other shapes."""

ACTUATOR_ID: int
"""The actuator's body id (8)."""
ACTUATOR_NAME: str
"""The actuator's body name (``actuator``)."""
BLUE_ID: int
"""The blue block's id (15, ``blockA``)."""
RED_ID: int
"""The red block's id (27, ``blockB``)."""
MAX_POSITION: float
"""The farthest any body is from the origin on an axis, in metres (1000)."""

def quaternion_to_yaw(x: float, y: float, z: float, w: float) -> float:
    """The yaw of the quaternion ``(x, y, z, w)`` as the learners read it (Rust
    ``pushlearn_core::orientation::yaw``), unrounded."""

def yaw_to_quaternion(theta: float) -> tuple[float, float, float, float]:
    """The quaternion ``(x, y, z, w)`` of a rotation by ``theta`` about z."""

def is_skipped(name: str) -> bool:
    """Whether the learners skip a body of this name (the ground, walls, ghosts)."""

def check_stats(document: str) -> None:
    """Raises ValueError, with the experiment driver's reason, unless ``document`` (the
    JSON of ``{maps, extra, labels}``) is statistics the driver accepts from a learner."""

# What an experiment gives pushlearn.bench: the report document (JSON), the
# text ``pushlearn experiment`` prints, and each table as (name, title lines, CSV).
_Cell: TypeAlias = int | float | str | None

@final
class Table:
    """One table of a report, as ``pushlearn experiment --csv`` writes it (made
    by the native run; not constructible)."""

    @property
    def name(self) -> str:
        """The table's name (the CSV file's: ``learning-curve``, …)."""
    @property
    def title(self) -> str:
        """The lines printed above it."""
    @property
    def columns(self) -> list[str]:
        """The column names, in order."""
    @property
    def rows(self) -> list[dict[str, _Cell]]:
        """The rows: dicts by column name, numbers as int or float, empty cells
        ``None`` (``pandas.DataFrame(table.rows)`` takes them); a new list each time."""

@final
class Report:
    """What an experiment gave: its report document and its tables, assembled
    and held by the native run (not constructible)."""

    @property
    def document(self) -> dict[str, Any]:
        """The JSON document ``pushlearn experiment --json`` writes, as a dict (a
        new one each time)."""
    @property
    def tables(self) -> list[Table]:
        """The tables ``pushlearn experiment`` prints, beside the thesis's numbers."""
    @property
    def printed(self) -> str:
        """The text ``pushlearn experiment`` prints: every table, with the thesis's numbers."""
    def table(self, name: str) -> Table:
        """The table called ``name``; ``KeyError`` naming the tables there are if none is."""
    def to_json(self) -> str:
        """The document as ``pushlearn experiment --json`` writes it."""
    def text(self) -> str:
        """What ``pushlearn experiment`` prints for the experiment."""

def run_experiment(
    command: str,
    words: list[str],
    *,
    learner: Any | None,
    progress: Callable[[int, int], None] | None,
    timeout: float,
) -> Report:
    """``pushlearn experiment COMMAND WORDS…`` in this process: the words parsed and
    lowered by the command's own parser (ValueError with its message, naming the
    option), run with ``learner`` (a ``pushlearn.bench._Direct``) in place of the
    options' learner when given; ``progress(done, jobs)`` after each job; each
    learner call made on the calling thread, given ``timeout`` seconds. Writes the
    outputs the words ask for (``--json``, ``--plots``, ``--csv``)."""

def experiment_options(command: str) -> list[tuple[str, bool, list[str], list[str]]]:
    """Every option of ``pushlearn experiment COMMAND``, from the command's
    definition: ``(name without --, switch, values it takes by name, default)``."""

def without_timing(document: str) -> str:
    """A report document's JSON without its machine-dependent part."""

# One body of a world-state message: (name, id, (x, y, z), (qx, qy, qz, qw)),
# optionally with its shape as a fifth element.
_Body: TypeAlias = (
    tuple[str, int, Sequence[float], Sequence[float]]
    | tuple[str, int, Sequence[float], Sequence[float], Shape | None]
)

class GateWorld:
    """A world state of the gate model, parsed or predicted (returned by
    GateModel.parse and GateModel.predict; not constructible).

    It holds the model's own world unchanged, including the identity of its
    block records (docs/spec/gate-model.md §4.1): a block the model adopted as
    its record shows the model's current state whenever it is read, as in the
    original. Never rebuild a world from its poses.
    """

    def poses(self) -> npt.NDArray[np.float64]:
        """The world's bodies as a float64 array of shape (n, 4), one row
        ``[id, x, y, theta]`` per body: the actuator (id 8) first, then the
        blocks in ascending id order (``Model::poses``)."""

class GateModel:
    """The object-state model with gating function (docs/spec/gate-model.md).

    ``config`` is the original's configuration number, the sum of its bits (1
    USE_DYNS, 2 LOWFREQ, 4 and 8 driver-only, 16 HARDCODEDACT, 32
    HARDCODEDGATE, 64 USINGPREDICTIONBOOST); ``eta`` the forward models'
    learning rate (0 in the final thesis); ``publish_rate_hz`` the world's
    rate (10 selects the LOWFREQ thresholds, as bit 2 does);
    ``no_angular_velocity`` leaves the block's angular velocity out of the
    USE_DYNS features; ``improve`` names changes beyond the thesis as
    ``--improve`` does: "unrounded", "interpolate", "adapt-actuator",
    "average-outputs", "forward-check", "shared-blocks", or "all", which is
    the command line's gate+ model (docs/models.md, "Beyond the thesis").
    The checks and the texts of the ValueError they raise are the command
    line's (``pushlearn learn --model gate``), from the same model registry.

    Thread safety: a GateModel may be used from any thread (it is Send and
    Sync in Rust); every method holds the GIL throughout, so calls from
    several threads on one model run one after another.
    """

    def __init__(
        self,
        config: int = 0,
        eta: float = 0.0,
        publish_rate_hz: int = 100,
        no_angular_velocity: bool = False,
        improve: Sequence[str] = (),
    ) -> None:
        """Raises ValueError for unknown configuration bits, a negative or
        non-finite eta, no_angular_velocity without bit 1, an unknown change
        in improve (the message lists the valid names), or an integer out of
        range."""
    @property
    def name(self) -> str:
        """The name reports give this model, as ``pushlearn experiment``
        names it: "gate", "gate+" (every change) or "gate+CHANGE+…"."""
    @property
    def ignores_actuator_yaw(self) -> bool:
        """Whether the driver reads the actuator's yaw as 0 for this model
        (``Hello.ignores_actuator_yaw``)."""
    def parse(self, bodies: Sequence[_Body]) -> GateWorld:
        """Parse one world-state message into a world of this model
        (``Model::parse``).

        ``bodies`` lists every body of the message as
        ``(name, id, (x, y, z), (qx, qy, qz, qw))``: the model's name, its id,
        its position in metres and its orientation quaternion in the order x,
        y, z, w; a fifth element, the body's :class:`pushlearn.Shape` (or
        None), shows the model the body's shape, as the learner protocol's
        states do. The actuator is the body named "actuator" (id 8); blocks
        need an id of the learner's shape table (15 "blockA", 27 "blockB").
        Parsing learns nothing.

        Raises ValueError with the parser's reason when the message has no
        actuator, an unknown or duplicate id, a non-finite number or a shape
        no world can have.
        """
    def reset_objects(self, world: GateWorld) -> None:
        """Re-synchronise with ``world`` at the first message of a run,
        without learning (``Model::reset_objects``)."""
    def update(self, world: GateWorld, vx: float, vy: float) -> None:
        """Learn from the transition from the model's stored state into
        ``world`` under the action (vx, vy) in m/s that was in force
        meanwhile, then store ``world`` (``Model::update``). With training off
        only the stored state moves on.

        Raises ValueError if vx or vy is not finite.
        """
    def predict(self, world: GateWorld, vx: float, vy: float) -> GateWorld:
        """The predicted world one message after ``world`` (parsed or itself a
        prediction) if the action (vx, vy) is in force (``Model::predict``).
        Learns nothing.

        Raises ValueError if vx or vy is not finite.
        """
    def set_training(self, on: bool) -> None:
        """Turn training on (a new model's default) or off
        (``Model::set_training``)."""
    @property
    def is_training(self) -> bool:
        """Whether ``update`` currently trains (``Model::is_training``)."""
    def set_target(self, id: int, x: float, y: float, theta: float) -> None:
        """Set the Move-to-Target goal: block ``id`` at (x, y) m with yaw
        ``theta`` rad (``Model::set_target``).

        Raises ValueError with the model's reason (the actuator, a non-finite
        pose, an object the model cannot plan for); the previous target then
        stays in place.
        """
    def clear_target(self) -> None:
        """Clear the Move-to-Target goal (``Model::set_target(None)``)."""
    @property
    def has_target(self) -> bool:
        """Whether a target is set; ``act`` clears it once it finds the target
        reached (``Model::has_target``)."""
    def seed(self, seed: int) -> None:
        """Seed the exploration generator that ``act`` draws from: ChaCha8
        seeded with ``seed_from_u64(seed)``, as the experiment driver seeds
        each job's generator, so that ``act`` draws the same stream as an
        in-process run with that seed. A model that was never seeded uses
        seed 0. ``seed`` must be in 0 .. 2**64 - 1 (else ValueError)."""
    def act(self) -> tuple[float, float]:
        """The next action (vx, vy) in m/s towards the target from the model's
        stored state (``Model::act``); (0.0, 0.0) without a target or once it
        is reached, when the target is cleared. Its exploration fallback draws
        from the generator of ``seed``."""
    def stats(self) -> dict[str, Any]:
        """The model's statistics (``Model::stats``) in their serialised form:
        ``{"maps": {name: {"update_calls": int, "inserts": int, "nodes": int}},
        "extra": {name: float}, "labels": {name: str}}``. The gate model's maps
        are "actuator", "gate" and "predictor/<block id>"."""
    def copy(self) -> GateModel:
        """A deep copy: the learned memory, the stored state, the target and
        the generator's state, shared with nothing (e.g. a fresh model for
        each fold from an untrained template)."""

class InteractionWorld:
    """A world state of the interaction model, parsed or predicted (returned
    by InteractionModel.parse and InteractionModel.predict; not
    constructible): the object states and the interaction states computed
    from them."""

    def poses(self) -> npt.NDArray[np.float64]:
        """The world's bodies as a float64 array of shape (n, 4), one row
        ``[id, x, y, theta]`` per body: the actuator (id 8) first, then the
        blocks in ascending id order (``Model::poses``; for predictions the
        finalised objects, the actuator's yaw 0)."""

class InteractionModel:
    """The pairwise interaction-state model with Abstract Collections
    (docs/spec/interaction-model.md).

    ``config`` is the original's configuration number (only bit 2, LOWFREQ,
    and the driver-only bits 4 and 8 apply); ``eta`` the Abstract
    Collections' learning rate (0 in the final thesis); ``publish_rate_hz``
    the world's rate (10 selects the LOWFREQ thresholds, as bit 2 does);
    ``selector`` the Abstract Collection Selector: "aitm" (final thesis),
    "tree", "incremental-tree" or "nearest" (the thesis draft's variants).
    The checks and the texts of the ValueError they raise are the command
    line's (``pushlearn learn --model interaction``).

    Thread safety: an InteractionModel may be used from any thread (it is
    Send and Sync in Rust); every method holds the GIL throughout, so calls
    from several threads on one model run one after another.
    """

    def __init__(
        self,
        config: int = 0,
        eta: float = 0.0,
        publish_rate_hz: int = 100,
        selector: str = "aitm",
    ) -> None:
        """Raises ValueError for configuration bits that do not apply, a
        negative or non-finite eta, an unknown selector (the message lists
        the valid names) or an integer out of range."""
    @property
    def name(self) -> str:
        """The name reports give this model: "interaction"."""
    @property
    def ignores_actuator_yaw(self) -> bool:
        """Whether the driver reads the actuator's yaw as 0 for this model
        (``Hello.ignores_actuator_yaw``)."""
    def parse(self, bodies: Sequence[_Body]) -> InteractionWorld:
        """Parse one world-state message into a world of this model
        (``Model::parse``); ``bodies`` as for GateModel.parse.

        Raises ValueError with the parser's reason when the message has no
        actuator, an unknown or duplicate id, or a non-finite number.
        """
    def reset_objects(self, world: InteractionWorld) -> None:
        """Re-synchronise with ``world`` at the first message of a run,
        without learning (``Model::reset_objects``)."""
    def update(self, world: InteractionWorld, vx: float, vy: float) -> None:
        """Learn from the transition from the model's stored state into
        ``world`` under the action (vx, vy) in m/s that was in force
        meanwhile, then store ``world`` (``Model::update``). With training off
        only the stored state moves on.

        Raises ValueError if vx or vy is not finite.
        """
    def predict(
        self, world: InteractionWorld, vx: float, vy: float
    ) -> InteractionWorld:
        """The predicted world one message after ``world`` (parsed or itself a
        prediction) if the action (vx, vy) is in force (``Model::predict``).
        Learns nothing.

        Raises ValueError if vx or vy is not finite.
        """
    def set_training(self, on: bool) -> None:
        """Turn training on (a new model's default) or off
        (``Model::set_training``)."""
    @property
    def is_training(self) -> bool:
        """Whether ``update`` currently trains (``Model::is_training``)."""
    def set_target(self, id: int, x: float, y: float, theta: float) -> None:
        """Set the Move-to-Target goal: block ``id`` at (x, y) m with yaw
        ``theta`` rad (``Model::set_target``).

        Raises ValueError with the model's reason (the actuator, a non-finite
        pose, an object the model cannot plan for); the previous target then
        stays in place.
        """
    def clear_target(self) -> None:
        """Clear the Move-to-Target goal (``Model::set_target(None)``)."""
    @property
    def has_target(self) -> bool:
        """Whether a target is set; ``act`` clears it once it finds the target
        reached (``Model::has_target``)."""
    def seed(self, seed: int) -> None:
        """Seed the exploration generator that ``act`` draws from: ChaCha8
        seeded with ``seed_from_u64(seed)``, as the experiment driver seeds
        each job's generator. A model that was never seeded uses seed 0.
        ``seed`` must be in 0 .. 2**64 - 1 (else ValueError)."""
    def act(self) -> tuple[float, float]:
        """The next action (vx, vy) in m/s towards the target from the model's
        stored state (``Model::act``); (0.0, 0.0) without a target or once it
        is reached, when the target is cleared. Its exploration fallback draws
        from the generator of ``seed``."""
    def stats(self) -> dict[str, Any]:
        """The model's statistics (``Model::stats``) in their serialised form:
        ``{"maps": {name: {"update_calls": int, "inserts": int, "nodes": int}},
        "extra": {name: float}, "labels": {name: str}}``. The interaction
        model's maps are "acs" and "ac/<k>"; "extra" has "ac_count" and the
        largest AC's numbers."""
    def copy(self) -> InteractionModel:
        """A deep copy: the learned memory, the stored state, the target and
        the generator's state, shared with nothing."""

class HybridWorld:
    """A world state of the hybrid model, parsed or predicted (returned by
    HybridModel.parse and HybridModel.predict; not constructible): the
    poses and each block's motion over the message before."""

    def poses(self) -> npt.NDArray[np.float64]:
        """The world's bodies as a float64 array of shape (n, 4), one row
        ``[id, x, y, theta]`` per body: the actuator (id 8) first, then the
        blocks in ascending id order (``Model::poses``)."""

class HybridModel:
    """Pushing mechanics identified online plus a memory of their residual
    (docs/models.md, "The hybrid model"); not a model of the thesis.

    ``publish_rate_hz`` is the world's rate; ``parts`` chooses the model's
    parts for its ablation, as ``--parts`` does: "mechanics" (the shape's
    mechanics alone, learning nothing), "identified" (their parameters
    identified online) or "full" (and the memory of their residual). The
    checks and the texts of the ValueError they raise are the command
    line's (``pushlearn learn --model hybrid``).

    Thread safety: a HybridModel may be used from any thread (it is Send and
    Sync in Rust); every method holds the GIL throughout, so calls from
    several threads on one model run one after another.
    """

    def __init__(self, publish_rate_hz: int = 100, parts: str = "full") -> None:
        """Raises ValueError for unknown parts (the message lists the valid
        names) or an integer out of range."""
    @property
    def name(self) -> str:
        """The name reports give this model: "hybrid", or "hybrid-PARTS"
        with fewer parts."""
    @property
    def ignores_actuator_yaw(self) -> bool:
        """Whether the driver reads the actuator's yaw as 0 for this model
        (``Hello.ignores_actuator_yaw``)."""
    def parse(self, bodies: Sequence[_Body]) -> HybridWorld:
        """Parse one world-state message into a world of this model
        (``Model::parse``); ``bodies`` as for GateModel.parse. A block's
        motion is read against the model's stored state.

        Raises ValueError with the parser's reason when the message has no
        actuator, an unknown or duplicate id, or a non-finite number.
        """
    def reset_objects(self, world: HybridWorld) -> None:
        """Re-synchronise with ``world`` at the first message of a run,
        without learning (``Model::reset_objects``)."""
    def update(self, world: HybridWorld, vx: float, vy: float) -> None:
        """Learn from the transition from the model's stored state into
        ``world`` under the action (vx, vy) in m/s that was in force
        meanwhile, then store ``world`` (``Model::update``). With training off
        only the stored state moves on.

        Raises ValueError if vx or vy is not finite.
        """
    def predict(self, world: HybridWorld, vx: float, vy: float) -> HybridWorld:
        """The predicted world one message after ``world`` (parsed or itself a
        prediction) if the action (vx, vy) is in force (``Model::predict``).
        Learns nothing.

        Raises ValueError if vx or vy is not finite.
        """
    def set_training(self, on: bool) -> None:
        """Turn training on (a new model's default) or off
        (``Model::set_training``)."""
    @property
    def is_training(self) -> bool:
        """Whether ``update`` currently trains (``Model::is_training``)."""
    def set_target(self, id: int, x: float, y: float, theta: float) -> None:
        """Set the Move-to-Target goal: block ``id`` at (x, y) m with yaw
        ``theta`` rad (``Model::set_target``).

        Raises ValueError with the model's reason (the actuator, a non-finite
        pose, an object the model cannot plan for); the previous target then
        stays in place.
        """
    def clear_target(self) -> None:
        """Clear the Move-to-Target goal (``Model::set_target(None)``)."""
    @property
    def has_target(self) -> bool:
        """Whether a target is set; ``act`` clears it once it finds the target
        reached (``Model::has_target``)."""
    def seed(self, seed: int) -> None:
        """Seed the exploration generator that ``act`` draws from, as for
        GateModel.seed."""
    def act(self) -> tuple[float, float]:
        """The next action (vx, vy) in m/s towards the target from the model's
        stored state (``Model::act``); (0.0, 0.0) without a target or once it
        is reached, when the target is cleared."""
    def stats(self) -> dict[str, Any]:
        """The model's statistics (``Model::stats``) in their serialised form:
        ``{"maps": {"residual/<id>": {...}}, "extra": {"tipping/<id>": float,
        "slide_linear/<id>": float, "slide_angular/<id>": float,
        "actuator_action_weight": float, "actuator_previous_weight": float},
        "labels": {"parts": str}}``."""
    def copy(self) -> HybridModel:
        """A deep copy: the learned memory, the stored state, the target and
        the generator's state, shared with nothing."""

def model_names() -> list[str]:
    """The registry's models by name, in its order: the names ``Model`` and
    ``pushlearn experiment --model`` take."""

def model_options_names() -> list[str]:
    """The keyword options ``Model`` takes: the command line's model options
    spelt with underscores (each model refuses those it does not take)."""

class ModelWorld:
    """A world state of a :class:`Model`, parsed or predicted (returned by
    Model.parse and Model.predict; not constructible). It belongs to the
    model kind that made it: a model of another kind refuses it with
    TypeError."""

    def poses(self) -> npt.NDArray[np.float64]:
        """The world's bodies as a float64 array of shape (n, 4), one row
        ``[id, x, y, theta]`` per body: the actuator (id 8) first, then the
        blocks in ascending id order (``Model::poses``)."""
    @property
    def model(self) -> str:
        """The report name of the model that made this world."""

class Model:
    """Any model of the registry by its name: ``Model(name,
    publish_rate_hz=100, **options)``.

    ``name`` is a model of ``pushlearn experiment --model``
    (:func:`model_names` lists them); the options are the command line's
    model options by keyword, spelt with underscores
    (:func:`model_options_names`: ``config``, ``flags``, ``eta``,
    ``selector``, ``no_angular_velocity``, ``improve``, ``parts``), their
    values by the command line's names; ``flags`` and ``improve`` take a
    list or one comma-separated string. The model is built and checked by
    the registry the command line uses, so a new model needs no binding of
    its own.

    The methods are the typed classes' (:class:`GateModel`, …), with worlds
    of type :class:`ModelWorld`. Thread safety as theirs.
    """

    def __init__(self, name: str, publish_rate_hz: int = 100, **options: Any) -> None:
        """Raises ValueError for an unknown model (the message lists the
        names), an option the model does not take or a bad value (the
        command line's reason); TypeError for an unknown option (the
        message lists the options)."""
    @property
    def name(self) -> str:
        """The name reports give this model under its options, as
        ``pushlearn experiment`` names it (e.g. "gate+unrounded",
        "hybrid-mechanics")."""
    @property
    def kind(self) -> str:
        """The registry's name the model was built by."""
    @property
    def options(self) -> str:
        """The options in one canonical line (``ModelOptions::canonical``)."""
    @property
    def ignores_actuator_yaw(self) -> bool:
        """Whether the driver reads the actuator's yaw as 0 for this model
        (``Hello.ignores_actuator_yaw``)."""
    def parse(self, bodies: Sequence[_Body]) -> ModelWorld:
        """Parse one world-state message into a world of this model; as
        GateModel.parse."""
    def reset_objects(self, world: ModelWorld) -> None:
        """Re-synchronise with ``world`` at the first message of a run,
        without learning. TypeError for another model's world."""
    def update(self, world: ModelWorld, vx: float, vy: float) -> None:
        """Learn from the transition into ``world`` under (vx, vy); as
        GateModel.update. TypeError for another model's world."""
    def predict(self, world: ModelWorld, vx: float, vy: float) -> ModelWorld:
        """The predicted world one message after ``world`` under (vx, vy);
        learns nothing. TypeError for another model's world."""
    def set_training(self, on: bool) -> None:
        """Turn training on (a new model's default) or off."""
    @property
    def is_training(self) -> bool:
        """Whether ``update`` currently trains."""
    def set_target(self, id: int, x: float, y: float, theta: float) -> None:
        """Set the Move-to-Target goal; ValueError with the model's reason."""
    def clear_target(self) -> None:
        """Clear the Move-to-Target goal."""
    @property
    def has_target(self) -> bool:
        """Whether a target is set."""
    def seed(self, seed: int) -> None:
        """Seed the exploration generator ``act`` draws from; as
        GateModel.seed."""
    def act(self) -> tuple[float, float]:
        """The next action (vx, vy) in m/s towards the target."""
    def stats(self) -> dict[str, Any]:
        """The model's statistics in their serialised form; as
        GateModel.stats."""
    def copy(self) -> Model:
        """A deep copy, shared with nothing."""

class Aitm:
    """The Adapted Instantaneous Topological Map (docs/spec/aitm.md): a
    growing graph of nodes in input space, each with an output vector and a
    local linear map; nodes are inserted where the map's own answer to a
    training sample is wrong.

    ``mode`` is the query mode, used for queries and for the map's own
    estimate during update: "winner", "besttwo" or "neighbour" (case does not
    matter). ``sigma`` is the width of the Gaussian interpolation weights,
    ``eps_max`` the distance below which no node is inserted, ``eta_in`` /
    ``eta_out`` / ``eta_a`` the winner's learning rates (0 in every evaluated
    instance), ``classifier`` whether outputs are integer class labels. The
    defaults are the evaluated instances' (``AitmParams::regressor``); the
    gate model's predictors use "besttwo", its classifiers and the
    interaction model's maps "winner".

    Arrays may be anything ``numpy.asarray`` turns into float64 numbers.
    """

    def __init__(
        self,
        input_dim: int,
        output_dim: int,
        *,
        mode: str,
        sigma: float = 0.05,
        eps_max: float = 0.001,
        eta_in: float = 0.0,
        eta_out: float = 0.0,
        eta_a: float = 0.0,
        classifier: bool = False,
    ) -> None:
        """Raises ValueError with the Rust check's text for invalid
        hyperparameters, for an unknown mode (listing the valid ones), and for
        negative or absurdly large dimensions (input_dim × output_dim at most
        2**24)."""
    def update(self, x: npt.ArrayLike, y: npt.ArrayLike) -> None:
        """One training step update(x, y) (docs/spec/aitm.md §4): ``x`` is a
        1-D array of input_dim finite numbers, ``y`` one of output_dim.

        Raises ValueError if either has the wrong shape or a non-finite
        element (naming which).
        """
    def update_label(self, x: npt.ArrayLike, label: int) -> None:
        """Train a one-output map with the integer class label ``label``
        (update(x, [label])); ``x`` as for update.

        Raises ValueError unless output_dim is 1, or for a bad x.
        """
    def predict(self, x: npt.ArrayLike) -> npt.NDArray[np.float64]:
        """The map's answer f(x, mode) (docs/spec/aitm.md §3); zeros for a map
        that was never trained.

        ``x`` is a 1-D array of input_dim finite numbers (the result is a 1-D
        float64 array of output_dim numbers) or a 2-D array of shape
        (n, input_dim), one input per row (the result has shape
        (n, output_dim)). Raises ValueError for another shape or a non-finite
        element.
        """
    def classify(self, x: npt.ArrayLike) -> int | None:
        """The classifier's answer (docs/spec/aitm.md §6): the winner's label
        for the 1-D input ``x``, or None if the map was never trained or has
        no output. ``x`` as for update."""
    @property
    def node_count(self) -> int:
        """The current number of nodes."""
    @property
    def input_dim(self) -> int:
        """The input dimension."""
    @property
    def output_dim(self) -> int:
        """The output dimension."""
    def stats(self) -> dict[str, int]:
        """The map's counters: ``{"update_calls": int, "inserts": int (nodes
        ever inserted), "nodes": int (current nodes)}``."""
    def copy(self) -> Aitm:
        """A deep copy of the map."""

class World:
    """The lock-step world of ``pushlearn-sim serve --mode lockstep`` in this process.

    ``scene`` is a built-in scene name (``one_block``, ``two_blocks``,
    ``objects``) or a scene file, as ``--scene`` takes it; ``latency_max``
    and ``latency_seed`` are ``--latency-max`` and ``--latency-seed``
    (``None``: no latency emulation), ``publish_rate`` is ``--rate`` (Hz,
    ``None``: the scene's). Every command is the message a
    :class:`pushlearn.SimClient` would send, checked by the daemon's own
    checks: what the daemon refuses raises ``ValueError`` with its text
    (unknown scene or body, a non-finite or out-of-range number, an Advance
    while paused, …), and a physics blow-up (the world resets itself) raises
    ``RuntimeError``. Commands return their seq, numbered from 1.

    States are float64 arrays with a row per dynamic body (:attr:`body_names`,
    scene order) and 13 columns: position x, y, z; orientation quaternion x,
    y, z, w; linear velocity x, y, z; angular velocity x, y, z (world frame,
    m, m/s, rad/s). With ``planar=True`` 6 columns: x, y, yaw (as the
    learners read it), vx, vy and the spin about z.
    """

    def __init__(
        self,
        scene: str = "one_block",
        *,
        latency_max: int | None = None,
        latency_seed: int = 0,
        publish_rate: int | None = None,
    ) -> None: ...
    @property
    def scene(self) -> str:
        """The scene as given."""
    @property
    def body_names(self) -> list[str]:
        """The dynamic bodies' names: the rows of a state, in order."""
    @property
    def latency_max(self) -> int | None:
        """The latency emulation's largest delay of a Move in steps (``None``: none)."""
    def hello_bytes(self) -> bytes:
        """The daemon's Hello for this world (``pushlearn.Hello`` message bytes)."""
    def reset(self) -> int:
        """Every body to its start pose at rest, step and time to 0 (the stored
        actuator command is kept)."""
    def pause(self) -> int:
        """Stops stepping; an Advance is refused until :meth:`unpause`."""
    def unpause(self) -> int:
        """Resumes stepping."""
    def move(self, vx: float, vy: float) -> int:
        """The actuator's velocity (m/s, world frame) until the next Move; the
        world scales it down to its top speed."""
    def set_pose(
        self,
        name: str,
        position: npt.ArrayLike,
        orientation: npt.ArrayLike | None = None,
    ) -> int:
        """Puts body ``name`` at ``position`` (x, y, z) with ``orientation``, the
        quaternion (x, y, z, w) (normalised by the world; default upright).
        ``…Shadow…`` names set the viewer's ghosts."""
    def latency_seed(self, seed: int) -> int:
        """Reseeds the latency emulation (``ValueError`` without it)."""
    def set_publish_rate(self, hz: int) -> int:
        """Publishes every ``1000 / hz`` steps (``hz`` must divide 1000)."""
    def advance(self, *, planar: bool = False) -> npt.NDArray[np.float64]:
        """Runs the world to its next publish (every command sent before is in
        force by then) and returns its state."""
    def move_and_advance(
        self, vx: float, vy: float, *, planar: bool = False
    ) -> npt.NDArray[np.float64]:
        """:meth:`move` and :meth:`advance` in one call: one environment step."""
    def state(self, *, planar: bool = False) -> npt.NDArray[np.float64]:
        """The last published state (``ValueError`` before the first advance)."""
    def state_bytes(self) -> bytes:
        """The last published state as the daemon sent it: ``pushlearn.WorldState``
        message bytes, ghosts and counters included."""
    def counters(self) -> tuple[int, int]:
        """``(step, applied_seq)`` of the last published state."""

class Worlds:
    """Several :class:`World` of one scene's bodies, stepped together in one call
    with the GIL released (the native vector environment's step)."""

    def __init__(self, worlds: Sequence[World]) -> None: ...
    def __len__(self) -> int: ...
    def move_and_advance(
        self,
        velocities: npt.NDArray[np.float64],
        *,
        planar: bool = False,
        stepped: Sequence[bool] | None = None,
    ) -> npt.NDArray[np.float64]:
        """Moves world i at ``velocities[i]`` (m/s; shape ``(len, 2)``) and advances
        it, for every i flagged in ``stepped`` (default all), and returns every
        world's state stacked: shape ``(len, bodies, 13)``, or ``(len, bodies, 6)``
        with ``planar``. Everything is checked before any world steps."""

class GoalTask:
    """The Gymnasium goal environments' step in Rust (``pushlearn.envs``): the
    action's checks, the Move and Advance, the observation's arrays, the goal
    distance, the reward, the flags and the info in one call, with the
    harness's arithmetic (``goal_distance``, ``GOAL_TOLERANCE``)."""

    def __init__(
        self,
        worlds: Sequence[World],
        actuator: int,
        blocks: Sequence[int],
        *,
        speed: float,
        dense: bool,
        terminate_on_success: bool,
        max_episode_steps: int | None = None,
    ) -> None: ...
    def __len__(self) -> int: ...
    def restart(self, i: int, desired: npt.ArrayLike) -> None:
        """World ``i``'s episode began (its reset is done) with target ``desired``."""
    def step(
        self, action: npt.ArrayLike
    ) -> tuple[dict[str, npt.NDArray[np.float64]], float, bool, bool, dict[str, Any]]:
        """One environment's step (a task of one world), as ``gymnasium.Env.step``
        returns it; truncation is the time limit wrapper's."""
    def step_all(
        self, actions: npt.ArrayLike
    ) -> tuple[
        tuple[
            dict[str, npt.NDArray[np.float64]],
            npt.NDArray[np.float64],
            npt.NDArray[np.bool_],
            npt.NDArray[np.bool_],
            dict[str, Any],
        ],
        list[int],
    ]:
        """A step of every world (actions ``(n, 2)``), batched as a vector
        environment's; a world whose episode ended at the last step is not
        stepped, and its index is in the list for Python to restart."""

def step_messages(
    velocities: npt.NDArray[np.float64],
    scene: str = "one_block",
    *,
    latency_max: int | None = None,
    episode_steps: int | None = None,
) -> float:
    """Seconds the world library takes to step ``velocities`` (shape ``(n, 2)``,
    m/s) as Moves, each followed by an Advance, on a fresh :class:`World` of
    ``scene``, with nothing between them: the physics floor. With
    ``episode_steps``, the world is reset after every ``episode_steps``
    messages, as an environment with that time limit resets it."""
