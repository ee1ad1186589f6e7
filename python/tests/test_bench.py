"""``pushlearn.bench``: the experiments from Python, equal to ``pushlearn experiment``'s."""

from __future__ import annotations

import json
import re
import signal
import subprocess
import sys
from pathlib import Path
from typing import Any, ClassVar

import pytest
from conftest import LIMIT, TESTS_DIR, python_env, run_python
from pushlearn import Capability, Learner, Prediction, StateLike, Target
from pushlearn.bench import (
    Report,
    arguments,
    move_to_target,
    push_task,
    without_timing,
)

pytest.importorskip("pushlearn._native")

PUSH: dict[str, Any] = {"train_runs": [1, 2], "folds": 2}
PUSH_FLAGS = ["--train-runs", "1,2", "--folds", "2"]
MTT: dict[str, Any] = {
    "targets": [(0.6, 0.7, 0.75)],
    "repetitions": 2,
    "max_steps": 400,
}
MTT_FLAGS = ["--target", "0.6,0.7,0.75", "--repetitions", "2", "--max-steps", "400"]


def cli_document(driver_bin: Path, tmp_path: Path, *args: str) -> dict[str, Any]:
    """``pushlearn experiment ARGS --json``'s document (embedded worlds, as the bench's)."""
    path = tmp_path / "cli.json"
    done = subprocess.run(
        [str(driver_bin), "experiment", *args, "--json", str(path)],
        capture_output=True,
        text=True,
        env=python_env(),
        cwd=TESTS_DIR,
        timeout=8 * LIMIT,
        check=False,
    )
    assert done.returncode == 0, done.stderr
    document: dict[str, Any] = json.loads(path.read_text())
    return document


def comparable(document: dict[str, Any]) -> dict[str, Any]:
    """Without timing, and without where the learner ran (a command, or this process)."""
    document = without_timing(document)
    learner = document.get("learner")
    if learner is not None:
        learner.pop("source")
    return document


@pytest.mark.parametrize(
    ("run", "kwargs", "flags"),
    [
        (push_task, PUSH, ["push-task", *PUSH_FLAGS]),
        (move_to_target, MTT, ["move-to-target", *MTT_FLAGS]),
    ],
    ids=["push-task", "move-to-target"],
)
def test_a_python_learner_gives_the_report_it_gives_through_learner_bit_for_bit(
    driver_bin: Path, tmp_path: Path, run: Any, kwargs: dict[str, Any], flags: list[str]
) -> None:
    from pushlearn.models import GateLearner

    here = run(GateLearner, progress=False, **kwargs)
    served = f"{sys.executable} -m pushlearn.serve pushlearn.models:GateLearner"
    there = cli_document(driver_bin, tmp_path, *flags, "--learner", served)
    assert here.document["learner"]["source"] == "pushlearn.bench, in-process"
    assert comparable(here.document) == comparable(there)
    assert here.document["model"].startswith("gate")


# Every kind of experiment, reduced: (bench function, its arguments, the
# command line's arguments).
KINDS: dict[str, tuple[Any, dict[str, Any], list[str]]] = {
    "push-task": (push_task, {"train_runs": [1], "folds": 1}, ["push-task"]),
    "two-objects": (
        push_task,
        {"variant": "two-objects", "train_runs": [6], "folds": 1},
        ["push-task", "--variant", "two-objects"],
    ),
    "new-objects": (
        push_task,
        {
            "train_on": ["blue", "red"],
            "test_on": "cylinder",
            "train_runs": [2],
            "folds": 1,
        },
        ["push-task", "--train-on", "blue,red", "--test-on", "cylinder"],
    ),
    "cross-object": (
        push_task,
        {"train_on": ["red"], "test_on": "blue", "train_runs": [1], "folds": 1},
        ["push-task", "--train-on", "red", "--test-on", "blue"],
    ),
    "move-to-target": (
        move_to_target,
        {"targets": [(0.6, 0.7, 0.75)], "repetitions": 1, "max_steps": 300},
        ["move-to-target", "--target", "0.6,0.7,0.75", "--repetitions", "1"],
    ),
}


def _flags(kwargs: dict[str, Any]) -> list[str]:
    """The command line's spelling of the counts in ``kwargs``."""
    flags = []
    if "train_runs" in kwargs:
        flags += ["--train-runs", ",".join(map(str, kwargs["train_runs"]))]
    if "folds" in kwargs:
        flags += ["--folds", str(kwargs["folds"])]
    if "max_steps" in kwargs:
        flags += ["--max-steps", str(kwargs["max_steps"])]
    return flags


@pytest.mark.parametrize("kind", sorted(KINDS))
@pytest.mark.parametrize("model", ["gate", "interaction", "gate+", "hybrid", "still"])
def test_a_built_in_models_report_is_the_clis_in_every_kind(
    driver_bin: Path, tmp_path: Path, model: str, kind: str
) -> None:
    run, kwargs, args = KINDS[kind]
    here = run(model, progress=False, **kwargs)
    there = cli_document(driver_bin, tmp_path, *args, *_flags(kwargs), "--model", model)
    assert comparable(here.document) == comparable(there)


@pytest.mark.parametrize("oracle", ["oracle-known", "oracle-unknown"])
def test_an_oracles_report_is_the_clis(
    driver_bin: Path, tmp_path: Path, oracle: str
) -> None:
    here = push_task(oracle, progress=False, **PUSH)
    latency = oracle.removeprefix("oracle-")
    there = cli_document(
        driver_bin, tmp_path, "push-task", *PUSH_FLAGS, "--oracle", latency
    )
    assert comparable(here.document) == comparable(there)


@pytest.mark.parametrize("kind", ["new-objects", "move-to-target"])
def test_the_sdks_learner_of_a_native_model_is_the_built_in_one(
    driver_bin: Path, tmp_path: Path, kind: str
) -> None:
    """The SDK path in process: the hybrid model (which reads the shapes the
    protocol's states carry) wrapped as a ``pushlearn.Learner`` gives the
    built-in model's report."""
    from pushlearn.models import HybridLearner

    run, kwargs, args = KINDS[kind]
    here = run(HybridLearner, progress=False, **kwargs)
    there = cli_document(
        driver_bin, tmp_path, *args, *_flags(kwargs), "--model", "hybrid"
    )
    mine, theirs = comparable(here.document), comparable(there)
    # The built-in model has no learner record; the learner object one.
    mine.pop("learner", None)
    assert mine == theirs


def test_the_report_has_the_tables_as_rows_and_the_progress_counts_every_job() -> None:
    seen: list[tuple[int, int]] = []
    report = push_task(
        "gate",
        train_runs=[1],
        folds=2,
        mode="lockstep",
        progress=lambda d, n: seen.append((d, n)),
    )
    assert isinstance(report, Report)
    assert seen[-1] == (2, 2)
    curve = report.table("learning-curve")
    assert curve.rows and all(isinstance(row, dict) for row in curve.rows)
    first = curve.rows[0]
    assert set(first) == set(curve.columns)
    numbers = [v for v in first.values() if isinstance(v, float)]
    assert numbers, f"no numeric cell in {first}"
    assert report.document["mode"] == "lockstep"
    assert json.loads(report.to_json()) == report.document
    with pytest.raises(KeyError, match="learning-curve"):
        report.table("no such table")


class Exploding(Learner):
    name = "exploding"

    def new_fold(self, seed: int) -> None:
        pass

    def predict(self, state: StateLike, action: tuple[float, float]) -> Prediction:
        raise ZeroDivisionError("the model divided by zero")


class Wrong(Exploding):
    name = "wrong"

    def predict(self, state: StateLike, action: tuple[float, float]) -> Prediction:
        poses = state.poses()
        poses.pop(8)
        return Prediction(poses)


class ForwardOnly(Exploding):
    capabilities: ClassVar[frozenset[Capability]] = frozenset({Capability.FORWARD})


def test_a_learners_exception_ends_the_run_with_it_as_the_cause() -> None:
    with pytest.raises(RuntimeError, match="exploding") as caught:
        push_task(Exploding, train_runs=[1], folds=1, progress=False)
    assert isinstance(caught.value.__cause__, ZeroDivisionError)


def test_a_wrong_prediction_is_named() -> None:
    with pytest.raises(RuntimeError, match="no pose for body 8"):
        push_task(Wrong(), train_runs=[1], folds=1, progress=False)


@pytest.mark.parametrize(
    ("call", "message"),
    [
        (
            lambda: push_task("no-such-model", progress=False),
            "invalid value 'no-such-model' for '--model",
        ),
        (
            lambda: push_task("gate", variant="sideways", progress=False),
            "invalid value 'sideways' for '--variant",
        ),
        (lambda: push_task("gate", folds=0, progress=False), "'0' for '--folds"),
        (
            lambda: push_task("gate", test_on="teapot", progress=False),
            "invalid value 'teapot' for '--test-on",
        ),
        (
            lambda: push_task("gate", mode="lockstep", latency_max=5, progress=False),
            "--latency-max",
        ),
        (
            lambda: push_task(Exploding, model="gate", progress=False),
            "drop model",
        ),
        (lambda: push_task("gate", eta=-1, progress=False), "'-1' for '--eta"),
        (lambda: push_task("gate", turbo=True, progress=False), "'--turbo'"),
        (lambda: move_to_target(ForwardOnly, progress=False), "INVERSE"),
        (
            lambda: move_to_target(
                "gate", targets=[(float("nan"), 0, 0)], progress=False
            ),
            "finite",
        ),
        (lambda: move_to_target("oracle-unknown", progress=False), "does not plan"),
        (lambda: push_task("floor", progress=False), "'floor' for '--model"),
        (lambda: push_task(42, progress=False), "expected a pushlearn.Learner"),  # type: ignore[arg-type]
    ],
)
def test_bad_arguments_are_named(call: Any, message: str) -> None:
    with pytest.raises((ValueError, TypeError), match=message):
        call()


def test_the_readmes_bench_example_runs_as_written(tmp_path: Path) -> None:
    """README.md's pushlearn.bench block, beside its mylearner.py."""
    readme = (TESTS_DIR.parents[1] / "README.md").read_text()
    learner = re.findall(r"```python\n(# mylearner\.py.*?)```", readme, flags=re.DOTALL)
    bench = re.findall(
        r"```python\n(from pushlearn\.bench.*?)```", readme, flags=re.DOTALL
    )
    assert len(learner) == 1 and len(bench) == 1, "README.md lost an example"
    (tmp_path / "mylearner.py").write_text(learner[0])
    done = run_python(bench[0], cwd=tmp_path, timeout=4 * LIMIT)
    assert done.returncode == 0, done.stderr
    assert "learner 'still' 1" in done.stdout, done.stdout


class Cheater(Learner):
    """Never moves, and from its new_fold replaces everything the Python side of
    ``pushlearn.bench`` could build a report with (issue 49, item 6: replacing
    ``pushlearn.bench._report`` made the table say "reached 1 of 1")."""

    name = "cheater"
    capabilities: ClassVar[frozenset[Capability]] = frozenset(
        {Capability.FORWARD, Capability.INVERSE}
    )
    patch: ClassVar[pytest.MonkeyPatch]

    def new_fold(self, seed: int) -> None:
        from pushlearn import bench

        forged = {"reached": 1, "runs": 1}

        class Forged:
            document = forged
            printed = "reached 1 of 1"

            def text(self) -> str:
                return self.printed

        for name in ["_report", "Report", "Table", "_Progress", "push_task"]:
            self.patch.setattr(bench, name, lambda *a, **k: Forged(), raising=False)
        self.patch.setattr(json, "loads", lambda *a, **k: forged)

    def predict(self, state: StateLike, action: tuple[float, float]) -> Prediction:
        return Prediction(state.poses())

    def set_target(self, target: Target | None) -> None:
        pass

    def act(self) -> tuple[tuple[float, float], bool]:
        return (0.0, 0.0), True


def test_a_learner_cannot_rewrite_its_report(monkeypatch: pytest.MonkeyPatch) -> None:
    Cheater.patch = monkeypatch
    report = move_to_target(
        Cheater,
        targets=[(0.6, 0.7, 0.75)],
        repetitions=1,
        max_steps=30,
        mode="lockstep",
        progress=False,
    )
    assert isinstance(report, Report), type(report)
    summary = report.document["targets"][0]["summary"]
    assert (summary["reached"], summary["runs"]) == (0, 1), summary
    assert "reached 1 of 1" not in report.text()
    assert "     1     1  no  " in report.text()
    monkeypatch.undo()
    assert json.loads(report.to_json())["targets"][0]["summary"]["reached"] == 0


SLEEPER = """
import sys, time
from pushlearn import Learner, Prediction
from pushlearn.bench import push_task

class Sleeper(Learner):
    name = "sleeper"
    def new_fold(self, seed):
        pass
    def predict(self, state, action):
        print("predicting", file=sys.stderr, flush=True)
        time.sleep(3600)
        return Prediction(state.poses())

try:
    push_task(Sleeper, train_runs=[1], folds=1, progress=False, {timeout})
except BaseException as err:
    print("ended:", type(err).__name__, "cause:", type(err.__cause__).__name__, err)
"""


def test_a_learner_call_past_its_timeout_ends_the_run_with_timeouterror_as_cause() -> (
    None
):
    """Issue 49, item 5: a learner sleeping in predict ran for ever (the command
    line has --learner-timeout; pushlearn.bench had nothing)."""
    done = run_python(SLEEPER.replace("{timeout}", "timeout=0.5"))
    assert "ended: RuntimeError cause: TimeoutError" in done.stdout, (
        done.stdout + done.stderr
    )
    assert "no answer within 0.5 s" in done.stdout, done.stdout


def test_ctrl_c_stops_a_run_inside_learner_code_as_keyboardinterrupt() -> None:
    """Issue 49, item 5: learner code ran on a worker thread, so SIGINT at 3 s
    surfaced at 21.9 s, and as a RuntimeError. Now learner code runs on the
    calling thread: SIGINT interrupts it and comes back as itself."""
    process = subprocess.Popen(
        [sys.executable, "-c", SLEEPER.replace("{timeout}", "timeout=3600")],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        env=python_env(),
    )
    assert process.stderr is not None
    try:
        while "predicting" not in process.stderr.readline():
            pass
        process.send_signal(signal.SIGINT)
        out, _ = process.communicate(timeout=LIMIT)
    finally:
        process.kill()
    assert out.startswith("ended: KeyboardInterrupt"), out


class Quitting(Exploding):
    name = "quitting"
    error: ClassVar[type[BaseException]] = KeyboardInterrupt

    def predict(self, state: StateLike, action: tuple[float, float]) -> Prediction:
        raise self.error("the learner asked to stop")


@pytest.mark.parametrize("error", [KeyboardInterrupt, SystemExit])
def test_keyboardinterrupt_and_systemexit_from_learner_code_keep_their_type(
    error: type[BaseException],
) -> None:
    """Issue 49, item 5: they came back as RuntimeError."""
    Quitting.error = error
    with pytest.raises(error, match="asked to stop"):
        push_task(Quitting, train_runs=[1], folds=1, progress=False)


# A value for each option of ``pushlearn experiment`` that has neither a
# default nor names to choose from (as the command's own test,
# ``lab::args``): a new option of that kind fails the next test until it
# has one here.
SAMPLES: dict[str, str] = {
    "train-runs": "2",
    "folds": "2",
    "workers": "2",
    "sim-bin": "pushlearn-sim",
    "sim": "127.0.0.1:9",
    "json": "out.json",
    "plots": "figures",
    "csv": "tables",
    "learner": "true",
    "learner-connect": "127.0.0.1:9",
    "target": "0.6,0.7,0.75",
    "sample-targets": "3",
}


def _sample(name: str, switch: bool, values: list[str], default: list[str]) -> Any:
    """A value of option ``name`` as a keyword of ``pushlearn.bench`` takes it: a
    name other than the default where there are names, else the default or the
    sample."""
    if switch:
        return True
    other = [v for v in values if v not in default]
    if other:
        return other[0]
    if default:
        return default[0]
    assert name in SAMPLES, f"--{name}: add a sample value to SAMPLES"
    return SAMPLES[name]


@pytest.mark.parametrize("command", ["push-task", "move-to-target"])
def test_every_option_of_the_command_reaches_the_bench(
    tmp_path: Path, command: str
) -> None:
    """Every option, listed from the command's own definition, spelled as a
    keyword (``-`` as ``_``) goes through the bench's spelling and the native
    parser to the end of the lowering: the run stops at the first thing after
    it, the check of a ``--json`` file in a missing directory, or is refused
    naming that option (an oracle has no Move to Target)."""
    from pushlearn import native

    module = native()
    missing = str(tmp_path / "missing" / "out.json")
    listed = module.experiment_options(command)
    assert len(listed) > 20
    for name, switch, values, default in listed:
        keyword = name.replace("-", "_")
        value = missing if name == "json" else _sample(name, switch, values, default)
        words = arguments(
            {keyword: value, "json": missing} if name != "json" else {keyword: value}
        )
        assert f"--{name}" in words or any(w.startswith(f"--{name}=") for w in words)
        with pytest.raises(ValueError) as refused:
            module.run_experiment(
                command, words, learner=None, progress=None, timeout=30.0
            )
        message = str(refused.value)
        assert "--json" in message or f"--{name}" in message, (name, message)


@pytest.mark.parametrize(
    "options",
    [
        {"model": "gate", "improve": ["unrounded"], "eta": 0.1, "mode": "lockstep"},
        {"model": "hybrid", "parts": "identified", "seed": 3},
        {"model": "interaction", "selector": "tree", "eta": 0.2, "no_reuse": True},
    ],
    ids=["gate-improve-eta", "hybrid-parts", "interaction-selector"],
)
def test_the_bench_gives_the_commands_report_with_the_same_options(
    driver_bin: Path, tmp_path: Path, options: dict[str, Any]
) -> None:
    """One small push task run by ``pushlearn experiment … --json`` and by
    ``pushlearn.bench`` with the same options (the model's among them): equal
    documents apart from timing; the bench writes its ``json`` as the command."""
    options = {**options, "train_runs": [1], "folds": 1}
    model = options.pop("model")
    written = tmp_path / "bench.json"
    here = push_task(model, progress=False, json=str(written), **options)
    there = cli_document(
        driver_bin,
        tmp_path,
        "push-task",
        "--model",
        model,
        *arguments(options),
    )
    assert comparable(here.document) == comparable(there)
    assert json.loads(written.read_text()) == here.document
