"""Each rule of ``docs/learner-protocol.md`` §8 that the driver checks: a learner written
against the protocol alone (``raw_learner.py``) breaks it, and both the experiment driver
and ``pushlearn learner-check`` stop with an error that names the rule."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest
from conftest import LIMIT, TESTS_DIR, python_env

RAW = TESTS_DIR / "raw_learner.py"

# mode, the experiment that meets the broken rule, what the error must say.
BROKEN = [
    ("old-version", "push-task", "speaks learner protocol version 2"),
    ("no-name", "push-task", "said hello without a name"),
    ("no-forward", "push-task", "does not announce the FORWARD capability"),
    ("answer-one-way", "push-task", "new_fold is one-way and gets no reply"),
    (
        "wrong-seq",
        "push-task",
        "a prediction reply for message 5 (expected a prediction reply for message 4)",
    ),
    ("miss-block", "push-task", "predicted no pose for block 15"),
    (
        "extra-body",
        "push-task",
        "predicted body 99, which the state it predicted from does not have",
    ),
    ("twice", "push-task", "predicted body 8 twice"),
    (
        "error",
        "push-task",
        "the learner failed on message 4 (predict): ValueError: raw",
    ),
    ("reserved-stats", "push-task", 'map "actuator" is missing'),
    ("refuse-target", "move-to-target", "refused the target: no"),
    ("nan-action", "move-to-target", "chose a non-finite action"),
]


def learner(mode: str) -> str:
    return f"{sys.executable} {RAW} {mode}"


def run(driver_bin: Path, *args: str) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        [str(driver_bin), *args],
        capture_output=True,
        text=True,
        env=python_env(),
        cwd=TESTS_DIR,
        timeout=8 * LIMIT,
        check=False,
    )


def experiment_args(task: str, mode: str, sim_bin: Path, out: Path) -> list[str]:
    common = ["--learner", learner(mode), "--workers", "1", "--sim-bin", str(sim_bin)]
    common += ["--json", str(out)]
    if task == "push-task":
        return ["experiment", "push-task", "--train-runs", "1", "--folds", "1", *common]
    return [
        "experiment",
        "move-to-target",
        "--target=-0.6,-0.7,0",
        "--repetitions",
        "1",
        *common,
    ]


@pytest.mark.parametrize(
    ("mode", "task", "message"), BROKEN, ids=[b[0] for b in BROKEN]
)
def test_the_driver_names_the_rule_a_learner_breaks(
    driver_bin: Path, sim_bin: Path, tmp_path: Path, mode: str, task: str, message: str
) -> None:
    out = tmp_path / "report.json"
    done = run(driver_bin, *experiment_args(task, mode, sim_bin, out))
    assert done.returncode == 1, done.stderr
    assert message in done.stderr, done.stderr
    assert done.stderr.count("error:") == 1, done.stderr
    assert not out.exists(), "a report was written although the learner broke a rule"


@pytest.mark.parametrize(
    ("mode", "task", "message"), BROKEN, ids=[b[0] for b in BROKEN]
)
def test_learner_check_names_the_rule_a_learner_breaks(
    driver_bin: Path, mode: str, task: str, message: str
) -> None:
    done = run(driver_bin, "learner-check", learner(mode))
    assert done.returncode == 1, done.stdout + done.stderr
    assert message in done.stdout, done.stdout
    assert "BROKEN" in done.stdout, done.stdout


def test_a_learner_that_keeps_the_rules_passes_learner_check(driver_bin: Path) -> None:
    done = run(driver_bin, "learner-check", learner("ok"))
    assert done.returncode == 0, done.stdout + done.stderr
    assert "BROKEN" not in done.stdout, done.stdout
    # Every conversation ran: the hello, two folds and Move to Target.
    assert done.stdout.count("  ok ") == 4, done.stdout
    assert "learner 'raw' 1" in done.stdout, done.stdout


def test_a_learner_that_claims_the_target_at_once_is_not_scored_reached(
    driver_bin: Path, sim_bin: Path, tmp_path: Path
) -> None:
    out = tmp_path / "report.json"
    done = run(driver_bin, *experiment_args("move-to-target", "liar", sim_bin, out))
    assert done.returncode == 0, done.stderr
    report = json.loads(out.read_text())
    [target] = report["targets"]
    [only] = target["runs"]
    # The learner's first Act ended the run; the block had not moved.
    assert only["steps"] == 0, only
    assert only["reached"] is False, only
    assert only["pos_err"] > 1.0, only
    assert target["summary"]["reached"] == 0, target["summary"]
    assert target["summary"]["pos_err_all"] == only["pos_err"], target["summary"]
