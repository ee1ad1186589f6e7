"""The real experiment driver running Python learners (``pushlearn experiment --learner``)."""

from __future__ import annotations

import json
import re
import subprocess
import sys
from pathlib import Path

import pytest
from conftest import LIMIT, PYTHON_DIR, TESTS_DIR, python_env


def pushlearn(
    driver_bin: Path, sim_bin: Path, *args: str, cwd: Path = TESTS_DIR
) -> subprocess.CompletedProcess[str]:
    """``pushlearn experiment ARGS`` with this build's world."""
    return subprocess.run(
        [str(driver_bin), "experiment", *args, "--sim-bin", str(sim_bin)],
        capture_output=True,
        text=True,
        env=python_env(),
        cwd=cwd,
        timeout=8 * LIMIT,
        check=False,
    )


def experiment(
    driver_bin: Path, sim_bin: Path, learner: str, *extra: str, cwd: Path = TESTS_DIR
) -> subprocess.CompletedProcess[str]:
    """A one-fold push task with one training run, on one worker."""
    return pushlearn(
        driver_bin,
        sim_bin,
        "push-task",
        "--learner",
        learner,
        "--train-runs",
        "1",
        "--folds",
        "1",
        "--workers",
        "1",
        *extra,
        cwd=cwd,
    )


def test_the_driver_runs_the_knn_baseline(
    driver_bin: Path, sim_bin: Path, tmp_path: Path
) -> None:
    report = tmp_path / "knn.json"
    done = experiment(
        driver_bin,
        sim_bin,
        f"{sys.executable} -m pushlearn.baselines knn",
        "--json",
        str(report),
    )
    assert done.returncode == 0, done.stderr
    result = json.loads(report.read_text())
    assert result["model"] == "knn"
    assert result["learner"]["version"] == "0.2.0"
    assert "learner 'knn'" in done.stdout


def test_a_failing_python_learner_fails_the_job_with_its_error(
    driver_bin: Path, sim_bin: Path, tmp_path: Path
) -> None:
    report = tmp_path / "broken.json"
    done = experiment(
        driver_bin,
        sim_bin,
        f"{sys.executable} -m pushlearn.serve sample_learners:Broken",
        "--json",
        str(report),
    )
    assert done.returncode != 0
    assert "ZeroDivisionError: the model divided by zero" in done.stderr
    assert not report.exists()  # no report from a failed job


# What depends on the machine or says who ran: left out of the comparison.
RUN_TIME = {
    "wall_seconds",
    "too_slow",
    "too_slow_fraction",
    "mean_handling_ms",
    "p50_handling_us",
    "p99_handling_us",
    "max_handling_ms",
    "simulated_states",
}


def comparable(path: Path) -> str:
    report = json.loads(path.read_text())
    report.pop("model")
    report.pop("learner", None)
    for key in RUN_TIME:
        report["run"].pop(key, None)
    return json.dumps(report, sort_keys=True)


def run_driver(driver_bin: Path, sim_bin: Path, *args: str) -> str:
    done = pushlearn(driver_bin, sim_bin, *args)
    assert done.returncode == 0, done.stderr
    return done.stdout


@pytest.mark.parametrize(
    "task",
    [
        ["push-task", "--train-runs", "1,3", "--folds", "2"],
        [
            "move-to-target",
            "--target",
            "0.6,0.7,0.75",
            "--repetitions",
            "2",
            "--max-steps",
            "400",
        ],
    ],
    ids=["push-task", "move-to-target"],
)
def test_the_gate_model_served_from_python_is_the_in_process_one_bit_for_bit(
    driver_bin: Path, sim_bin: Path, tmp_path: Path, task: list[str]
) -> None:
    """The cross-check of the whole path: bindings, SDK, protocol, driver."""
    pytest.importorskip("pushlearn._native")
    inside, outside = tmp_path / "inside.json", tmp_path / "outside.json"
    run_driver(driver_bin, sim_bin, *task, "--model", "gate", "--json", str(inside))
    served = f"{sys.executable} -m pushlearn.serve pushlearn.models:GateLearner"
    table = run_driver(
        driver_bin, sim_bin, *task, "--learner", served, "--json", str(outside)
    )
    assert "learner 'gate" in table
    assert comparable(inside) == comparable(outside)


# Not `unrounded` (so not gate+): through the learner protocol its model is
# not the in-process one bit for bit, `pushlearn serve-learner --model gate+`
# neither; GateModel(improve=["all"]) is checked against the native model in
# test_models.py.
@pytest.mark.parametrize(
    ("changes", "name"),
    [
        ("average-outputs", "gate+average-outputs"),
        (
            "shared-blocks,forward-check,interpolate,adapt-actuator",
            "gate+interpolate+adapt-actuator+forward-check+shared-blocks",
        ),
    ],
    ids=["one", "four"],
)
def test_the_improved_gate_model_served_from_python_is_the_in_process_one(
    driver_bin: Path,
    sim_bin: Path,
    tmp_path: Path,
    changes: str,
    name: str,
) -> None:
    """``GateModel(improve=[…])`` is ``--model gate --improve …`` (one registry)."""
    pytest.importorskip("pushlearn._native")
    task = ["push-task", "--train-runs", "1,3", "--folds", "2"]
    inside, outside = tmp_path / "inside.json", tmp_path / "outside.json"
    model = ["--model", "gate", "--improve", changes]
    run_driver(driver_bin, sim_bin, *task, *model, "--json", str(inside))
    served = (
        f"{sys.executable} -m pushlearn.serve "
        f"pushlearn.models:GateLearner --improve {changes}"
    )
    table = run_driver(
        driver_bin, sim_bin, *task, "--learner", served, "--json", str(outside)
    )
    assert f"learner '{name}'" in table
    assert "thesis values: the gate model's" in table
    for path in (inside, outside):
        assert json.loads(path.read_text())["model"] == name
    assert comparable(inside) == comparable(outside)


def test_the_readme_learner_runs_through_the_driver(
    driver_bin: Path, sim_bin: Path, tmp_path: Path
) -> None:
    """README.md's "Your own learner" example, as written."""
    readme = (PYTHON_DIR.parent / "README.md").read_text()
    blocks = re.findall(r"```python\n(# mylearner\.py.*?)```", readme, flags=re.DOTALL)
    assert len(blocks) == 1, "README.md lost its mylearner.py example"
    (tmp_path / "mylearner.py").write_text(blocks[0])
    report = tmp_path / "still.json"
    done = experiment(
        driver_bin,
        sim_bin,
        f"{sys.executable} -m pushlearn.serve mylearner.py:Still",
        "--json",
        str(report),
        cwd=tmp_path,
    )
    assert done.returncode == 0, done.stderr
    result = json.loads(report.read_text())
    assert result["model"] == "still"
    # Nothing but the actuator moves: the block's error is its whole travel.
    assert result["results"][0]["actuator_pos_err"]["mean"] < 0.01
