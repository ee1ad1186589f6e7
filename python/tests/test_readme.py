"""python/README.md's examples work as written."""

from __future__ import annotations

import re
import subprocess
import sys
from collections.abc import Callable
from pathlib import Path

import pytest
from conftest import LIMIT, PYTHON_DIR, Daemon, python_env, run_python
from driver import (
    LAST_PREDICTION,
    Script,
    action,
    decode_replies,
    observed,
    recent,
    world,
)
from pushlearn._pb import learner_pb2

README = PYTHON_DIR / "README.md"


def python_blocks() -> list[str]:
    return [
        str(b)
        for b in re.findall(r"```python\n(.*?)```", README.read_text(), flags=re.DOTALL)
    ]


def learner_example() -> str:
    sources = [b for b in python_blocks() if b.startswith("# mymodule.py")]
    assert len(sources) == 1, "README.md lost its mymodule.py example"
    return sources[0]


@pytest.mark.parametrize("how", ["serve", "script"])
def test_the_readme_learner_serves_the_push_task_calls(
    tmp_path: Path, how: str
) -> None:
    (tmp_path / "mymodule.py").write_text(learner_example())
    s = Script()
    s.start()
    s.add(new_fold=learner_pb2.NewFold(seed=1))
    s.add(
        predict=learner_pb2.Predict(
            **{"from": observed(world((0.0, 0.0))), "action": action(0, 0.5)}
        )
    )
    s.add(
        predict=learner_pb2.Predict(
            **{"from": recent(LAST_PREDICTION), "action": action(0, 0.5)}
        )
    )
    s.add(bye=learner_pb2.Bye())
    argv = (
        ["-m", "pushlearn.serve", "mymodule:MyLearner"]
        if how == "serve"
        else ["mymodule.py"]
    )
    done = subprocess.run(
        [sys.executable, *argv],
        input=s.bytes(),
        capture_output=True,
        env=python_env(),
        cwd=tmp_path,
        timeout=LIMIT,
        check=False,
    )
    assert done.returncode == 0, done.stderr.decode()
    replies = decode_replies(done.stdout)
    assert replies[0].hello.name == "still"
    ys = [r.prediction.bodies[0].y for r in replies[1:]]
    assert ys == pytest.approx([0.005, 0.010])
    assert [b.id for b in replies[2].prediction.bodies] == [8, 15]


def test_the_readme_sim_client_example_runs(start_sim: Callable[..., Daemon]) -> None:
    daemon = start_sim("--mode", "lockstep")
    (source,) = [b for b in python_blocks() if "SimClient.connect" in b]
    source = source.replace("11345", str(daemon.port))
    done = run_python(source)
    assert done.returncode == 0, done.stderr
    first, last = done.stdout.strip().splitlines()
    assert first == "one_block lockstep 100"
    assert last.startswith("Pose(x=") and "y=0.82" in last


def test_the_readme_native_model_options_run() -> None:
    pytest.importorskip("pushlearn._native")
    (source,) = [b for b in python_blocks() if "GateModel(improve" in b]
    done = run_python(source)
    assert done.returncode == 0, done.stderr
    assert done.stdout == "gate+average-outputs gate+\n"


def test_the_readme_bench_example_runs_the_learner_through_the_push_task(
    tmp_path: Path,
) -> None:
    pytest.importorskip("pushlearn._native")
    (tmp_path / "mymodule.py").write_text(learner_example())
    (source,) = [b for b in python_blocks() if "pushlearn.bench import" in b]
    done = run_python(source, cwd=tmp_path, timeout=4 * LIMIT)
    assert done.returncode == 0, done.stderr
    assert "learner 'still' 1" in done.stdout, done.stdout
    assert "Learning curve, all 21 test positions" in done.stdout
