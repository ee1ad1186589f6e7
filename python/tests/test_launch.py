"""The ``pushlearn`` and ``pushlearn-sim`` console scripts (pushlearn._launch)."""

from __future__ import annotations

import subprocess
from pathlib import Path

from conftest import run_python


def launch(bin_dir: Path, script: str, *args: str) -> subprocess.CompletedProcess[str]:
    """Runs console script ``script`` (``pushlearn`` or ``pushlearn_sim``) with
    its executables in ``bin_dir``, in a child Python: it replaces its process."""
    source = (
        "import sys\n"
        "from pathlib import Path\n"
        "import pushlearn._launch as launch\n"
        f"launch.BIN_DIR = Path({str(bin_dir)!r})\n"
        f"sys.argv = ['{script}', *{list(args)!r}]\n"
        f"launch.{script}()\n"
    )
    return run_python(source)


def test_the_script_becomes_the_executable_with_its_arguments(tmp_path: Path) -> None:
    # A stand-in executable that reports its own path (what current_exe sees
    # is the file the process executes) and its arguments.
    fake = tmp_path / "pushlearn-sim"
    fake.write_text('#!/bin/sh\necho "$0" "$@"\n')
    fake.chmod(0o755)
    done = launch(tmp_path, "pushlearn_sim", "serve", "--port", "0")
    assert done.returncode == 0, done.stderr
    assert done.stdout.split() == [str(fake), "serve", "--port", "0"]


def test_a_missing_executable_is_one_clear_error(tmp_path: Path) -> None:
    done = launch(tmp_path, "pushlearn", "--help")
    assert done.returncode == 1
    assert done.stdout == ""
    assert done.stderr.startswith(
        f"error: this installation of the pushlearn package has no pushlearn executable (looked for {tmp_path / 'pushlearn'})"
    ), done.stderr
    assert "cargo build --release -p pushlearn-cli -p sim-plugin --bins" in done.stderr
