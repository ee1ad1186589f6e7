"""Baseline forward models as learners: k-nearest neighbours, a Gaussian process
and an online ensemble of small neural networks.

Three standard regressors, :class:`KnnLearner` (scikit-learn's
``KNeighborsRegressor``), :class:`GpLearner` (scikit-learn's
``GaussianProcessRegressor``), both computed with numpy and scipy directly
(see "Prediction" and the GP below), and :class:`MlpLearner` (an ensemble of
scikit-learn ``MLPRegressor`` networks trained online with ``partial_fit``),
learning the same per-message transition features behind the same contact
gate, so that the push task's learning curve of the memory-based models can
be compared with off-the-shelf regression given a fair chance. Capability
``FORWARD`` only. Serve them with ``python -m pushlearn.baselines knn``,
``… gp`` or ``… mlp`` (options: ``… knn --help``).

What changed in 0.2.0, and why
------------------------------
Version 0.1.0 regressed the block's change on 4 numbers (the actuator's
position and the action, in the block's frame) everywhere, and moved the
actuator by one gain on the action. An outside learner written from the
protocol page alone (a kNN, k = 4, of the pose change over the actuator's
position and velocity in the block's frame, no motion beyond the largest
contact distance seen) beat it at every N (issue 35). A careful researcher
gives a regressor what the physics needs, so 0.2.0 does:

* **the actuator's velocity** over the last message replaces the action as
  input: with the world's latency the action in force says less about the
  coming motion than the motion just seen, and in the block's frame the
  velocity also tells the block's orientation relative to the push;
* **a contact gate** (:class:`ContactGate`): the regressor learns and
  predicts only where training saw the block pushed; elsewhere the block
  slides freely (its last change times a decay learned by least squares),
  so a test run no longer borrows motion from pushes the actuator is far
  from, and a free slide after release is predicted instead of a stop;
* **the pusher put back onto the contact surface**, along its path: a chained prediction
  that lags the block by a millimetre puts the actuator inside the block,
  where 0.1.0 found only the training samples of pushers sliding past the
  block's ends (no motion) and stopped the block for the rest of the run —
  the largest of its errors (a push off the centre that turns the block by
  0.9 rad was predicted to stop after 0.15 rad);
* **the actuator** fitted on the action in force and the one before it
  (latency delays part of a new Move by a message), with the run's history
  kept across messages (a test run's first message starts at rest).

Which features the regressors see (``--inputs``, default
``position,velocity``) was compared on the thesis draft's protocol (its own
20 test positions, training starts in [−0.35, 0.35), seed 7, 5 folds), never
on the push task's 21 test positions: adding the block's last change
(``motion``) as an input helped little at 3 runs and cost orientation at 10
and 30 runs (chained, a remembered motion feeds itself), so the default
leaves it to the gate's free slide. On the same protocol, putting the pusher
back along its path rather than by the shortest way took a quarter off the
kNN's position error after one run (0.095 against 0.124 m, though 0.06 rad
more in orientation) and was within 0.003 m at 3–30 runs; it was chosen as
the physical choice (:meth:`ContactGate.snap` says why). The MLP's
sizes were fixed before any measurement and are not tuned.

Features (one sample per block and message)
-------------------------------------------
For a transition from state ``s`` into state ``s'`` under the action
``a = (vx, vy)`` in force meanwhile, the state ``s⁻`` one message before
``s`` (none at a run's first message), and each block ``b`` (id) present in
both, with ``R(φ)`` the rotation by φ, all in the block's frame of ``s``
(:data:`FEATURES`, :func:`block_features`):

* **position** (2 numbers): ``R(−θ_b) · (p_actuator − p_b)``;
* **velocity** (2 numbers): the actuator's over the last message,
  ``R(−θ_b) · (p_actuator − p⁻_actuator) · publish_rate_hz`` (zero at a
  run's first message);
* **motion** (3 numbers): the block's change over the last message
  (:func:`block_change` of ``s⁻`` into ``s``; zero at a run's first message);
* **output** (3 numbers): the block's change over the message, in the
  block's frame of ``s``: ``R(−θ_b) · (p'_b − p_b)`` and
  ``Δθ = θ'_b − θ_b`` wrapped to (−π, π].

A prediction applies the predicted change: ``p'_b = p_b + R(θ_b) · Δp``,
``θ'_b = θ_b + Δθ`` (wrapped). One gate and one regressor per block id (the
blocks' shapes differ), fitted on that block's samples; a block without
samples stays where it is.

The history a prediction needs (``s⁻`` and the last action) is the learner's
own: every ``update`` moves it on by a message, ``reset`` starts a run at
rest (no previous state, last action zero), and the push task's first
``update`` of a test run, which restates the run's first state, starts no
history. In a chained test run the history is the learner's own predictions.

The contact gate
----------------
:class:`ContactGate`, fitted on all of a block's samples: the region of
actuator positions at which the block was seen pushed, ``|x| ≤ X``,
``|y| ≤ Y`` and ``|(x, y)| ≤ D``, each the largest seen (the box holds a
rectangle's faces, the radius a round block's rim; the shape need not be
known). A sample counts as pushed when the block translated or turned by
more than :data:`MOVED` per message and that motion did not fade to below
:data:`SLIDING` of the last message's (a free slide fades, a push does
not), so the slide after release does not widen the region. Inside the
region the regressor predicts, from the features with the actuator moved
back onto the region's boundary along its path, against its velocity in the
block's frame (:meth:`ContactGate.snap`, training samples alike); outside, the block slides: ``Δ = decay ⊙ motion``,
``decay`` per output by least squares over the training samples outside
the region (``Σ motion·Δ / Σ motion²``, clipped to [0, 1]); a block at rest
stays at rest. The regressors are fitted on the samples inside the region
only.

**The actuator** is velocity-controlled by the world, so its change is
learned from the actions alone, by the simplest model that generalises to
every direction and knows the latency: two scalar gains with
``Δp_actuator = (g · a + g⁻ · a⁻) / publish_rate_hz`` (``a⁻`` the action in
force one message earlier, zero at a run's start), fitted by least squares
over all training transitions, both axes together (with a single action
throughout, ``g`` alone). The actuator's yaw is kept.

Training and fitting
--------------------
Samples come from :meth:`~pushlearn.Learner.update` while training is on:
the transition from the stored state (the state of the last ``reset`` or
``update``) into the new one under the update's action, exactly as the
learner protocol defines ``Update``. With training off ``update`` only
moves the stored state forward. Runs (the segments between two ``reset``
calls) are the groups of the cross-validation below.

Fitting is lazy: at the first :meth:`predict` with training off after new
samples arrived (so, in a push task, once when the test runs begin). While
training is on, predictions use the last fit (the MLP's, its online
ensemble: below); before any fit, the prior: nothing moves but the
actuator, by ``a / publish_rate_hz``. (The push task
predicts at every training message for display only, so refitting there
would only cost time; the constant-feedback experiment, which never turns
training off, therefore sees only the prior: these baselines are meant for
the push tasks.)

Inputs are standardised with the mean and standard deviation of the
training samples in the contact region (scikit-learn's ``StandardScaler``;
a constant input is left unscaled). Hyper-parameters are chosen on the
training samples only, never on test positions:

* **kNN**: ``k`` in 1 … ``max_k`` (default 50, at most the smallest training
  fold) and ``weights`` ``"uniform"`` or ``"distance"`` by cross-validation,
  minimising the mean squared error of the outputs scaled by their training
  standard deviation. The folds are :class:`~sklearn.model_selection.GroupKFold`
  over the training runs (``min(5, runs)`` folds), so no run is both trained
  on and validated on. With a single run, contiguous segments of it
  (``KFold`` without shuffling, ``min(5, n)`` folds) stand in for runs; with a
  single sample, ``k = 1``. Ties go to the smaller ``k``, then ``uniform``.
* **GP**: kernel ``C · RBF(ℓ₁ … ℓ_d) + White`` (an anisotropic RBF with one
  length scale per input, ``d = 4`` by default, an amplitude and a noise
  level), outputs
  normalised (``normalize_y``), one GP per block for its three outputs
  (shared kernel), a jitter of 1e-10 on the kernel matrix's diagonal,
  hyper-parameters by maximising the log marginal likelihood on the
  training samples with L-BFGS-B (``scipy.optimize.minimize``) over their
  logarithms, from the kernel's initial values (amplitude 1, length scales
  1, noise 0.01) within its bounds, no restarts: scikit-learn's
  ``GaussianProcessRegressor(kernel, normalize_y=True)`` and its default
  optimiser, exactly. Then, with two or more training runs, every length
  scale is stretched by the factor of :data:`GP_STRETCHES` (1, 2, 4 or 8)
  that predicts held-out runs best (the kNN's ``GroupKFold``; amplitude and
  noise kept; ties to the smaller): the likelihood treats a run's dense,
  smooth trajectory as independent samples and picks length scales short
  enough to follow one run, between which the posterior reverts to the
  mean change (new in 0.2.0; on the draft's protocol it took a quarter off
  the position error and nearly half off the orientation error at 30 runs
  and changed little at 3 and 10). The likelihood and its gradient are
  computed here
  (:func:`_gp_neg_log_likelihood`, the same formulas), at a third of
  scikit-learn's cost: it builds ``K⁻¹`` by solving for an identity matrix
  and contracts an n × n × outputs × parameters product, where LAPACK's
  ``potri`` and one n × n product per parameter do. Exact GP fitting costs
  O(n³) time and O(n²) memory, and every prediction O(n), so a GP is fitted
  on at most ``max_samples`` (default 600) of a block's samples in its
  contact region, chosen by a seeded subsample without replacement (seed:
  the fold's seed from ``new_fold``, and the block id). 600 samples are
  about ten training runs' pushes. Each evaluation of the marginal likelihood and its gradient
  factorises the n × n kernel matrix, and the optimiser needs 40–100 of
  them: at n = 600, on one core with one BLAS thread (OpenBLAS's Nehalem
  kernels, as ``pushlearn reproduce`` runs it), one evaluation takes about
  30 ms and a fit 0.5–2.5 s (scikit-learn's: about 0.17 s and 7–17 s);
  the 1800 pushed samples of 30 training runs would cost (1800 / 600)³ ≈ 27
  times as much per evaluation.
* **MLP ensemble**: no hyper-parameter is chosen; the sizes are fixed
  (``--members 5``, ``--hidden 64,64``, ReLU, Adam with step 0.001, an L2
  penalty of 1e-4, minibatches of 32, ``--batch 64``, ``--epochs 30``), as a
  probabilistic-ensemble model-based RL learner fixes them. Each block has
  an ensemble of ``members`` ``MLPRegressor`` networks that differ in their
  seeded initial weights and minibatch order (``random_state`` from the
  fold's seed, the block id and the member's index, through numpy's
  ``SeedSequence``). **Online**: every ``batch`` training messages, each
  member makes one ``partial_fit`` pass over the block's new samples that
  lie in the contact region as the samples so far draw it, inputs and
  outputs standardised with the statistics of that block's memory so far;
  from its first such call the ensemble predicts the training messages.
  **When training ends** (the lazy fit above), the gate is fitted on every
  sample and each member makes ``epochs`` more ``partial_fit`` passes over
  the whole memory in the region, standardised with its final statistics.
  The prediction is the members' mean, computed from their weights (what
  ``MLPRegressor.predict`` computes); an output that never varied in
  training is predicted as its constant, and every change is clipped to the
  range of that output in training (a network extrapolates without bound
  where it saw nothing, after one run most of the region, and a chained
  test run compounds it: unclipped, the first measurement's block flew off
  by metres after one training run). A 30-run fold trains in a few seconds
  on one core.

Prediction
----------
Every message's prediction computes what the scikit-learn estimator behind
a ``StandardScaler`` would predict, without its per-call checks and
pipelines: the features are standardised with the stored mean and scale,
then the kNN queries a scipy ``cKDTree`` of the standardised samples (the
``k`` nearest, their mean or inverse-distance-weighted mean, an exact
match taking all the weight), the GP computes its posterior mean
``k(x*, X) @ α`` with the weights ``α`` stored at the fit (the RBF by
``cdist``, as scikit-learn does, so that it is the same number), and the
MLP ensemble runs its members' layers on the standardised features.

Reproducibility
---------------
A GP's fit and predictions, and an MLP's training, turn on the last bits of
OpenBLAS's and libm's results, which differ between CPUs unless pinned;
``pushlearn reproduce`` therefore runs every baseline with the packages of
``python/constraints.txt`` and the environment its learner command starts
with (``PYTHON_LEARNER_ENV`` in ``crates/lab/src/reproduce/manifest.rs``:
OpenBLAS's Nehalem kernels, one thread, numpy's baseline SIMD loops,
glibc's SSE2 ``exp``). Run by hand with the same assignments in front of
``python -m pushlearn.baselines gp`` (or ``mlp``) to get the same numbers.

Statistics and logs
-------------------
``stats()`` reports the samples as maps, ``actuator_steps`` and
``block/ID`` (``inserts``: samples recorded, ``nodes``: samples in the
contact region the last fit used). The fitted gates are in
:meth:`BaselineLearner.describe_gates`, the chosen hyper-parameters in
:meth:`BaselineLearner.describe_fit`, and, with ``--verbose``, both are
logged to stderr at every fit.

Everything is deterministic given the fold seed.
"""

from __future__ import annotations

import math
import sys
from dataclasses import dataclass, field
from typing import Any, ClassVar

import numpy as np
from numpy.typing import NDArray

from .learner import (
    ACTUATOR_ID,
    Action,
    ArgumentParser,
    Capability,
    Learner,
    Pose,
    Prediction,
    StateLike,
    UsageError,
)

__all__ = [
    "BaselineLearner",
    "ContactGate",
    "CvChoice",
    "GpLearner",
    "KnnLearner",
    "MlpLearner",
    "apply_change",
    "block_change",
    "block_features",
    "main",
    "wrap_angle",
]

Array = NDArray[np.float64]

_EPS_STD = 1e-12


def wrap_angle(angle: float) -> float:
    """``angle`` wrapped to (−π, π]."""
    wrapped = math.remainder(angle, 2.0 * math.pi)
    return math.pi if wrapped == -math.pi else wrapped


FEATURES = (
    "rel_x",
    "rel_y",
    "vel_x",
    "vel_y",
    "prev_dx",
    "prev_dy",
    "prev_dtheta",
)
"""The names of :func:`block_features`' numbers, in order."""


def block_features(
    actuator: Pose,
    block: Pose,
    previous_actuator: Pose | None = None,
    previous_block: Pose | None = None,
    publish_rate_hz: float = 100.0,
) -> list[float]:
    """The regressors' input for one block (:data:`FEATURES`), all in the block's
    frame of the current state: the actuator's position relative to the block,
    the actuator's velocity over the last message (m/s), and the block's own
    change over the last message (:func:`block_change`). Without a previous
    state (a run's first message) the velocity and the change are zero."""
    c, s = math.cos(block.theta), math.sin(block.theta)
    dx, dy = actuator.x - block.x, actuator.y - block.y
    features = [c * dx + s * dy, -s * dx + c * dy, 0.0, 0.0, 0.0, 0.0, 0.0]
    if previous_actuator is not None:
        vx = (actuator.x - previous_actuator.x) * publish_rate_hz
        vy = (actuator.y - previous_actuator.y) * publish_rate_hz
        features[2] = c * vx + s * vy
        features[3] = -s * vx + c * vy
    if previous_block is not None:
        features[4:7] = block_change(previous_block, block, frame=block.theta)
    return features


def block_change(before: Pose, after: Pose, frame: float | None = None) -> list[float]:
    """The regressors' output: the block's change ``[dx, dy, dθ]`` in its frame of
    ``before`` (or in the frame turned by ``frame``)."""
    angle = before.theta if frame is None else frame
    c, s = math.cos(angle), math.sin(angle)
    dx, dy = after.x - before.x, after.y - before.y
    return [c * dx + s * dy, -s * dx + c * dy, wrap_angle(after.theta - before.theta)]


def apply_change(block: Pose, change: Any) -> Pose:
    """The block's pose after a change ``[dx, dy, dθ]`` given in its frame."""
    c, s = math.cos(block.theta), math.sin(block.theta)
    dx, dy, dtheta = (float(v) for v in change)
    return Pose(
        block.x + c * dx - s * dy,
        block.y + s * dx + c * dy,
        wrap_angle(block.theta + dtheta),
    )


MOVED = 1e-4
"""A block's change over one message counts as motion above this (m, or rad)."""

SLIDING = 0.9
"""A moving block whose change fell below this fraction of the last message's
is taken to be sliding freely, not pushed (see :class:`ContactGate`)."""


@dataclass
class ContactGate:
    """Where a block is pushed, as the training samples showed it, and how it
    slides when it is not.

    The contact region is the set of actuator positions (in the block's frame)
    at which a training sample saw the block pushed: ``|rel_x| ≤ half_x``,
    ``|rel_y| ≤ half_y`` and ``|rel| ≤ radius``, each bound the largest
    seen. The box fits a rectangle's faces, the radius a round block's rim;
    their intersection holds both without knowing the shape. A sample counts
    as pushed when the block moved (a change above :data:`MOVED`) and did not
    slow down as a freely sliding block does (its change at least
    :data:`SLIDING` times the last message's), so the slide after a push
    does not widen the region.

    Outside the region the block slides freely: its change is
    ``decay ⊙ previous change``, ``decay`` fitted per output by least
    squares over the training samples outside the region (clipped to
    [0, 1]); a block at rest stays at rest.
    """

    half_x: float = -1.0
    half_y: float = -1.0
    radius: float = -1.0
    decay: tuple[float, float, float] = (0.0, 0.0, 0.0)
    pushed: int = 0
    """How many training samples saw the block pushed."""

    @classmethod
    def fit(cls, x: Array, y: Array) -> ContactGate:
        """The gate of one block's samples (inputs :func:`block_features`, outputs
        :func:`block_change`)."""
        before = np.linalg.norm(x[:, 4:6], axis=1)
        now = np.linalg.norm(y[:, :2], axis=1)
        turn_before, turn_now = np.abs(x[:, 6]), np.abs(y[:, 2])
        # Pushed: a translation or a turn that did not fade as a slide does.
        pushed = ((now > MOVED) & (now >= SLIDING * before)) | (
            (turn_now > MOVED) & (turn_now >= SLIDING * turn_before)
        )
        gate = cls(pushed=int(pushed.sum()))
        if pushed.any():
            rel = x[pushed, :2]
            gate.half_x = float(np.max(np.abs(rel[:, 0])))
            gate.half_y = float(np.max(np.abs(rel[:, 1])))
            gate.radius = float(np.max(np.hypot(rel[:, 0], rel[:, 1])))
        outside = ~gate.inside_all(x)
        previous, current = x[outside, 4:7], y[outside]
        denominator = np.sum(previous**2, axis=0)
        numerator = np.sum(previous * current, axis=0)
        decay = [
            float(np.clip(n / d, 0.0, 1.0)) if d > 0 else 0.0
            for n, d in zip(numerator, denominator, strict=True)
        ]
        gate.decay = (decay[0], decay[1], decay[2])
        return gate

    def inside(self, features: list[float]) -> bool:
        """Whether the actuator of ``features`` is in the contact region."""
        rx, ry = features[0], features[1]
        return (
            abs(rx) <= self.half_x
            and abs(ry) <= self.half_y
            and math.hypot(rx, ry) <= self.radius
        )

    def inside_all(self, x: Array) -> NDArray[np.bool_]:
        """:meth:`inside` for every row of ``x``."""
        return np.asarray(
            (np.abs(x[:, 0]) <= self.half_x)
            & (np.abs(x[:, 1]) <= self.half_y)
            & (np.hypot(x[:, 0], x[:, 1]) <= self.radius)
        )

    def snap(self, features: list[float]) -> list[float]:
        """``features`` with the actuator moved back onto the region's boundary,
        the contact surface, along its path: against its velocity in the
        block's frame, to where it would have met the surface (without a
        velocity, by the shortest way: the box's nearest face or the rim).

        A rigid block's pusher is never inside it; a chained prediction that
        lags the block by a little puts it there, and a regressor would read
        that as a position it never saw pushing (near the ends, where
        training saw the pusher slide past without moving the block) and
        stop the block. Training samples are snapped the same way. The
        shortest way would be wrong where the region is narrower than the
        block (after one push the box spans only the offsets pushed at): it
        would put the pusher on a side it never touched; the path does not.
        """
        rx, ry = features[0], features[1]
        snapped = list(features)
        vx, vy = features[2], features[3]
        speed = math.hypot(vx, vy)
        if speed > 0:
            dx, dy = -vx / speed, -vy / speed
            exits = [math.inf]
            for p, d, h in ((rx, dx, self.half_x), (ry, dy, self.half_y)):
                if d != 0:
                    exits.append((math.copysign(h, d) - p) / d)
            along = rx * dx + ry * dy
            beyond = rx * rx + ry * ry - self.radius * self.radius
            exits.append(-along + math.sqrt(max(along * along - beyond, 0.0)))
            t = max(min(exits), 0.0)
            snapped[0], snapped[1] = rx + t * dx, ry + t * dy
            return snapped
        to_x, to_y = self.half_x - abs(rx), self.half_y - abs(ry)
        r = math.hypot(rx, ry)
        to_rim = self.radius - r
        if min(to_x, to_y) <= to_rim:
            if to_x <= to_y:
                snapped[0] = math.copysign(self.half_x, rx)
            else:
                snapped[1] = math.copysign(self.half_y, ry)
        elif r > 0:
            snapped[0], snapped[1] = rx * self.radius / r, ry * self.radius / r
        return snapped

    def snap_all(self, x: Array) -> Array:
        """:meth:`snap` for every row of ``x`` (rows inside the region)."""
        return np.asarray([self.snap(list(row)) for row in x], dtype=np.float64)

    def slide(self, features: list[float]) -> list[float]:
        """The free slide's change: the last change, decayed."""
        return [d * f for d, f in zip(self.decay, features[4:7], strict=True)]


@dataclass
class CvChoice:
    """How a kNN's hyper-parameters were chosen, for inspection and the statistics."""

    k: int
    """The chosen number of neighbours."""
    weights: str
    """``"uniform"`` or ``"distance"``."""
    method: str
    """``"GroupKFold"`` (over runs), ``"KFold"`` (segments of one run) or ``"none"``."""
    groups: list[int] = field(default_factory=list)
    """The runs the samples came from, as the cross-validation grouped them."""
    splits: list[tuple[list[int], list[int]]] = field(default_factory=list)
    """The (training, validation) sample indices of every fold."""
    scores: dict[tuple[int, str], float] = field(default_factory=dict)
    """The validation error of every candidate."""


@dataclass
class _BlockSamples:
    inputs: list[list[float]] = field(default_factory=list)
    outputs: list[list[float]] = field(default_factory=list)
    runs: list[int] = field(default_factory=list)


_NO_ACTION: Action = (0.0, 0.0)

INPUT_GROUPS: dict[str, tuple[int, ...]] = {
    "position": (0, 1),
    "velocity": (2, 3),
    "motion": (4, 5, 6),
}
"""The groups of :data:`FEATURES` a regressor's inputs are chosen from."""

DEFAULT_INPUTS = "position,velocity"
"""The regressors' inputs unless ``--inputs`` says otherwise."""


def _parse_inputs(text: str) -> list[int]:
    groups = [g.strip() for g in text.split(",") if g.strip()]
    unknown = [g for g in groups if g not in INPUT_GROUPS]
    if unknown or not groups:
        raise ValueError(
            f"inputs must name some of {', '.join(INPUT_GROUPS)}, got {text!r}"
        )
    return sorted({i for g in groups for i in INPUT_GROUPS[g]})


class BaselineLearner(Learner):
    """What the baselines share: samples, the actuator's gains, the contact gate,
    lazy fitting, prediction.

    Subclasses implement :meth:`_fit_block` (a fitted predictor for one
    block's samples inside its contact region) and name themselves.
    """

    capabilities: ClassVar[frozenset[Capability]] = frozenset({Capability.FORWARD})
    version: ClassVar[str] = "0.2.0"

    def __init__(self, *, inputs: str = DEFAULT_INPUTS, verbose: bool = False) -> None:
        self.inputs = _parse_inputs(inputs)
        """The indices into :data:`FEATURES` the regressor sees (the gate sees all)."""
        self.seed = 0
        """The fold's seed (from :meth:`new_fold`)."""
        self.verbose = verbose
        """Whether every fit logs its choices (:meth:`describe_fit`) to stderr."""
        self._clear()

    def _clear(self) -> None:
        self.training = True
        self._stored: StateLike | None = None
        self._previous: StateLike | None = None
        self._last_action: Action = _NO_ACTION
        self._fresh = True
        self._run = -1
        self._samples: dict[int, _BlockSamples] = {}
        # a·dt, a_prev·dt, Δp of every training message (x and y)
        self._actuator_steps: list[tuple[float, float, float, float, float, float]] = []
        self._updates = 0
        self._training_runs: set[int] = set()
        self._dirty = False
        self._models: dict[int, Any] = {}
        self._gates: dict[int, ContactGate] = {}
        self._used: dict[int, int] = {}
        self._gains = (1.0, 0.0)

    # -- the protocol's calls --------------------------------------------------

    def new_fold(self, seed: int) -> None:
        """Forgets every sample and fit; ``seed`` seeds the fold's randomness."""
        self.seed = seed
        self._clear()

    def reset(self, state: StateLike) -> None:
        """Starts a run (a new cross-validation group) at ``state``, at rest."""
        self._stored = state
        self._previous = None
        self._last_action = _NO_ACTION
        self._fresh = True
        self._run += 1

    def update(self, state: StateLike, action: Action) -> None:
        """Records the transition from the stored state into ``state`` (training on)
        and moves the history (previous state and action) one message on."""
        previous = self._stored
        if previous is None:  # no reset before: treat as a new run
            self.reset(state)
            return
        # A test run restates its first state as an update from it: no time
        # passed, so the history must not start a message early (the
        # actuator's velocity and last action stay those of a resting run).
        if self._fresh and _same_poses(previous, state):
            self._stored = state
            return
        if self.training:
            self._record(self._previous, self._last_action, previous, state, action)
        self._previous, self._stored = previous, state
        self._last_action = action
        self._fresh = False

    def set_training(self, on: bool) -> None:
        """Turns training on or off (the fit happens at the next prediction with it off)."""
        self.training = on

    def predict(self, state: StateLike, action: Action) -> Prediction:
        """The state one message later (see the module documentation)."""
        if not self.training and self._dirty:
            self._fit()
        poses = state.poses()
        if state is self._stored or (
            self._stored is not None and _same_poses(state, self._stored)
        ):
            before = self._previous.poses() if self._previous is not None else {}
            last_action = self._last_action
        else:  # a state outside the run's history: no motion known
            before, last_action = {}, _NO_ACTION
        dt = 1.0 / self.publish_rate_hz
        out: dict[int, tuple[float, float, float]] = {}
        actuator = poses[ACTUATOR_ID]
        g, g_last = self._gains
        out[ACTUATOR_ID] = (
            actuator.x + (g * action[0] + g_last * last_action[0]) * dt,
            actuator.y + (g * action[1] + g_last * last_action[1]) * dt,
            actuator.theta,
        )
        for id_, block in poses.items():
            if id_ == ACTUATOR_ID:
                continue
            gate = self._gates.get(id_)
            if gate is None:
                out[id_] = block
                continue
            features = block_features(
                actuator,
                block,
                before.get(ACTUATOR_ID),
                before.get(id_),
                self.publish_rate_hz,
            )
            model = self._models.get(id_)
            if model is not None and gate.inside(features):
                snapped = gate.snap(features)
                change = model.predict_one([snapped[i] for i in self.inputs])
            else:
                change = gate.slide(features)
            out[id_] = apply_change(block, change)
        return Prediction(out)

    def stats(self) -> dict[str, Any]:
        """Sample counts as maps: ``actuator_steps`` and ``block/ID``.

        ``update_calls`` counts the training updates, ``inserts`` the samples
        recorded, ``nodes`` the samples the last fit's regressor used (those in
        the contact region). No extras or labels: the driver accepts those only
        in the built-in models' forms; the fit's choices are in
        :meth:`describe_fit` (logged with ``verbose``).
        """
        maps: dict[str, dict[str, int]] = {
            "actuator_steps": {
                "update_calls": self._updates,
                "inserts": len(self._actuator_steps),
                "nodes": len(self._actuator_steps),
            }
        }
        for id_, samples in sorted(self._samples.items()):
            maps[f"block/{id_}"] = {
                "update_calls": self._updates,
                "inserts": len(samples.inputs),
                "nodes": self._used.get(id_, 0),
            }
        return {"maps": maps}

    @property
    def actuator_gain(self) -> float:
        """The fitted gain of the action in force (1 before any fit)."""
        return self._gains[0]

    @property
    def actuator_gains(self) -> tuple[float, float]:
        """The fitted gains of the action in force and of the one before it."""
        return self._gains

    @property
    def gates(self) -> dict[int, ContactGate]:
        """The last fit's contact gate per block id."""
        return dict(self._gates)

    @property
    def training_runs(self) -> int:
        """How many runs (segments between resets) gave training samples this fold."""
        return len(self._training_runs)

    def describe_fit(self) -> list[str]:
        """The last fit's choices, one line per block (empty before any fit)."""
        return []

    def describe_gates(self) -> list[str]:
        """The last fit's contact gates, one line per block."""
        return [
            f"block {id_}: contact |x| ≤ {g.half_x:.4f}, |y| ≤ {g.half_y:.4f}, "
            f"|r| ≤ {g.radius:.4f} ({g.pushed} pushed samples), slide decay "
            + ", ".join(f"{d:.3f}" for d in g.decay)
            for id_, g in sorted(self._gates.items())
        ]

    # -- samples and fitting ---------------------------------------------------

    def _record(
        self,
        earlier: StateLike | None,
        last_action: Action,
        before: StateLike,
        after: StateLike,
        action: Action,
    ) -> None:
        old, new = before.poses(), after.poses()
        first = earlier.poses() if earlier is not None else {}
        self._updates += 1
        self._training_runs.add(self._run)
        a0, a1 = old[ACTUATOR_ID], new[ACTUATOR_ID]
        dt = 1.0 / self.publish_rate_hz
        self._actuator_steps.append(
            (
                action[0] * dt,
                action[1] * dt,
                last_action[0] * dt,
                last_action[1] * dt,
                a1.x - a0.x,
                a1.y - a0.y,
            )
        )
        for id_, block in old.items():
            if id_ == ACTUATOR_ID or id_ not in new:
                continue
            samples = self._samples.setdefault(id_, _BlockSamples())
            samples.inputs.append(
                block_features(
                    a0,
                    block,
                    first.get(ACTUATOR_ID),
                    first.get(id_),
                    self.publish_rate_hz,
                )
            )
            samples.outputs.append(block_change(block, new[id_]))
            samples.runs.append(self._run)
        self._dirty = True

    def _fit_actuator(self) -> None:
        steps = np.asarray(self._actuator_steps, dtype=np.float64).reshape(-1, 6)
        # Both axes share the gains: rows (a_x, a_prev_x) → Δx and (a_y, a_prev_y) → Δy.
        design = np.concatenate([steps[:, [0, 2]], steps[:, [1, 3]]])
        target = np.concatenate([steps[:, 4], steps[:, 5]])
        gram = design.T @ design
        if np.linalg.matrix_rank(gram) == 2:
            g, g_last = np.linalg.solve(gram, design.T @ target)
            self._gains = (float(g), float(g_last))
        elif float(gram[0, 0]) > 0:  # one action throughout: the gain alone
            self._gains = (float(design[:, 0] @ target / gram[0, 0]), 0.0)
        else:
            self._gains = (1.0, 0.0)

    def _fit(self) -> None:
        self._fit_actuator()
        self._models = {}
        self._gates = {}
        self._used = {}
        for id_, samples in sorted(self._samples.items()):
            x = np.asarray(samples.inputs, dtype=np.float64)
            y = np.asarray(samples.outputs, dtype=np.float64)
            runs = np.asarray(samples.runs, dtype=np.int64)
            gate = ContactGate.fit(x, y)
            self._gates[id_] = gate
            inside = gate.inside_all(x)
            if inside.any():
                self._models[id_], self._used[id_] = self._fit_block(
                    id_,
                    gate.snap_all(x[inside])[:, self.inputs],
                    y[inside],
                    runs[inside],
                )
            else:
                self._used[id_] = 0
        self._dirty = False
        if self.verbose:
            g, g_last = self._gains
            lines = [
                f"actuator gains {g:.6f} (action), {g_last:.6f} (last action)",
                *self.describe_gates(),
                *self.describe_fit(),
            ]
            for line in lines:
                sys.stderr.write(f"{self.display_name} (seed {self.seed}): {line}\n")
            sys.stderr.flush()

    def _fit_block(
        self, block_id: int, x: Array, y: Array, runs: NDArray[np.int64]
    ) -> tuple[Any, int]:
        """A fitted predictor (``predict_one(features) -> change``) of one block's
        samples in its contact region, and the number of samples it used."""
        raise NotImplementedError


def _same_poses(a: StateLike, b: StateLike) -> bool:
    return a is b or a.poses() == b.poses()


def _verbose_option(parser: ArgumentParser) -> None:
    parser.add_argument(
        "--inputs",
        default=DEFAULT_INPUTS,
        help="the feature groups the regressor sees, comma-separated, of "
        f"{', '.join(INPUT_GROUPS)} (default {DEFAULT_INPUTS}; the contact gate "
        "always sees all)",
    )
    parser.add_argument(
        "--verbose", action="store_true", help="log every fit's choices to stderr"
    )


def _scaler(x: Array) -> Any:
    from sklearn.preprocessing import StandardScaler

    return StandardScaler().fit(x)


class _KnnPredictor:
    """A fitted kNN of one block, queried without scikit-learn's per-call checks:
    the scaler's mean and scale and a scipy ``cKDTree`` over the standardised
    samples. It computes what ``make_pipeline(StandardScaler(),
    KNeighborsRegressor(k, weights)).predict`` does, in the same order."""

    def __init__(self, x: Array, y: Array, k: int, weights: str) -> None:
        from scipy.spatial import cKDTree

        scaler = _scaler(x)
        self._mean: Array = scaler.mean_
        self._scale: Array = scaler.scale_
        self._tree = cKDTree(scaler.transform(x))
        self._y = y
        self._y_by_output = np.ascontiguousarray(y.T)
        self._k = min(k, len(x))
        self._distance = weights == "distance"

    def predict_one(self, features: list[float]) -> Array:
        z = (np.asarray(features, dtype=np.float64) - self._mean) / self._scale
        dist, index = self._tree.query(z, k=self._k)
        dist, index = np.atleast_1d(dist), np.atleast_1d(index)
        if not self._distance:
            return np.asarray(self._y[index].mean(axis=0))
        with np.errstate(divide="ignore"):
            w = 1.0 / dist
        exact = np.isinf(w)
        if exact.any():  # exact matches take all the weight, as sklearn does
            w = exact.astype(np.float64)
        return np.asarray((self._y_by_output[:, index] * w).sum(axis=1) / w.sum())


def _neighbour_means(
    y_train: Array, index: NDArray[np.int64], dist: Array, k: int, weights: str
) -> Array:
    """What ``KNeighborsRegressor`` predicts from precomputed neighbours (same weighting)."""
    neighbours = y_train[index[:, :k]]  # (m, k, outputs)
    if weights == "uniform":
        return np.asarray(neighbours.mean(axis=1))
    with np.errstate(divide="ignore"):
        w = 1.0 / dist[:, :k]
    inf_mask = np.isinf(w)
    inf_rows = np.any(inf_mask, axis=1)
    w[inf_rows] = inf_mask[
        inf_rows
    ]  # exact matches take all the weight, as sklearn does
    return np.asarray(np.einsum("mk,mko->mo", w, neighbours) / w.sum(axis=1)[:, None])


class KnnLearner(BaselineLearner):
    """k-nearest-neighbour regression of each block's change (what scikit-learn's
    ``KNeighborsRegressor`` predicts, queried in a scipy ``cKDTree``); ``k`` and the weighting chosen by cross-validation
    over the training runs (module documentation)."""

    name: ClassVar[str] = "knn"

    def __init__(
        self, max_k: int = 50, *, inputs: str = DEFAULT_INPUTS, verbose: bool = False
    ) -> None:
        if max_k < 1:
            raise ValueError(f"max_k must be at least 1, got {max_k}")
        self.max_k = max_k
        """The largest ``k`` tried."""
        self.choices: dict[int, CvChoice] = {}
        """The last fit's cross-validation per block id."""
        super().__init__(inputs=inputs, verbose=verbose)

    @classmethod
    def from_args(cls, argv: list[str]) -> KnnLearner:
        """``[--max-k K] [--verbose]``."""
        parser = ArgumentParser(prog="knn", description="k-nearest-neighbour baseline")
        parser.add_argument(
            "--max-k", type=int, default=50, help="largest k tried (default 50)"
        )
        _verbose_option(parser)
        args = parser.parse_args(argv)
        try:
            return cls(max_k=args.max_k, inputs=args.inputs, verbose=args.verbose)
        except ValueError as err:
            raise UsageError(f"knn: {err}") from None

    def _clear(self) -> None:
        super()._clear()
        self.choices = {}

    def choose(self, x: Array, y: Array, runs: NDArray[np.int64]) -> CvChoice:
        """Cross-validates ``k`` and the weighting on standardised inputs ``x``."""
        from sklearn.model_selection import GroupKFold, KFold
        from sklearn.neighbors import NearestNeighbors

        n = len(x)
        groups = [int(r) for r in runs]
        if n < 2:
            return CvChoice(k=1, weights="uniform", method="none", groups=groups)
        distinct = len(set(groups))
        if distinct >= 2:
            method = "GroupKFold"
            splits = list(
                GroupKFold(n_splits=min(5, distinct)).split(x, y, groups=runs)
            )
        else:
            method = "KFold"
            splits = list(KFold(n_splits=min(5, n), shuffle=False).split(x, y))
        k_max = max(1, min(self.max_k, min(len(train) for train, _ in splits)))
        scale = y.std(axis=0)
        scale[scale < _EPS_STD] = 1.0
        errors: dict[tuple[int, str], float] = {
            (k, w): 0.0 for k in range(1, k_max + 1) for w in ("uniform", "distance")
        }
        for train, val in splits:
            nn = NearestNeighbors(n_neighbors=k_max).fit(x[train])
            dist, index = nn.kneighbors(x[val])
            for k, weights in errors:
                predicted = _neighbour_means(y[train], index, dist, k, weights)
                errors[(k, weights)] += float(
                    np.sum(((predicted - y[val]) / scale) ** 2)
                )
        scores = {key: total / (n * y.shape[1]) for key, total in errors.items()}
        order = {"uniform": 0, "distance": 1}
        (k, weights) = min(scores, key=lambda key: (scores[key], key[0], order[key[1]]))
        return CvChoice(
            k=k,
            weights=weights,
            method=method,
            groups=groups,
            splits=[([int(i) for i in t], [int(i) for i in v]) for t, v in splits],
            scores=scores,
        )

    def _fit_block(
        self, block_id: int, x: Array, y: Array, runs: NDArray[np.int64]
    ) -> tuple[Any, int]:
        choice = self.choose(_scaler(x).transform(x), y, runs)
        self.choices[block_id] = choice
        return _KnnPredictor(x, y, choice.k, choice.weights), len(x)

    def describe_fit(self) -> list[str]:
        """``block ID: k=… weights=… (method, folds, runs)`` per block of the last fit."""
        return [
            f"block {id_}: k={c.k} weights={c.weights} ({c.method}, {len(c.splits)} folds, "
            f"{len(set(c.groups))} runs, {len(c.groups)} samples)"
            for id_, c in sorted(self.choices.items())
        ]


def _cv_splits(
    n: int, runs: NDArray[np.int64]
) -> tuple[str, list[tuple[NDArray[np.int64], NDArray[np.int64]]]]:
    """The cross-validation of ``n`` samples from ``runs``: ``GroupKFold`` over
    the runs (``min(5, runs)`` folds), or with a single run contiguous
    segments of it (``KFold`` without shuffling, ``min(5, n)`` folds)."""
    from sklearn.model_selection import GroupKFold, KFold

    placeholder = np.zeros((n, 1))
    distinct = len({int(r) for r in runs})
    if distinct >= 2:
        folds = GroupKFold(n_splits=min(5, distinct))
        return "GroupKFold", list(folds.split(placeholder, groups=runs))
    return "KFold", list(KFold(n_splits=min(5, n), shuffle=False).split(placeholder))


GP_STRETCHES = (1.0, 2.0, 4.0, 8.0)
"""The factors on the GP's fitted length scales that cross-validation tries."""

_GP_JITTER = 1e-10
"""Added to the kernel matrix's diagonal: ``GaussianProcessRegressor``'s ``alpha``."""


def _gp_theta0(inputs: int) -> Array:
    """The kernel's initial hyper-parameters (amplitude, one length scale per
    input, noise), as logs."""
    return np.log([1.0] + [1.0] * inputs + [1e-2])


def _gp_bounds(inputs: int) -> Array:
    """Their bounds, as logs."""
    return np.log([(1e-3, 1e3)] + [(1e-2, 1e3)] * inputs + [(1e-10, 1e1)])


_GP_THETA0 = _gp_theta0(len(_parse_inputs(DEFAULT_INPUTS)))
"""The initial hyper-parameters for the default inputs."""


def _gp_neg_log_likelihood(
    theta: Array, sqdiff: Array, y: Array
) -> tuple[float, Array]:
    """Minus the log marginal likelihood of ``C · RBF(ℓ) + White`` (summed over
    the columns of ``y``) and its gradient, with respect to the logs ``theta``
    of ``(C, ℓ₁ … ℓ_d, noise)``; ``sqdiff[d]`` holds the inputs' squared
    differences along input ``d``.

    What scikit-learn's ``GaussianProcessRegressor.log_marginal_likelihood``
    computes, at a third of its cost: the trace term of the gradient,
    ``½ tr((ααᵀ − K⁻¹) ∂K)``, takes ``K⁻¹`` from the Cholesky factor by LAPACK's
    ``potri`` instead of solving for an identity matrix, and sums over the
    outputs before, not after, multiplying by each ``∂K``.
    """
    from scipy.linalg.lapack import dpotrf, dpotri, dpotrs

    amplitude, noise = math.exp(theta[0]), math.exp(theta[-1])
    inv_sq_scales = np.exp(-2.0 * theta[1:-1])
    n, outputs = y.shape
    rbf = amplitude * np.exp(-0.5 * np.tensordot(inv_sq_scales, sqdiff, axes=1))
    k = rbf.copy()
    k[np.diag_indices(n)] += noise + _GP_JITTER
    factor, info = dpotrf(k, lower=1, clean=1, overwrite_a=1)
    if info != 0:  # not positive definite: as sklearn, the worst likelihood
        return math.inf, np.zeros_like(theta)
    alpha, _ = dpotrs(factor, y, lower=1)
    log_likelihood = (
        -0.5 * float(np.sum(y * alpha))
        - outputs * float(np.sum(np.log(np.diag(factor))))
        - outputs * n / 2 * math.log(2 * math.pi)
    )
    k_inv, _ = dpotri(factor, lower=1, overwrite_c=1)
    k_inv = np.tril(k_inv) + np.tril(k_inv, -1).T
    w = alpha @ alpha.T - outputs * k_inv  # Σ over outputs of ααᵀ − K⁻¹
    w_rbf = w * rbf
    gradient = np.empty_like(theta)
    gradient[0] = 0.5 * float(np.sum(w_rbf))
    gradient[1:-1] = 0.5 * inv_sq_scales * np.tensordot(sqdiff, w_rbf, axes=2)
    gradient[-1] = 0.5 * noise * float(np.trace(w))
    return -log_likelihood, -gradient


def _squared_differences(x: Array) -> Array:
    """``[d, i, j] = (x[i, d] − x[j, d])²``: what every likelihood evaluation reuses."""
    return np.stack([(col[:, None] - col[None, :]) ** 2 for col in x.T])


class _GpPredictor:
    """A GP of one block, fitted as ``make_pipeline(StandardScaler(),
    GaussianProcessRegressor(C · RBF(ℓ) + White, normalize_y=True))`` fits
    (same likelihood, optimiser, start and bounds), and predicting its
    posterior mean ``k(x*, X) @ α`` as that pipeline does, without its
    per-call checks."""

    def __init__(
        self, x: Array, y: Array, runs: NDArray[np.int64] | None = None
    ) -> None:
        import scipy.optimize
        from scipy.linalg import cho_solve, cholesky
        from scipy.spatial.distance import pdist, squareform

        scaler = _scaler(x)
        self._mean: Array = scaler.mean_
        self._scale: Array = scaler.scale_
        xs = scaler.transform(x)
        self._y_mean: Array = np.mean(y, axis=0)
        y_std = np.std(y, axis=0)
        y_std[y_std < 10 * np.finfo(np.float64).eps] = 1.0  # sklearn's constant outputs
        self._y_std: Array = y_std
        yn = (y - self._y_mean) / self._y_std
        sqdiff = _squared_differences(xs)
        result = scipy.optimize.minimize(
            _gp_neg_log_likelihood,
            _gp_theta0(xs.shape[1]),
            args=(sqdiff, yn),
            method="L-BFGS-B",
            jac=True,
            bounds=_gp_bounds(xs.shape[1]),
        )
        theta = result.x
        self.evaluations = int(result.nfev)
        """How many likelihood evaluations the optimiser made."""
        self.amplitude = float(np.exp(theta[0]))
        self.length_scales: Array = np.exp(theta[1:-1])
        self.noise = float(np.exp(theta[-1]))
        self.stretch = 1.0
        """The factor on every length scale that cross-validation chose (1: none)."""
        self.stretch_scores: dict[float, float] = {}
        """The validation error of every stretch tried."""
        # Only between runs: one run has no offsets between runs to stretch
        # over, and its contiguous segments (the kNN's stand-in) validate a
        # push on the rest of the same push.
        if runs is not None and len({int(r) for r in runs}) >= 2:
            self._choose_stretch(xs, yn, runs)
            self.length_scales = self.length_scales * self.stretch
        # The weights as sklearn computes them after its optimisation: the
        # kernel matrix from pdist, its Cholesky factor, the solve.
        self._train = xs / self.length_scales
        k = squareform(np.exp(-0.5 * pdist(self._train, metric="sqeuclidean")))
        np.fill_diagonal(k, 1)
        k = self.amplitude * k + self.noise * np.eye(len(xs))
        k[np.diag_indices_from(k)] += _GP_JITTER
        self._alpha: Array = cho_solve(
            (cholesky(k, lower=True, check_finite=False), True),
            yn,
            check_finite=False,
        )

    def _choose_stretch(self, xs: Array, yn: Array, runs: NDArray[np.int64]) -> None:
        """Chooses :data:`GP_STRETCHES` by cross-validation over the training runs.

        The marginal likelihood treats every sample as independent, but a
        run's samples are a dense, smooth trajectory: the likelihood is
        maximised by length scales short enough to follow one run, and
        between the runs (the offsets a test push falls between) the
        posterior then reverts to the mean change, an unturned push. Held-out
        runs measure what a test push needs, so the kernel's length scales
        are stretched by the factor that predicts them best (amplitude and
        noise kept; ties to the smaller).
        """
        from scipy.linalg import cho_solve, cholesky
        from scipy.spatial.distance import cdist

        _, splits = _cv_splits(len(xs), runs)
        scaled = xs / self.length_scales
        sq = cdist(scaled, scaled, "sqeuclidean")
        n, outputs = yn.shape
        for stretch in GP_STRETCHES:
            k_all = self.amplitude * np.exp(-0.5 * sq / stretch**2)
            total = 0.0
            for train, val in splits:
                k = k_all[np.ix_(train, train)].copy()
                k[np.diag_indices_from(k)] += self.noise + _GP_JITTER
                try:
                    factor = cholesky(k, lower=True, check_finite=False)
                except np.linalg.LinAlgError:
                    total = math.inf
                    break
                alpha = cho_solve((factor, True), yn[train], check_finite=False)
                predicted = k_all[np.ix_(val, train)] @ alpha
                total += float(np.sum((predicted - yn[val]) ** 2))
            self.stretch_scores[stretch] = total / (n * outputs)
        self.stretch = min(
            self.stretch_scores, key=lambda f: (self.stretch_scores[f], f)
        )

    def predict_one(self, features: list[float]) -> Array:
        from scipy.spatial.distance import cdist

        z = (np.asarray(features, dtype=np.float64) - self._mean) / self._scale
        k = self.amplitude * np.exp(
            -0.5 * cdist((z / self.length_scales)[None, :], self._train, "sqeuclidean")
        )
        return np.asarray(self._y_std * (k @ self._alpha)[0] + self._y_mean)

    @property
    def theta(self) -> Array:
        """The fitted hyper-parameters as scikit-learn's kernel holds them (logs)."""
        return np.log([self.amplitude, *self.length_scales, self.noise])

    def kernel_text(self) -> str:
        """The fitted kernel as scikit-learn prints it."""
        scales = ", ".join(f"{v:.3g}" for v in self.length_scales)
        return (
            f"{math.sqrt(self.amplitude):.3g}**2 * RBF(length_scale=[{scales}]) "
            f"+ WhiteKernel(noise_level={self.noise:.3g})"
        )


class GpLearner(BaselineLearner):
    """Gaussian-process regression of each block's change (the model of
    scikit-learn's ``GaussianProcessRegressor``, ``C · RBF(ARD) + White``,
    hyper-parameters by marginal likelihood, computed with scipy) on at most
    ``max_samples`` seeded-subsampled samples."""

    name: ClassVar[str] = "gp"

    def __init__(
        self,
        max_samples: int = 600,
        *,
        inputs: str = DEFAULT_INPUTS,
        verbose: bool = False,
    ) -> None:
        if max_samples < 1:
            raise ValueError(f"max_samples must be at least 1, got {max_samples}")
        self.max_samples = max_samples
        """The cap on samples per block and fit (the fit is O(n³))."""
        self.kernels: dict[int, str] = {}
        """The last fit's optimised kernel per block id."""
        self.subsamples: dict[int, list[int]] = {}
        """The sample indices the last fit used per block id."""
        super().__init__(inputs=inputs, verbose=verbose)

    @classmethod
    def from_args(cls, argv: list[str]) -> GpLearner:
        """``[--max-samples N] [--verbose]``."""
        parser = ArgumentParser(prog="gp", description="Gaussian-process baseline")
        parser.add_argument(
            "--max-samples",
            type=int,
            default=600,
            help="samples per block a fit uses at most (default 600; the fit is O(n³))",
        )
        _verbose_option(parser)
        args = parser.parse_args(argv)
        try:
            return cls(
                max_samples=args.max_samples, inputs=args.inputs, verbose=args.verbose
            )
        except ValueError as err:
            raise UsageError(f"gp: {err}") from None

    def _clear(self) -> None:
        super()._clear()
        self.kernels = {}
        self.subsamples = {}

    def subsample(self, block_id: int, n: int) -> NDArray[np.int64]:
        """The sorted indices of the samples a fit on ``n`` samples uses (seeded)."""
        if n <= self.max_samples:
            return np.arange(n, dtype=np.int64)
        rng = np.random.default_rng([self.seed, block_id])
        return np.sort(rng.choice(n, size=self.max_samples, replace=False)).astype(
            np.int64
        )

    def _fit_block(
        self, block_id: int, x: Array, y: Array, runs: NDArray[np.int64]
    ) -> tuple[Any, int]:
        chosen = self.subsample(block_id, len(x))
        self.subsamples[block_id] = [int(i) for i in chosen]
        model = _GpPredictor(x[chosen], y[chosen], runs[chosen])
        self.kernels[block_id] = (
            f"{model.kernel_text()}, length scales stretched ×{model.stretch:g}"
        )
        return model, len(chosen)

    def describe_fit(self) -> list[str]:
        """``block ID: N samples, kernel …`` per block of the last fit."""
        return [
            f"block {id_}: {len(self.subsamples.get(id_, []))} samples, kernel {kernel}"
            for id_, kernel in sorted(self.kernels.items())
        ]


def _member_seed(seed: int, block_id: int, member: int) -> int:
    """A member's ``random_state``: the fold's seed, the block and the member mixed."""
    state = np.random.SeedSequence([seed, block_id, member]).generate_state(1)
    return int(state[0])


class _Ensemble:
    """An ensemble of small MLPs (scikit-learn's ``MLPRegressor``) of one block,
    trained by ``partial_fit`` only; inputs and outputs standardised with the
    statistics of the block's memory at the time of each training call. Its
    prediction is the members' mean, computed here by their weights (ReLU
    hidden layers, a linear output), as ``MLPRegressor.predict`` does."""

    def __init__(
        self,
        seed: int,
        block_id: int,
        members: int,
        hidden: tuple[int, ...],
        learning_rate: float,
    ) -> None:
        from sklearn.neural_network import MLPRegressor

        self.members = [
            MLPRegressor(
                hidden_layer_sizes=hidden,
                activation="relu",
                solver="adam",
                learning_rate_init=learning_rate,
                alpha=1e-4,
                batch_size=32,
                shuffle=True,
                random_state=_member_seed(seed, block_id, m),
            )
            for m in range(members)
        ]
        self.calls = 0
        """How many ``partial_fit`` calls each member has had."""
        self._x_mean: Array = np.zeros(0)
        self._x_scale: Array = np.ones(0)
        self._y_mean: Array = np.zeros(3)
        self._y_scale: Array = np.ones(3)
        self._y_constant: NDArray[np.bool_] = np.zeros(3, dtype=bool)
        self._y_low: Array = np.full(3, -np.inf)
        self._y_high: Array = np.full(3, np.inf)

    def scale_by(self, x: Array, y: Array) -> None:
        """Standardises with the statistics of ``x`` and ``y`` from now on."""
        self._x_mean, self._x_scale = _mean_scale(x)
        self._y_mean, self._y_scale = _mean_scale(y)
        self._y_constant = y.std(axis=0) < _EPS_STD
        self._y_low, self._y_high = y.min(axis=0), y.max(axis=0)

    def partial_fit(self, x: Array, y: Array) -> None:
        """One pass of every member over ``(x, y)`` (raw features and changes)."""
        import warnings

        xs = (x - self._x_mean) / self._x_scale
        ys = (y - self._y_mean) / self._y_scale
        with warnings.catch_warnings():
            # A call with fewer samples than a minibatch is one minibatch.
            warnings.filterwarnings("ignore", message="Got `batch_size`")
            for member in self.members:
                member.partial_fit(xs, ys)
        self.calls += 1

    def predict_one(self, features: list[float]) -> Array:
        z = (np.asarray(features, dtype=np.float64) - self._x_mean) / self._x_scale
        total = np.zeros(3)
        for member in self.members:
            a = z
            last = len(member.coefs_) - 1
            for layer, (w, b) in enumerate(
                zip(member.coefs_, member.intercepts_, strict=True)
            ):
                a = a @ w + b
                if layer < last:
                    a = np.maximum(a, 0.0)
            total += a
        out = total / len(self.members) * self._y_scale + self._y_mean
        # A network extrapolates without bound where it saw nothing (after one
        # run, most of the contact region), and a chain compounds it: the
        # change is kept within those it was trained on. An output that never
        # varied is that constant, not a network's noise.
        out = np.clip(out, self._y_low, self._y_high)
        return np.where(self._y_constant, self._y_mean, out)


def _mean_scale(x: Array) -> tuple[Array, Array]:
    """``StandardScaler``'s mean and scale: a constant column is left unscaled."""
    mean = x.mean(axis=0)
    scale = x.std(axis=0)
    scale[scale < _EPS_STD] = 1.0
    return mean, scale


class MlpLearner(BaselineLearner):
    """An ensemble of small MLPs per block (scikit-learn's ``MLPRegressor``),
    trained online by ``partial_fit`` on every batch of new samples as they
    arrive, then for a few epochs over the memory when training ends; the
    members' mean is the prediction (module documentation)."""

    name: ClassVar[str] = "mlp"

    def __init__(
        self,
        members: int = 5,
        hidden: tuple[int, ...] = (64, 64),
        batch: int = 64,
        epochs: int = 30,
        learning_rate: float = 1e-3,
        *,
        inputs: str = DEFAULT_INPUTS,
        verbose: bool = False,
    ) -> None:
        if members < 1:
            raise ValueError(f"members must be at least 1, got {members}")
        if not hidden or min(hidden) < 1:
            raise ValueError(f"hidden layers need at least one unit each, got {hidden}")
        if batch < 1:
            raise ValueError(f"batch must be at least 1, got {batch}")
        if epochs < 0:
            raise ValueError(f"epochs must not be negative, got {epochs}")
        if not learning_rate > 0:
            raise ValueError(f"learning rate must be positive, got {learning_rate}")
        self.members = members
        """Networks per block."""
        self.hidden = tuple(hidden)
        """Units of each hidden layer."""
        self.batch = batch
        """New samples (of every block) between two online training calls."""
        self.epochs = epochs
        """Passes over the memory when training ends."""
        self.learning_rate = learning_rate
        """Adam's step size."""
        self.ensembles: dict[int, _Ensemble] = {}
        """Each block's ensemble."""
        super().__init__(inputs=inputs, verbose=verbose)

    @classmethod
    def from_args(cls, argv: list[str]) -> MlpLearner:
        """``[--members N] [--hidden N,N] [--batch N] [--epochs N]
        [--learning-rate X] [--inputs …] [--verbose]``."""
        parser = ArgumentParser(
            prog="mlp",
            description="online ensemble-of-MLPs baseline (scikit-learn's "
            "MLPRegressor.partial_fit on each batch of new samples during "
            "training, a few epochs over the memory when it ends; the members' "
            "mean is the prediction; seeded from the fold's seed)",
        )
        parser.add_argument(
            "--members", type=int, default=5, help="networks per block (default 5)"
        )
        parser.add_argument(
            "--hidden",
            default="64,64",
            help="units per hidden layer, comma-separated (default 64,64)",
        )
        parser.add_argument(
            "--batch",
            type=int,
            default=64,
            help="new samples between two online training calls (default 64)",
        )
        parser.add_argument(
            "--epochs",
            type=int,
            default=30,
            help="passes over the memory when training ends (default 30)",
        )
        parser.add_argument(
            "--learning-rate",
            type=float,
            default=1e-3,
            help="Adam's step size (default 0.001)",
        )
        _verbose_option(parser)
        args = parser.parse_args(argv)
        try:
            hidden = tuple(int(v) for v in args.hidden.split(","))
            return cls(
                members=args.members,
                hidden=hidden,
                batch=args.batch,
                epochs=args.epochs,
                learning_rate=args.learning_rate,
                inputs=args.inputs,
                verbose=args.verbose,
            )
        except ValueError as err:
            raise UsageError(f"mlp: {err}") from None

    def _clear(self) -> None:
        super()._clear()
        self.ensembles = {}
        self._pending = 0

    def _ensemble(self, block_id: int) -> _Ensemble:
        if block_id not in self.ensembles:
            self.ensembles[block_id] = _Ensemble(
                self.seed, block_id, self.members, self.hidden, self.learning_rate
            )
        return self.ensembles[block_id]

    def _record(
        self,
        earlier: StateLike | None,
        last_action: Action,
        before: StateLike,
        after: StateLike,
        action: Action,
    ) -> None:
        super()._record(earlier, last_action, before, after, action)
        self._pending += 1
        if self._pending >= self.batch:
            self._train_online(self._pending)
            self._pending = 0

    def _train_online(self, new: int) -> None:
        """One training call of every block's ensemble on its last ``new`` samples
        in the contact region as the samples so far draw it; the ensemble then
        predicts (behind that gate) until the next call or the final fit."""
        for id_, samples in sorted(self._samples.items()):
            x = np.asarray(samples.inputs, dtype=np.float64)
            y = np.asarray(samples.outputs, dtype=np.float64)
            gate = ContactGate.fit(x, y)
            inside = gate.inside_all(x)
            if not inside.any():
                continue
            recent = inside.copy()
            recent[: max(0, len(x) - new)] = False
            if not recent.any():
                continue
            xs = gate.snap_all(x[inside])[:, self.inputs]
            ensemble = self._ensemble(id_)
            ensemble.scale_by(xs, y[inside])
            ensemble.partial_fit(gate.snap_all(x[recent])[:, self.inputs], y[recent])
            self._gates[id_] = gate
            self._models[id_] = ensemble
            self._used[id_] = int(inside.sum())

    def _fit_block(
        self, block_id: int, x: Array, y: Array, runs: NDArray[np.int64]
    ) -> tuple[Any, int]:
        ensemble = self._ensemble(block_id)
        ensemble.scale_by(x, y)
        for _ in range(self.epochs):
            ensemble.partial_fit(x, y)
        return ensemble, len(x)

    def _fit(self) -> None:
        self._pending = 0
        super()._fit()

    def describe_fit(self) -> list[str]:
        """``block ID: M members, hidden …, C training calls`` per block."""
        return [
            f"block {id_}: {len(e.members)} members, hidden {self.hidden}, "
            f"{e.calls} training calls"
            for id_, e in sorted(self.ensembles.items())
        ]


BASELINES: dict[str, type[BaselineLearner]] = {
    "knn": KnnLearner,
    "gp": GpLearner,
    "mlp": MlpLearner,
}
"""The baselines by the name ``python -m pushlearn.baselines`` takes.

The results page runs the same list (``BASELINES`` in
``crates/lab/src/reproduce/manifest.rs``, a Rust test keeps the two equal):
a new baseline is a class here and an entry in both.
"""


def main(argv: list[str] | None = None) -> int:
    """``python -m pushlearn.baselines knn|gp|mlp [--listen HOST:PORT] [OPTIONS]``."""
    from .serve import main as serve_main

    args = list(sys.argv[1:] if argv is None else argv)
    names = list(BASELINES)
    usage = f"usage: python -m pushlearn.baselines {'|'.join(names)} [--listen HOST:PORT] [OPTIONS]"
    if not args or args[0] in ("-h", "--help"):
        print(usage + "\n\n" + (__doc__ or "").split("\n\n", 1)[0])
        return 0 if args else 2
    if args[0] in BASELINES and any(a in ("-h", "--help") for a in args[1:]):
        # The learner's own options, not the server's (which `--help` alone shows).
        print(f"{usage}\n\n{args[0]}: {BASELINES[args[0]].__doc__ or ''}\n")
        try:
            BASELINES[args[0]].from_args(["--help"])
        except SystemExit as done:
            return int(done.code or 0)
        return 0
    if args[0] not in BASELINES:
        print(
            f"pushlearn.baselines: unknown baseline {args[0]!r} "
            f"(choose {', '.join(names[:-1])} or {names[-1]})\n{usage}",
            file=sys.stderr,
        )
        return 2
    return serve_main([f"pushlearn.baselines:{BASELINES[args[0]].__name__}", *args[1:]])


if __name__ == "__main__":
    raise SystemExit(main())
