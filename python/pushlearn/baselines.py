"""Baseline forward models as learners: k-nearest neighbours and a Gaussian process.

Two standard regressors from scikit-learn, :class:`KnnLearner`
(``KNeighborsRegressor``) and :class:`GpLearner`
(``GaussianProcessRegressor``), learning the same per-message transition
features, so that the push task's learning curve of the memory-based models
can be compared with off-the-shelf regression. Capability ``FORWARD`` only.
Serve them with ``python -m pushlearn.baselines knn`` or ``… gp`` (options:
``--help``).

Features (one sample per block and message)
-------------------------------------------
For a transition from state ``s`` into state ``s'`` under the action
``a = (vx, vy)`` in force meanwhile, and each block ``b`` (id) present in
both, with ``R(φ)`` the rotation by φ:

* **input** (4 numbers): the actuator's position relative to the block in
  the block's frame, ``R(−θ_b) · (p_actuator − p_b)``, and the action in the
  block's frame, ``R(−θ_b) · a``; all taken in ``s``;
* **output** (3 numbers): the block's change over the message, in the
  block's frame of ``s``: ``R(−θ_b) · (p'_b − p_b)`` and
  ``Δθ = θ'_b − θ_b`` wrapped to (−π, π].

A prediction applies the predicted change: ``p'_b = p_b + R(θ_b) · Δp``,
``θ'_b = θ_b + Δθ`` (wrapped). One regressor per block id (the blocks'
shapes differ), fitted on that block's samples; a block without samples
stays where it is.

**The actuator** is velocity-controlled by the world, so its change is
learned as a function of the action alone, by the simplest model that
generalises to every direction: a scalar gain ``g`` with
``Δp_actuator = g · a / publish_rate_hz``, fitted by least squares over all
training transitions (``g = Σ⟨Δp, u⟩ / Σ⟨u, u⟩``, ``u = a / rate``); it absorbs
the average loss of the first message of a Move (latency). The actuator's
yaw is kept.

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
training is on, predictions use the last fit; before any fit, the prior:
nothing moves but the actuator, by ``a / publish_rate_hz``. (The push task
predicts at every training message for display only, so refitting there
would only cost time; the constant-feedback experiment, which never turns
training off, therefore sees only the prior: these baselines are meant for
the push tasks.)

Inputs are standardised with the training samples' mean and standard
deviation (scikit-learn's ``StandardScaler``; a constant input is left
unscaled). Hyper-parameters are chosen on the training samples only, never
on test positions:

* **kNN**: ``k`` in 1 … ``max_k`` (default 50, at most the smallest training
  fold) and ``weights`` ``"uniform"`` or ``"distance"`` by cross-validation,
  minimising the mean squared error of the outputs scaled by their training
  standard deviation. The folds are :class:`~sklearn.model_selection.GroupKFold`
  over the training runs (``min(5, runs)`` folds), so no run is both trained
  on and validated on. With a single run, contiguous segments of it
  (``KFold`` without shuffling, ``min(5, n)`` folds) stand in for runs; with a
  single sample, ``k = 1``. Ties go to the smaller ``k``, then ``uniform``.
* **GP**: kernel ``C · RBF(ℓ₁ … ℓ₄) + White`` (an anisotropic RBF with one
  length scale per input, an amplitude and a noise level), outputs
  normalised (``normalize_y``), one GP per block for its three outputs
  (shared kernel), hyper-parameters by maximising the log marginal
  likelihood on the training samples with scikit-learn's default optimiser
  (L-BFGS-B) from the kernel's initial values, ``n_restarts_optimizer=0``.
  Exact GP fitting costs O(n³) time and O(n²) memory, and every prediction
  O(n), so a GP is fitted on at most ``max_samples`` (default 600) of a
  block's samples, chosen by a seeded subsample without replacement
  (seed: the fold's seed from ``new_fold``, and the block id). 600 samples
  are about four training runs. Each evaluation of the marginal likelihood
  and its gradient factorises the n × n kernel matrix, and the optimiser
  needs a hundred or more of them: at n = 600 one evaluation took
  0.1–0.2 s on a loaded two-core machine, a fit 10–30 s; the 4470 samples of
  30 training runs would cost (4470 / 600)³ ≈ 400 times as much per
  evaluation, hours per fit.

Because of this, a GP fit can take longer than the experiment driver's
default ``--learner-timeout`` (30 s) for one answer: run the GP with, e.g.,
``pushlearn experiment push-task --learner-timeout 300 --learner "python -m
pushlearn.baselines gp"``, or lower ``--max-samples``.

Statistics and logs
-------------------
``stats()`` reports the samples as maps, ``actuator_steps`` and
``block/ID`` (``inserts``: samples recorded, ``nodes``: samples the last fit
used). The chosen hyper-parameters are in :meth:`BaselineLearner.describe_fit`
and, with ``--verbose``, logged to stderr at every fit.

Everything is deterministic given the fold seed.
"""

from __future__ import annotations

import math
import sys
import warnings
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
    "CvChoice",
    "GpLearner",
    "KnnLearner",
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


def block_features(actuator: Pose, block: Pose, action: Action) -> list[float]:
    """The regressors' input for one block: the actuator's position and the action
    in the block's frame, ``[rel_x, rel_y, a_x, a_y]``."""
    c, s = math.cos(block.theta), math.sin(block.theta)
    dx, dy = actuator.x - block.x, actuator.y - block.y
    vx, vy = action
    return [c * dx + s * dy, -s * dx + c * dy, c * vx + s * vy, -s * vx + c * vy]


def block_change(before: Pose, after: Pose) -> list[float]:
    """The regressors' output: the block's change in its frame, ``[dx, dy, dθ]``."""
    c, s = math.cos(before.theta), math.sin(before.theta)
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


class BaselineLearner(Learner):
    """What the baselines share: samples, the actuator gain, lazy fitting, prediction.

    Subclasses implement :meth:`_fit_block` (a fitted predictor for one
    block's standardised samples) and name themselves.
    """

    capabilities: ClassVar[frozenset[Capability]] = frozenset({Capability.FORWARD})
    version: ClassVar[str] = "0.1.0"

    def __init__(self, *, verbose: bool = False) -> None:
        self.seed = 0
        """The fold's seed (from :meth:`new_fold`)."""
        self.verbose = verbose
        """Whether every fit logs its choices (:meth:`describe_fit`) to stderr."""
        self._clear()

    def _clear(self) -> None:
        self.training = True
        self._stored: StateLike | None = None
        self._run = -1
        self._samples: dict[int, _BlockSamples] = {}
        self._actuator_steps: list[tuple[float, float, float, float]] = []  # u, Δp
        self._updates = 0
        self._training_runs: set[int] = set()
        self._dirty = False
        self._models: dict[int, Any] = {}
        self._used: dict[int, int] = {}
        self._gain = 1.0

    # -- the protocol's calls --------------------------------------------------

    def new_fold(self, seed: int) -> None:
        """Forgets every sample and fit; ``seed`` seeds the fold's subsampling."""
        self.seed = seed
        self._clear()

    def reset(self, state: StateLike) -> None:
        """Starts a run (a new cross-validation group) at ``state``."""
        self._stored = state
        self._run += 1

    def update(self, state: StateLike, action: Action) -> None:
        """Records the transition from the stored state into ``state`` (training on)."""
        previous = self._stored
        if previous is None:  # no reset before: treat as a new run
            self._run += 1
        elif self.training:
            self._record(previous, state, action)
        self._stored = state

    def set_training(self, on: bool) -> None:
        """Turns training on or off (the fit happens at the next prediction with it off)."""
        self.training = on

    def predict(self, state: StateLike, action: Action) -> Prediction:
        """The state one message later (see the module documentation)."""
        if not self.training and self._dirty:
            self._fit()
        poses = state.poses()
        dt = 1.0 / self.publish_rate_hz
        out: dict[int, tuple[float, float, float]] = {}
        actuator = poses[ACTUATOR_ID]
        vx, vy = action
        out[ACTUATOR_ID] = (
            actuator.x + self._gain * vx * dt,
            actuator.y + self._gain * vy * dt,
            actuator.theta,
        )
        for id_, block in poses.items():
            if id_ == ACTUATOR_ID:
                continue
            model = self._models.get(id_)
            if model is None:
                out[id_] = block
                continue
            x = np.asarray([block_features(actuator, block, action)], dtype=np.float64)
            change = np.asarray(model.predict(x), dtype=np.float64).reshape(-1)
            out[id_] = apply_change(block, change)
        return Prediction(out)

    def stats(self) -> dict[str, Any]:
        """Sample counts as maps: ``actuator_steps`` and ``block/ID``.

        ``update_calls`` counts the training updates, ``inserts`` the samples
        recorded, ``nodes`` the samples the last fit used. No extras or
        labels: the driver accepts those only in the built-in models' forms;
        the fit's choices are in :meth:`describe_fit` (logged with ``verbose``).
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
        """The fitted gain of the actuator's step (1 before any fit)."""
        return self._gain

    @property
    def training_runs(self) -> int:
        """How many runs (segments between resets) gave training samples this fold."""
        return len(self._training_runs)

    def describe_fit(self) -> list[str]:
        """The last fit's choices, one line per block (empty before any fit)."""
        return []

    # -- samples and fitting ---------------------------------------------------

    def _record(self, before: StateLike, after: StateLike, action: Action) -> None:
        old, new = before.poses(), after.poses()
        self._updates += 1
        self._training_runs.add(self._run)
        a0, a1 = old[ACTUATOR_ID], new[ACTUATOR_ID]
        dt = 1.0 / self.publish_rate_hz
        self._actuator_steps.append(
            (action[0] * dt, action[1] * dt, a1.x - a0.x, a1.y - a0.y)
        )
        for id_, block in old.items():
            if id_ == ACTUATOR_ID or id_ not in new:
                continue
            samples = self._samples.setdefault(id_, _BlockSamples())
            samples.inputs.append(block_features(a0, block, action))
            samples.outputs.append(block_change(block, new[id_]))
            samples.runs.append(self._run)
        self._dirty = True

    def _fit(self) -> None:
        steps = np.asarray(self._actuator_steps, dtype=np.float64).reshape(-1, 4)
        denominator = float(np.sum(steps[:, :2] ** 2))
        self._gain = (
            float(np.sum(steps[:, :2] * steps[:, 2:]) / denominator)
            if denominator
            else 1.0
        )
        self._models = {}
        self._used = {}
        for id_, samples in sorted(self._samples.items()):
            x = np.asarray(samples.inputs, dtype=np.float64)
            y = np.asarray(samples.outputs, dtype=np.float64)
            runs = np.asarray(samples.runs, dtype=np.int64)
            self._models[id_], self._used[id_] = self._fit_block(id_, x, y, runs)
        self._dirty = False
        if self.verbose:
            lines = [f"actuator gain {self._gain:.6f}", *self.describe_fit()]
            for line in lines:
                sys.stderr.write(f"{self.display_name} (seed {self.seed}): {line}\n")
            sys.stderr.flush()

    def _fit_block(
        self, block_id: int, x: Array, y: Array, runs: NDArray[np.int64]
    ) -> tuple[Any, int]:
        """A fitted predictor (``predict(x) -> changes``) and the number of samples it used."""
        raise NotImplementedError


def _verbose_option(parser: ArgumentParser) -> None:
    parser.add_argument(
        "--verbose", action="store_true", help="log every fit's choices to stderr"
    )


def _scaler(x: Array) -> Any:
    from sklearn.preprocessing import StandardScaler

    return StandardScaler().fit(x)


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
    """k-nearest-neighbour regression of each block's change (scikit-learn's
    ``KNeighborsRegressor``); ``k`` and the weighting chosen by cross-validation
    over the training runs (module documentation)."""

    name: ClassVar[str] = "knn"

    def __init__(self, max_k: int = 50, *, verbose: bool = False) -> None:
        if max_k < 1:
            raise ValueError(f"max_k must be at least 1, got {max_k}")
        self.max_k = max_k
        """The largest ``k`` tried."""
        self.choices: dict[int, CvChoice] = {}
        """The last fit's cross-validation per block id."""
        super().__init__(verbose=verbose)

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
            return cls(max_k=args.max_k, verbose=args.verbose)
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
        from sklearn.neighbors import KNeighborsRegressor
        from sklearn.pipeline import make_pipeline
        from sklearn.preprocessing import StandardScaler

        choice = self.choose(_scaler(x).transform(x), y, runs)
        self.choices[block_id] = choice
        model = make_pipeline(
            StandardScaler(),
            KNeighborsRegressor(n_neighbors=choice.k, weights=choice.weights),
        ).fit(x, y)
        return model, len(x)

    def describe_fit(self) -> list[str]:
        """``block ID: k=… weights=… (method, folds, runs)`` per block of the last fit."""
        return [
            f"block {id_}: k={c.k} weights={c.weights} ({c.method}, {len(c.splits)} folds, "
            f"{len(set(c.groups))} runs, {len(c.groups)} samples)"
            for id_, c in sorted(self.choices.items())
        ]


class GpLearner(BaselineLearner):
    """Gaussian-process regression of each block's change (scikit-learn's
    ``GaussianProcessRegressor``, ``C · RBF(ARD) + White``, hyper-parameters by
    marginal likelihood) on at most ``max_samples`` seeded-subsampled samples."""

    name: ClassVar[str] = "gp"

    def __init__(self, max_samples: int = 600, *, verbose: bool = False) -> None:
        if max_samples < 1:
            raise ValueError(f"max_samples must be at least 1, got {max_samples}")
        self.max_samples = max_samples
        """The cap on samples per block and fit (the fit is O(n³))."""
        self.kernels: dict[int, str] = {}
        """The last fit's optimised kernel per block id."""
        self.subsamples: dict[int, list[int]] = {}
        """The sample indices the last fit used per block id."""
        super().__init__(verbose=verbose)

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
            return cls(max_samples=args.max_samples, verbose=args.verbose)
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
        from sklearn.exceptions import ConvergenceWarning
        from sklearn.gaussian_process import GaussianProcessRegressor
        from sklearn.gaussian_process.kernels import (
            RBF,
            ConstantKernel,
            WhiteKernel,
        )
        from sklearn.pipeline import make_pipeline
        from sklearn.preprocessing import StandardScaler

        chosen = self.subsample(block_id, len(x))
        self.subsamples[block_id] = [int(i) for i in chosen]
        kernel = ConstantKernel(1.0, (1e-3, 1e3)) * RBF(
            length_scale=np.ones(x.shape[1]), length_scale_bounds=(1e-2, 1e3)
        ) + WhiteKernel(noise_level=1e-2, noise_level_bounds=(1e-10, 1e1))
        gp = GaussianProcessRegressor(
            kernel=kernel,
            normalize_y=True,
            n_restarts_optimizer=0,
            random_state=self.seed % 2**32,
        )
        model = make_pipeline(StandardScaler(), gp)
        with warnings.catch_warnings():
            # Bounds reached by a length scale (an input that does not matter)
            # are expected, not a problem.
            warnings.simplefilter("ignore", ConvergenceWarning)
            model.fit(x[chosen], y[chosen])
        self.kernels[block_id] = str(gp.kernel_)
        return model, len(chosen)

    def describe_fit(self) -> list[str]:
        """``block ID: N samples, kernel …`` per block of the last fit."""
        return [
            f"block {id_}: {len(self.subsamples.get(id_, []))} samples, kernel {kernel}"
            for id_, kernel in sorted(self.kernels.items())
        ]


BASELINES: dict[str, type[BaselineLearner]] = {"knn": KnnLearner, "gp": GpLearner}
"""The baselines by the name ``python -m pushlearn.baselines`` takes."""


def main(argv: list[str] | None = None) -> int:
    """``python -m pushlearn.baselines knn|gp [--listen HOST:PORT] [OPTIONS]``."""
    from .serve import main as serve_main

    args = list(sys.argv[1:] if argv is None else argv)
    usage = "usage: python -m pushlearn.baselines knn|gp [--listen HOST:PORT] [OPTIONS]"
    if not args or args[0] in ("-h", "--help"):
        print(usage + "\n\n" + (__doc__ or "").split("\n\n", 1)[0])
        return 0 if args else 2
    if args[0] not in BASELINES:
        print(
            f"pushlearn.baselines: unknown baseline {args[0]!r} (choose knn or gp)\n{usage}",
            file=sys.stderr,
        )
        return 2
    return serve_main([f"pushlearn.baselines:{BASELINES[args[0]].__name__}", *args[1:]])


if __name__ == "__main__":
    raise SystemExit(main())
