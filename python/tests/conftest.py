"""Shared fixtures: the repository's root, the binaries, a running world daemon.

The world daemon is the real ``pushlearn-sim`` binary, found as the package
finds it (:func:`pushlearn.local_world.find_sim_binary`: ``PUSHLEARN_SIM_BIN``,
the package's own, beside the running Python, ``PATH``, then
``$CARGO_TARGET_DIR/release`` or the checkout's ``target/release``; build it
with ``cargo build --release -p sim-plugin --bins``). Tests needing it are
skipped when it is missing, unless ``PUSHLEARN_REQUIRE_SIM=1`` (set it on CI)
turns the skip into a failure.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import threading
from collections.abc import Callable, Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import NoReturn

import pytest

REPO_ROOT = Path(__file__).resolve().parents[2]
"""The repository's top level (``python/tests/`` is two levels below it)."""
PYTHON_DIR = REPO_ROOT / "python"
"""The directory holding the ``pushlearn`` package."""
TESTS_DIR = Path(__file__).resolve().parent
"""This directory (holds the sample learners the subprocess tests serve)."""

LIMIT = 60.0
"""Seconds after which a child process counts as hung (the test then fails)."""


def sim_binary() -> Path | str:
    """The ``pushlearn-sim`` binary, or the message saying where it was looked for."""
    # Imported here, not at the top: collecting the tests imports no package
    # module before a test does (some replace ``pushlearn._native`` first).
    from pushlearn.local_world import SimNotFound, find_sim_binary

    try:
        return find_sim_binary()
    except SimNotFound as err:
        return str(err)


def pushlearn_binary() -> Path | None:
    """The ``pushlearn`` binary (the experiment driver), or ``None``."""
    explicit = os.environ.get("PUSHLEARN_BIN")
    if explicit:
        return Path(explicit)
    sim = sim_binary()
    candidates = [sim.parent / "pushlearn"] if isinstance(sim, Path) else []
    candidates.append(REPO_ROOT / "target" / "release" / "pushlearn")
    return next((c for c in candidates if c.is_file()), None)


def _missing(message: str) -> NoReturn:
    if os.environ.get("PUSHLEARN_REQUIRE_SIM") == "1":
        pytest.fail(message)
    pytest.skip(message)


@pytest.fixture(scope="session")
def driver_bin(sim_bin: Path) -> Path:
    """The ``pushlearn`` binary next to ``pushlearn-sim`` (or PUSHLEARN_BIN); skips like sim_bin."""
    path = pushlearn_binary()
    if path is None or not path.is_file():
        _missing(
            "pushlearn (the experiment driver) not found: build it with "
            "`cargo build --release -p pushlearn-cli --bins` or set PUSHLEARN_BIN"
        )
    assert path is not None
    return path


@pytest.fixture(scope="session")
def sim_bin() -> Path:
    """The ``pushlearn-sim`` binary (skips, or fails with PUSHLEARN_REQUIRE_SIM=1, if missing)."""
    path = sim_binary()
    if isinstance(path, str):
        _missing(path)
    return path


def python_env() -> dict[str, str]:
    """The environment for a child Python that must import this checkout's package."""
    env = dict(os.environ)
    import pushlearn

    # The package the tests import: the installed one (with its native
    # module) or, run from the source tree, python/ itself.
    package_root = Path(pushlearn.__file__).resolve().parents[1]
    paths = [str(package_root), str(TESTS_DIR)]
    if env.get("PYTHONPATH"):
        paths.append(env["PYTHONPATH"])
    env["PYTHONPATH"] = os.pathsep.join(paths)
    env["PYTHONDONTWRITEBYTECODE"] = "1"
    return env


def run_python(
    source: str, *, cwd: Path | None = None, timeout: float = LIMIT
) -> subprocess.CompletedProcess[str]:
    """Runs ``source`` as its own Python process, as a reader pasting it would."""
    return subprocess.run(
        [sys.executable, "-c", source],
        capture_output=True,
        text=True,
        env=python_env(),
        cwd=cwd,
        timeout=timeout,
        check=False,
    )


@dataclass
class Background:
    """A child process started by a test, killed by pid when the test ends."""

    process: subprocess.Popen[bytes]
    first_line: str
    log_path: Path

    @property
    def pid(self) -> int:
        """The child's process id."""
        return self.process.pid

    def log(self) -> str:
        """What the child wrote to stderr so far."""
        return self.log_path.read_text(errors="replace")

    def stop(self) -> None:
        """Kills the child (by its pid) and waits for it."""
        if self.process.poll() is None:
            self.process.kill()
        self.process.wait(timeout=LIMIT)


def start_background(
    argv: list[str], log_path: Path, env: dict[str, str] | None = None
) -> Background:
    """Starts ``argv`` and waits (at most :data:`LIMIT` s) for the first line on its stdout.

    Its stderr goes to ``log_path``; its stdout is drained after the first
    line so that the child never blocks on a full pipe.
    """
    log = log_path.open("wb")
    process = subprocess.Popen(
        argv, stdin=subprocess.DEVNULL, stdout=subprocess.PIPE, stderr=log, env=env
    )
    log.close()
    assert process.stdout is not None
    stdout = process.stdout
    lines: list[str] = []
    got_line = threading.Event()

    def drain() -> None:
        lines.append(stdout.readline().decode(errors="replace"))
        got_line.set()
        while stdout.read(65536):
            pass

    threading.Thread(target=drain, daemon=True).start()
    child = Background(process, "", log_path)
    if not got_line.wait(LIMIT):
        child.stop()
        pytest.fail(f"{argv} printed nothing within {LIMIT} s; its log:\n{child.log()}")
    child.first_line = lines[0]
    return child


def listening_port(child: Background) -> int:
    """The port of a ``listening on HOST:PORT`` first line; fails the test otherwise."""
    line = child.first_line.strip()
    if not line.startswith("listening on "):
        child.stop()
        pytest.fail(
            f"expected 'listening on HOST:PORT', got {line!r}; log:\n{child.log()}"
        )
    return int(line.rsplit(":", 1)[1])


@dataclass
class Daemon:
    """A running ``pushlearn-sim serve`` on a free port."""

    child: Background
    port: int


@pytest.fixture
def start_sim(sim_bin: Path, tmp_path: Path) -> Iterator[Callable[..., Daemon]]:
    """A function starting ``pushlearn-sim serve --port 0 ARGS...``; every daemon is
    killed by pid when the test ends (its log is printed if the test failed)."""
    started: list[Daemon] = []

    def start(*args: str) -> Daemon:
        log_path = tmp_path / f"pushlearn-sim-{len(started)}.log"
        child = start_background(
            [str(sim_bin), "serve", "--port", "0", *args], log_path
        )
        daemon = Daemon(child, listening_port(child))
        started.append(daemon)
        return daemon

    yield start
    for daemon in started:
        daemon.child.stop()
        sys.stderr.write(daemon.child.log()[-4000:])


def sweep_centre(sim_bin: Path) -> list[str]:
    """The calibration sweep's run from x0 = 0, to 4 decimals."""
    done = subprocess.run(
        [str(sim_bin), "sweep", "--json"],
        capture_output=True,
        timeout=LIMIT,
        check=True,
    )
    rows = json.loads(done.stdout)
    centre = next(row for row in rows if row["x0"] == 0.0)
    return [f"{centre[key]:.4f}" for key in ("block_x", "block_y", "block_yaw")]
