"""examples/python/push.py against the real world daemon."""

from __future__ import annotations

import socket
import subprocess
import sys
from collections.abc import Callable
from pathlib import Path

from conftest import LIMIT, REPO_ROOT, Daemon, python_env, sweep_centre

EXAMPLE = REPO_ROOT / "examples" / "python" / "push.py"


def free_port() -> int:
    with socket.socket() as probe:
        probe.bind(("127.0.0.1", 0))
        return int(probe.getsockname()[1])


def test_the_push_example_prints_the_calibration_push(
    start_sim: Callable[..., Daemon], sim_bin: Path
) -> None:
    daemon = start_sim("--mode", "lockstep")
    done = subprocess.run(
        [
            sys.executable,
            str(EXAMPLE),
            "--port",
            str(daemon.port),
        ],
        capture_output=True,
        text=True,
        env=python_env(),
        timeout=LIMIT,
        check=False,
    )
    assert done.returncode == 0, done.stderr
    first, last = done.stdout.strip().splitlines()
    assert first == "scene one_block, lockstep mode, 100 Hz, bodies: actuator, blockA"
    prefix = "blockA (blue block) after 150 states: "
    assert last.startswith(prefix), last
    fields = dict(f.split("=") for f in last[len(prefix) :].split() if "=" in f)
    assert [fields["x"], fields["y"], fields["yaw"]] == sweep_centre(sim_bin)


def test_the_push_example_reports_a_missing_world() -> None:
    done = subprocess.run(
        [
            sys.executable,
            str(EXAMPLE),
            "--port",
            str(free_port()),
        ],
        capture_output=True,
        text=True,
        env=python_env(),
        timeout=LIMIT,
        check=False,
    )
    assert done.returncode == 1
    assert (
        "is pushlearn-sim running there?" in done.stderr
        and "Traceback" not in done.stderr
    )


# Runs the example with every `google.*` import failing, as on a machine
# without protobuf.
_WITHOUT_PROTOBUF = """
import runpy, sys

class NoProtobuf:
    def find_spec(self, name, path=None, target=None):
        if name == "google" or name.startswith("google."):
            raise ModuleNotFoundError(f"No module named {name!r}", name=name)
        return None

sys.meta_path.insert(0, NoProtobuf())
sys.argv = sys.argv[1:]
runpy.run_path(sys.argv[0], run_name="__main__")
"""


def test_without_protobuf_the_example_says_what_to_install() -> None:
    done = subprocess.run(
        [sys.executable, "-c", _WITHOUT_PROTOBUF, str(EXAMPLE), "--port", "9"],
        capture_output=True,
        text=True,
        env=python_env(),
        timeout=LIMIT,
        check=False,
    )
    assert done.returncode == 1, done.stderr
    assert done.stderr.strip() == (
        "error: pushlearn needs the protobuf package (4.21 or newer, as "
        "pyproject.toml says): python3 -m pip install 'protobuf>=4.21'"
    )


CURVE = REPO_ROOT / "examples" / "python" / "curve.py"


def test_the_curve_example_runs_the_knn_baseline_and_draws_its_curve(
    tmp_path: Path,
) -> None:
    """examples/python/curve.py, reduced: two training settings, two folds."""
    done = subprocess.run(
        [
            sys.executable,
            str(CURVE),
            "--train-runs",
            "1,3",
            "--folds",
            "2",
            "--out",
            str(tmp_path),
        ],
        capture_output=True,
        text=True,
        env=python_env(),
        timeout=4 * LIMIT,
        check=False,
    )
    assert done.returncode == 0, done.stderr
    figure = tmp_path / "learning-curve.png"
    assert done.stdout.strip().endswith(f"wrote {figure}")
    assert figure.read_bytes().startswith(b"\x89PNG\r\n\x1a\n")
    # The printed learning curve: a row per N, ours beside the thesis's.
    rows = [
        line.split()
        for line in done.stdout.splitlines()
        if line.strip()[:2] in ("1 ", "3 ")
    ]
    assert [row[0] for row in rows[:2]] == ["1", "3"], done.stdout
