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
(``"gate"``, ``"still"``, …: :func:`pushlearn.model_names` lists them; or an oracle, ``"oracle-known"`` or
``"oracle-unknown"``: a copy of the world predicting itself, docs/models.md
"Reference rows").
A learner object is called exactly as :func:`pushlearn.serve` calls it for
``pushlearn experiment --learner``: the same :class:`~pushlearn.State` and
:class:`~pushlearn.Prediction` objects, the same checks of its answers, in
the same order; its report equals the one through ``--learner`` bit for bit
(the report's ``learner.source`` says where it ran). Folds run one after the
other in this process: one learner object, one world at a time.

The keywords are ``pushlearn experiment``'s options, every one of them
(``-`` spelled ``_``), turned into its arguments (:func:`arguments`) and
parsed and lowered by the command's own parser: the same defaults, the same
refusals with the same messages, the same experiment.

An exception in learner code ends the experiment with a ``RuntimeError``
naming the job, the exception as its cause (with its traceback);
``KeyboardInterrupt`` and ``SystemExit`` end it as themselves. Each learner
call may take ``timeout`` seconds (default 30, as ``pushlearn experiment
--learner-timeout``): past it the call is interrupted with ``TimeoutError``
(the cause), where Python can interrupt it, i.e. when ``pushlearn.bench`` is
called from the main thread (it sets ``SIGALRM`` for the run and restores the
previous handler after); elsewhere a call that returns late fails the run.
Learner code runs on the calling thread and Ctrl-C stops the run at once.

**What in-process trusts.** The learner shares the interpreter. The driver
scores it in Rust and builds the :class:`Report` there, after the run, from
data learner code never holds, so replacing anything in this module changes
nothing; but a learner that rewrites the interpreter itself (builtins, the
report's class) is beyond any in-process harness: run a learner you do not
trust through ``pushlearn experiment --learner``, where a process boundary
holds. One learner object serves every fold, as one process does over the
protocol: ``new_fold`` is its promise to forget, which the report cannot
check (``pushlearn learner-check`` runs a fold twice and warns of a learner
that remembers; ``docs/learner-protocol.md`` §5).
"""

from __future__ import annotations

import contextlib
import json
import math
import signal
import threading
from collections.abc import Callable, Iterator, Sequence
from types import FrameType
from typing import TYPE_CHECKING, Any, Self, TypeAlias

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
    "Option",
    "Report",
    "Table",
    "arguments",
    "move_to_target",
    "push_task",
    "without_timing",
]

LearnerLike: TypeAlias = Learner | LearnerFactory | str
"""A learner object, something that makes one, or a built-in model's name."""

if TYPE_CHECKING:
    from ._native import Report, Table
else:
    try:
        from ._native import Report, Table
    except ImportError:  # the SDK works without the extension; the bench does not
        Report = Table = None

DEFAULT_TIMEOUT = 30.0
"""Seconds a learner call may take: ``pushlearn experiment --learner-timeout``'s default."""


Option: TypeAlias = (
    bool | int | float | str | Sequence[int | float | str | Sequence[float]] | None
)
"""A value of ``pushlearn experiment``'s options, as :func:`push_task` takes it."""


def push_task(
    learner: LearnerLike,
    train_runs: Sequence[int] | None = None,
    folds: int | None = None,
    *,
    variant: str | None = None,
    train_on: Sequence[str] | None = None,
    test_on: str | None = None,
    mode: str | None = None,
    latency_max: int | None = None,
    seed: int | None = None,
    progress: bool | Callable[[int, int], None] = True,
    timeout: float = DEFAULT_TIMEOUT,
    **options: Option,
) -> Report:
    """Push Task Simulation: train on N pushes, then predict 150 messages of each test push.

    Every keyword is an option of ``pushlearn experiment push-task``,
    spelled with ``_`` for ``-`` (``train_runs=[1, 3]`` is
    ``--train-runs=1 --train-runs=3``: a list repeats its option;
    ``no_reuse=True`` is ``--no-reuse``),
    and goes through that command's own parser: the same defaults, checks
    and messages. ``None`` leaves an option at the command's default.
    Named here: ``train_runs`` (default: the variant's, 1,2,3,5,10,20,30
    for ``random``), ``folds`` (each with a fresh model; default 20, 1 for
    ``variant="draft"``), ``variant`` (``random``, ``fixed-three``,
    ``two-objects``, ``constant-feedback``, ``draft``), the new objects
    ``train_on`` / ``test_on`` (``blue``, ``red``, ``cylinder``), the
    world's timing ``mode`` (``lockstep-jitter`` with ``latency_max``
    steps, ``lockstep`` or ``realtime``) and the ``seed`` of every random
    choice; through ``options`` every other one, the model options among
    them (``eta=0.1``, ``improve=["unrounded"]``, ``parts="identified"``,
    ``selector="tree"``, …) and the outputs (``json=``, ``plots=``,
    ``csv=``), written as the command writes them.
    ``progress``: a bar on stderr (``True``), none (``False``), or a
    function called with ``(jobs done, jobs)``. ``timeout``: seconds each
    call of a learner object may take.

    Raises ``ValueError`` naming a bad argument (the command's message),
    ``RuntimeError`` when a job fails (a learner's exception is its cause).
    """
    given: dict[str, Option] = {
        "train_runs": train_runs,
        "folds": folds,
        "variant": variant,
        "train_on": train_on,
        "test_on": test_on,
        "mode": mode,
        "latency_max": latency_max,
        "seed": seed,
    }
    return _experiment(
        "push-task", learner, {**given, **options}, progress, timeout, "push task"
    )


def move_to_target(
    learner: LearnerLike,
    targets: Sequence[tuple[float, float, float]] | None = None,
    *,
    sample_targets: int | None = None,
    repetitions: int | None = None,
    max_steps: int | None = None,
    mode: str | None = None,
    latency_max: int | None = None,
    seed: int | None = None,
    progress: bool | Callable[[int, int], None] = True,
    timeout: float = DEFAULT_TIMEOUT,
    **options: Option,
) -> Report:
    """Move to Target: train on 8 fixed pushes, then push the blue block to each target pose.

    The options of ``pushlearn experiment move-to-target``, as
    :func:`push_task` takes its command's: ``targets`` are ``(x, y, theta)``
    poses of the blue block (``--target``, one each; default: the thesis's
    four), or ``sample_targets`` draws that many from the reachable region
    (seeded by ``seed``); ``repetitions`` test runs per target (default 5),
    each with a freshly trained model, of at most ``max_steps`` messages
    (default 3000). Success is judged from the world's state, not the
    learner's word. A learner object must declare ``Capability.INVERSE``
    and implement ``act``.
    """
    given: dict[str, Option] = {
        "target": targets,
        "sample_targets": sample_targets,
        "repetitions": repetitions,
        "max_steps": max_steps,
        "mode": mode,
        "latency_max": latency_max,
        "seed": seed,
    }
    return _experiment(
        "move-to-target",
        learner,
        {**given, **options},
        progress,
        timeout,
        "move to target",
    )


_LEARNER_OPTIONS = ("model", "learner", "learner_connect", "oracle")
"""The options that choose the learner, which a learner object replaces."""


def arguments(options: dict[str, Option]) -> list[str]:
    """``options`` as ``pushlearn experiment``'s arguments: ``{"train_runs": [1, 3],
    "no_reuse": True, "eta": 0.1}`` is ``--train-runs=1 --train-runs=3 --no-reuse
    --eta=0.1`` (with ``=``, so that a value may start with ``-``); ``None`` and
    ``False`` give nothing (the command's default), a pose's ``(x, y, theta)`` is
    ``x,y,theta``."""
    words: list[str] = []
    for key, value in options.items():
        flag = "--" + key.replace("_", "-")
        if value is None or value is False:
            continue
        if value is True:
            words.append(flag)
        elif isinstance(value, str | int | float):
            words.append(f"{flag}={_word(value)}")
        else:
            words += [f"{flag}={_word(item)}" for item in value]
    return words


def _word(value: float | str | Sequence[float]) -> str:
    if isinstance(value, str):
        return value
    if isinstance(value, int | float):
        return repr(value)
    return ",".join(repr(v) for v in value)


def _experiment(
    command: str,
    learner: LearnerLike,
    options: dict[str, Option],
    progress: bool | Callable[[int, int], None],
    timeout: float,
    what: str,
) -> Report:
    """Runs ``pushlearn experiment COMMAND`` with ``options`` in this process."""
    from . import native

    module = native()
    direct = None
    if isinstance(learner, str):
        oracle = learner.removeprefix("oracle-")
        chosen = {"oracle": oracle} if oracle != learner else {"model": learner}
        options = {**chosen, **options}
    elif isinstance(learner, Learner) or callable(learner):
        given = [k for k in _LEARNER_OPTIONS if options.get(k) is not None]
        if given:
            raise ValueError(
                f"the learner is the object given; drop {', '.join(given)}"
            )
        direct = _Direct(learner)
    else:
        raise TypeError(
            f"learner is {type(learner).__name__}: expected a pushlearn.Learner, "
            "a class or function that makes one, or a built-in model's name"
        )
    words = arguments(options)
    # The report comes from the native run as it is: no function of this
    # module is looked up after learner code has run.
    with _Progress(progress, what) as bar, _deadlines(direct, timeout):
        report: Report = module.run_experiment(
            command,
            words,
            learner=direct,
            progress=bar.callback,
            timeout=float(timeout),
        )
    return report


def without_timing(document: dict[str, Any]) -> dict[str, Any]:
    """A report document without what depends on the machine (wall time, handling
    times, workers): two runs of one experiment give equal documents."""
    from . import native

    result: dict[str, Any] = json.loads(native().without_timing(json.dumps(document)))
    return result


@contextlib.contextmanager
def _deadlines(learner: Any, timeout: float) -> Iterator[None]:
    """Lets ``learner`` (a :class:`_Direct`) interrupt a call that overruns
    ``timeout`` with ``TimeoutError``: a ``SIGALRM`` handler for the run, set
    on the main thread only (Python runs signal handlers nowhere else)."""
    if not (
        isinstance(timeout, int | float) and math.isfinite(timeout) and timeout > 0
    ):
        raise ValueError(
            f"timeout must be a positive number of seconds, not {timeout!r}"
        )
    if not isinstance(learner, _Direct) or (
        threading.current_thread() is not threading.main_thread()
    ):
        yield
        return

    def overrun(signum: int, frame: FrameType | None) -> None:
        raise TimeoutError(f"no answer within {timeout:g} s")

    previous = signal.signal(signal.SIGALRM, overrun)
    learner.alarm = True
    try:
        yield
    finally:
        learner.alarm = False
        signal.setitimer(signal.ITIMER_REAL, 0)
        signal.signal(signal.SIGALRM, previous)


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
        self.alarm = False
        """Whether :func:`_deadlines` set ``SIGALRM`` for the run."""

    def call(self, method: str, args: tuple[Any, ...], timeout: float) -> Any:
        """One call of the native driver's, given ``timeout`` seconds where a
        ``SIGALRM`` can interrupt it."""
        function = getattr(self, method)
        if not self.alarm:
            return function(*args)
        signal.setitimer(signal.ITIMER_REAL, timeout)
        try:
            return function(*args)
        finally:
            signal.setitimer(signal.ITIMER_REAL, 0)

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
