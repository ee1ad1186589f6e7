"""The real experiment driver running Python learners (``pushlearn experiment --learner``)."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

from conftest import LIMIT, TESTS_DIR, python_env


def experiment(
    driver_bin: Path, sim_bin: Path, learner: str, *extra: str
) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        [
            str(driver_bin),
            "experiment",
            "push-task",
            "--learner",
            learner,
            "--train-runs",
            "1",
            "--folds",
            "1",
            "--workers",
            "1",
            "--sim-bin",
            str(sim_bin),
            *extra,
        ],
        capture_output=True,
        text=True,
        env=python_env(),
        cwd=TESTS_DIR,
        timeout=4 * LIMIT,
        check=False,
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
    assert result["learner"]["version"] == "0.1.0"
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
