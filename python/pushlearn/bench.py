"""The benchmark from Python: the thesis's experiments with a learner object.

:func:`push_task` and :func:`move_to_target` run ``pushlearn experiment
push-task`` and ``move-to-target`` in this process: the same embedded worlds
(the world of ``pushlearn-sim``, stepped by the native extension), the same
seeds, driver and reports, with no subprocess and no learner protocol
between the driver and your learner::

    from pushlearn import Learner, Prediction
    from pushlearn.bench import push_task

    class Still(Learner):
        name = "still"

        def new_fold(self, seed):
            pass

        def predict(self, state, action):
            return Prediction(state.poses())

    report = push_task(Still, train_runs=[1, 3], folds=5)
    print(report.text())                     # the tables beside the thesis's
    curve = report.table("learning-curve")   # rows: a pandas.DataFrame(curve.rows)

``learner`` is a :class:`~pushlearn.Learner` (an instance, or its class or
any function that makes one, called once), or the name of a built-in model
(``"gate"``, ``"hybrid"``, …, or ``"floor"``, the world predicting itself).
A learner object is called exactly as :func:`pushlearn.serve` calls it for
``pushlearn experiment --learner``: the same :class:`~pushlearn.State` and
:class:`~pushlearn.Prediction` objects, the same checks of its answers, in
the same order; its report equals the one through ``--learner`` bit for bit
(the report's ``learner.source`` says where it ran). Folds run one after the
other in this process: one learner object, one world at a time.

An exception in learner code ends the experiment with a ``RuntimeError``
naming the job, the exception as its cause (with its traceback).
"""

from __future__ import annotations

import csv
import io
import json
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any, Self, TypeAlias

from .learner import (
    Body,
    Capability,
    Learner,
    LearnerFactory,
    Prediction,
    Shape,
    State,
    StateLike,
    Target,
    TargetRefused,
    _check_act,
    _checked_poses,
    _started,
    _stats_to_proto,
)

__all__ = [
    "LearnerLike",
    "Report",
    "Table",
    "move_to_target",
    "push_task",
    "without_timing",
]

LearnerLike: TypeAlias = Learner | LearnerFactory | str
"""A learner object, something that makes one, or a built-in model's name."""

Cell: TypeAlias = int | float | str | None
"""A table cell: a number, a text, or ``None`` where the table has none."""


@dataclass(frozen=True)
class Table:
    """One table of a report, as ``pushlearn experiment --csv`` writes it.

    ``rows`` are dicts by column name, numbers as floats, empty cells
    ``None``: ``pandas.DataFrame(table.rows)`` takes them as they are.
    """

    name: str
    """The table's name (the CSV file's: ``learning-curve``, …)."""
    title: str
    """The lines printed above it."""
    columns: list[str]
    """The column names, in order."""
    rows: list[dict[str, Cell]]
    """The rows."""


@dataclass(frozen=True)
class Report:
    """What an experiment gave: its report document and its tables."""

    document: dict[str, Any]
    """The JSON document ``pushlearn experiment --json`` writes, as a dict."""
    tables: list[Table]
    """The tables ``pushlearn experiment`` prints, beside the thesis's numbers."""
    printed: str
    """The text ``pushlearn experiment`` prints: every table, with the thesis's numbers."""

    def table(self, name: str) -> Table:
        """The table called ``name``; ``KeyError`` naming the tables there are if none is."""
        for table in self.tables:
            if table.name == name:
                return table
        names = ", ".join(t.name for t in self.tables)
        raise KeyError(f"the report has no table {name!r} (it has: {names})")

    def to_json(self) -> str:
        """The document as ``pushlearn experiment --json`` writes it."""
        return json.dumps(self.document, indent=2) + "\n"

    def text(self) -> str:
        """What ``pushlearn experiment`` prints for the experiment."""
        return self.printed


def push_task(
    learner: LearnerLike,
    train_runs: Sequence[int] | None = None,
    folds: int = 20,
    *,
    variant: str = "random",
    train_on: Sequence[str] | None = None,
    test_on: str | None = None,
    mode: str = "lockstep-jitter",
    latency_max: int = 2,
    seed: int = 1,
    progress: bool | Callable[[int, int], None] = True,
) -> Report:
    """Push Task Simulation: train on N pushes, then predict 150 messages of each test push.

    The arguments are ``pushlearn experiment push-task``'s options:
    ``train_runs`` (default: the variant's, 1,2,3,5,10,20,30 for
    ``random``), ``folds`` (each with a fresh model), ``variant``
    (``random``, ``fixed-three``, ``two-objects``, ``draft``), the new
    objects ``train_on`` / ``test_on`` (``blue``, ``red``, ``cylinder``),
    the world's timing ``mode`` (``lockstep-jitter`` with ``latency_max``
    steps, or ``lockstep``) and the ``seed`` of every random choice.
    ``progress``: a bar on stderr (``True``), none (``False``), or a
    function called with ``(jobs done, jobs)``.

    Raises ``ValueError`` naming a bad argument, ``RuntimeError`` when a job
    fails (a learner's exception is its cause).
    """
    native, learner_arg = _prepare(learner)
    with _Progress(progress, "push task") as bar:
        outcome = native.run_push_task(
            learner_arg,
            variant=variant,
            train_runs=None if train_runs is None else [int(n) for n in train_runs],
            folds=int(folds),
            train_on=None if train_on is None else list(train_on),
            test_on=test_on,
            mode=mode,
            latency_max=int(latency_max),
            seed=int(seed),
            progress=bar.callback,
        )
    return _report(outcome)


def move_to_target(
    learner: LearnerLike,
    targets: Sequence[tuple[float, float, float]] | None = None,
    *,
    sample_targets: int | None = None,
    repetitions: int = 5,
    max_steps: int = 3000,
    mode: str = "lockstep-jitter",
    latency_max: int = 2,
    seed: int = 1,
    progress: bool | Callable[[int, int], None] = True,
) -> Report:
    """Move to Target: train on 8 fixed pushes, then push the blue block to each target pose.

    ``targets`` are ``(x, y, theta)`` poses of the blue block (default: the
    thesis's four), or ``sample_targets`` draws that many from the reachable
    region (seeded by ``seed``); ``repetitions`` test runs per target, each
    with a freshly trained model, of at most ``max_steps`` messages. Success
    is judged from the world's state, not the learner's word. The other
    arguments are :func:`push_task`'s. The learner must declare
    ``Capability.INVERSE`` and implement ``act``.
    """
    native, learner_arg = _prepare(learner)
    with _Progress(progress, "move to target") as bar:
        outcome = native.run_move_to_target(
            learner_arg,
            targets=None
            if targets is None
            else [tuple(map(float, t)) for t in targets],
            sample_targets=sample_targets,
            repetitions=int(repetitions),
            max_steps=int(max_steps),
            mode=mode,
            latency_max=int(latency_max),
            seed=int(seed),
            progress=bar.callback,
        )
    return _report(outcome)


def without_timing(document: dict[str, Any]) -> dict[str, Any]:
    """A report document without what depends on the machine (wall time, handling
    times, workers): two runs of one experiment give equal documents."""
    from . import native

    result: dict[str, Any] = json.loads(native().without_timing(json.dumps(document)))
    return result


def _prepare(learner: LearnerLike) -> tuple[Any, Any]:
    """The native module and what it takes for ``learner``: a name, or a :class:`_Direct`."""
    from . import native

    module = native()
    if isinstance(learner, str):
        return module, learner
    if not (isinstance(learner, Learner) or callable(learner)):
        raise TypeError(
            f"learner is {type(learner).__name__}: expected a pushlearn.Learner, "
            "a class or function that makes one, or a built-in model's name"
        )
    return module, _Direct(learner)


def _cell(text: str) -> Cell:
    if text == "":
        return None
    for number in (int, float):
        try:
            return number(text)
        except ValueError:
            pass
    return text


def _report(outcome: tuple[str, str, list[tuple[str, list[str], str]]]) -> Report:
    document_json, printed, tables = outcome
    parsed = []
    for name, title, text in tables:
        reader = csv.reader(io.StringIO(text))
        columns = next(reader, [])
        rows = [
            {column: _cell(value) for column, value in zip(columns, row, strict=True)}
            for row in reader
        ]
        parsed.append(
            Table(name=name, title="\n".join(title), columns=columns, rows=rows)
        )
    return Report(document=json.loads(document_json), tables=parsed, printed=printed)


class _Progress:
    """The progress the native run reports: a tqdm bar, a function, or nothing."""

    def __init__(self, progress: bool | Callable[[int, int], None], what: str) -> None:
        self._what = what
        self._user = progress if callable(progress) else None
        self._bar: Any = None
        self._show = progress is True

    def __enter__(self) -> Self:
        return self

    def __exit__(self, *exc: object) -> None:
        if self._bar is not None:
            self._bar.close()

    def callback(self, done: int, total: int) -> None:
        """Called by the native run after each job."""
        if self._user is not None:
            self._user(done, total)
        elif self._show:
            if self._bar is None:
                from tqdm.auto import tqdm

                self._bar = tqdm(total=total, desc=self._what, unit="job")
            self._bar.update(done - self._bar.n)


class _Direct:
    """The learner protocol's dispatch without the protocol, called by the native driver.

    Each method is one request of ``pushlearn.serve``'s session, with the
    same objects and the same checks of the learner's answers
    (:mod:`pushlearn.learner`), so that a learner gives here what it gives
    through ``pushlearn experiment --learner``.
    """

    def __init__(self, source: Learner | LearnerFactory) -> None:
        self._source = source
        self._learner: Learner | None = None

    @property
    def learner(self) -> Learner:
        if self._learner is None:
            raise RuntimeError("the learner was called before start (a driver bug)")
        return self._learner

    def start(self, task: str, publish_rate_hz: int) -> tuple[str, str, bool, bool]:
        """Start: the learner made and started; what its Hello would say."""
        learner = _started(self._source, task, publish_rate_hz)
        if Capability.FORWARD not in learner.capabilities:
            raise ValueError(
                f"learner '{learner.display_name}' does not declare Capability.FORWARD, "
                "which every experiment needs"
            )
        self._learner = learner
        return (
            learner.display_name,
            str(learner.version),
            Capability.INVERSE in learner.capabilities,
            bool(learner.ignores_actuator_yaw),
        )

    @staticmethod
    def observed(
        bodies: list[
            tuple[
                str,
                int,
                Sequence[float],
                Sequence[float],
                tuple[str, Sequence[float]] | None,
            ]
        ],
    ) -> State:
        """An observed world state, as the protocol delivers one (no velocities, no
        counters; each body with its shape)."""
        return State(
            Body(
                name=name,
                id=id_,
                position=(position[0], position[1], position[2]),
                orientation=(
                    orientation[0],
                    orientation[1],
                    orientation[2],
                    orientation[3],
                ),
                shape=None if shape is None else _shape(name, *shape),
            )
            for name, id_, position, orientation, shape in bodies
        )

    def new_fold(self, seed: int) -> None:
        self.learner.new_fold(int(seed))

    def reset(self, state: StateLike) -> None:
        self.learner.reset(state)

    def update(self, state: StateLike, vx: float, vy: float) -> None:
        self.learner.update(state, (vx, vy))

    def predict(
        self, state: StateLike, vx: float, vy: float
    ) -> tuple[Prediction, list[tuple[int, float, float, float]]]:
        prediction = self.learner.predict(state, (vx, vy))
        poses = _checked_poses(prediction, state)
        return prediction, [(id_, p.x, p.y, p.theta) for id_, p in poses.items()]

    def set_training(self, on: bool) -> None:
        self.learner.set_training(bool(on))

    def set_target(self, goal: tuple[int, float, float, float] | None) -> str | None:
        """None when accepted, else the refusal's reason."""
        target = None if goal is None else Target(*goal)
        try:
            self.learner.set_target(target)
        except TargetRefused as refused:
            return refused.reason
        return None

    def act(self) -> tuple[float, float, bool]:
        reply = _check_act(self.learner.act())
        return (reply.action.vx, reply.action.vy, reply.has_target)

    def stats(self) -> bytes:
        """The statistics in the protocol's form (checked as ``serve`` checks them)."""
        result: bytes = _stats_to_proto(self.learner.stats()).SerializeToString()
        return result


def _shape(name: str, kind: str, sizes: Sequence[float]) -> Shape:
    """The SDK's shape of body ``name`` from the native side's ``(kind, sizes)``."""
    if kind == "sphere":
        return Shape(name, sphere_radius=sizes[0])
    if kind == "box":
        return Shape(name, box_size=(sizes[0], sizes[1], sizes[2]))
    return Shape(name, cylinder=(sizes[0], sizes[1]))
