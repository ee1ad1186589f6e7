"""A world of one's own: ``pushlearn-sim`` started as a child process.

::

    from pushlearn.local_world import LocalWorld

    with LocalWorld(latency_max=2) as world:       # lock-step, on a free loopback port
        client = world.connect()                   # a SimClient
        ...

The binary is found by :func:`find_sim_binary`, in the order every lookup
of it follows (the command line's too; ``docs/simulator.md``, "Where
pushlearn-sim is found"): the ``sim_bin`` argument, the environment variable
``PUSHLEARN_SIM_BIN``, beside the running program (the one the package
carries, ``pushlearn/_bin/``, in an installed wheel: the world built with
the extension; then next to the running Python, a virtual environment's
``bin/``), on ``PATH``, and last the build of the checkout the native
extension was built from (``$CARGO_TARGET_DIR/release/`` if that is set,
else its ``target/release/``: for an editable install, after ``cargo build
--release``).

The world never outlives its owner: :meth:`LocalWorld.close` (idempotent)
stops it with SIGTERM, and SIGKILL if it does not stop within 5 s; garbage
collection and the interpreter's exit call it; and the world is started with
``--stop-with-stdin`` and a pipe as its standard input, whose end closes
when this process ends in any way, SIGKILL included, so that the world
stops itself.
"""

from __future__ import annotations

import os
import select
import shutil
import subprocess
import sys
import tempfile
import time
import weakref
from pathlib import Path
from types import TracebackType
from typing import IO, Any, Self

from ._launch import packaged
from .sim import SimClient

__all__ = ["LocalWorld", "SimNotFound", "find_sim_binary"]

SIM_BIN = "pushlearn-sim"
"""The world daemon's executable name."""

_LISTENING = "listening on "
_STOP_WAIT = 5.0


class SimNotFound(FileNotFoundError):
    """No ``pushlearn-sim`` binary where one was looked for; the message says where and how to build it."""


def _checkout_binary() -> Path | None:
    """The binary cargo builds in the checkout the extension was built from."""
    try:
        from . import native

        checkout = native().SOURCE_CHECKOUT
    except (ImportError, AttributeError):
        return None
    target = os.environ.get("CARGO_TARGET_DIR")
    target_dir = Path(target) if target else Path(checkout).resolve() / "target"
    return target_dir / "release" / SIM_BIN


def find_sim_binary(explicit: str | os.PathLike[str] | None = None) -> Path:
    """The ``pushlearn-sim`` to run (see the module documentation for the order).

    Raises :class:`SimNotFound` naming every place looked in.
    """
    if explicit is not None:
        path = Path(explicit)
        if not path.is_file():
            raise SimNotFound(f"pushlearn-sim not found: {path} is not a file")
        return path
    from_env = os.environ.get("PUSHLEARN_SIM_BIN")
    if from_env:
        path = Path(from_env)
        if not path.is_file():
            raise SimNotFound(
                f"pushlearn-sim not found: PUSHLEARN_SIM_BIN is {from_env}, which is not a file"
            )
        return path
    carried = packaged(SIM_BIN)
    if carried.is_file():
        return carried
    beside = Path(sys.executable).parent / SIM_BIN
    looked = [str(carried), str(beside), "PATH"]
    if beside.is_file():
        return beside
    on_path = shutil.which(SIM_BIN)
    if on_path is not None:
        return Path(on_path)
    checkout = _checkout_binary()
    if checkout is not None:
        if checkout.is_file():
            return checkout
        looked.append(str(checkout))
    raise SimNotFound(
        f"pushlearn-sim not found (looked in {', '.join(looked)}): build it with "
        "`cargo build --release -p sim-plugin --bins` in the repository, then put "
        "target/release on PATH or set PUSHLEARN_SIM_BIN"
    )


def _stop(process: subprocess.Popen[bytes], files: tuple[IO[Any], ...]) -> None:
    """Stops the world (SIGTERM, then SIGKILL) and closes its pipes; safe to call twice."""
    if process.poll() is None:
        process.terminate()
        try:
            process.wait(_STOP_WAIT)
        except subprocess.TimeoutExpired:
            process.kill()
            process.wait()
    for file in files:
        file.close()


class LocalWorld:
    """A ``pushlearn-sim serve`` child process on a free port of 127.0.0.1.

    ``scene`` is a built-in scene name or a scene file, ``mode``
    ``"lockstep"`` (default) or ``"realtime"``, ``latency_max`` the lock-step
    latency emulation's largest delay in steps (``None``: none), ``rate`` the
    publish rate in Hz (``None``: the scene's). Raises :class:`SimNotFound`
    when there is no binary and ``RuntimeError`` with the world's own
    message when it does not start.
    """

    def __init__(
        self,
        *,
        scene: str = "one_block",
        mode: str = "lockstep",
        latency_max: int | None = None,
        rate: int | None = None,
        sim_bin: str | os.PathLike[str] | None = None,
        start_timeout: float = 30.0,
    ) -> None:
        binary = find_sim_binary(sim_bin)
        command = [str(binary), "serve", "--port", "0", "--stop-with-stdin"]
        command += ["--scene", scene, "--mode", mode]
        if latency_max is not None:
            command += ["--latency-max", str(latency_max)]
        if rate is not None:
            command += ["--rate", str(rate)]
        self.command = command
        """The command line the world runs with."""
        # The world's log, for the message when it does not start; open as
        # long as the world runs, closed by _stop.
        log = tempfile.TemporaryFile()  # noqa: SIM115
        process = subprocess.Popen(
            command,
            stdin=subprocess.PIPE,
            stdout=subprocess.PIPE,
            stderr=log,
            # A Ctrl-C in a terminal goes to the whole foreground group; the
            # owner decides when its world stops (close, or its stdin).
            start_new_session=True,
        )
        assert process.stdin is not None and process.stdout is not None
        files: tuple[IO[Any], ...] = (process.stdin, process.stdout, log)
        self._process = process
        self._finalizer = weakref.finalize(self, _stop, process, files)
        try:
            line = _first_line(process, binary.name, start_timeout)
        except BaseException:
            self.close()
            raise
        if not line.startswith(_LISTENING):
            # Its last words, once it has ended (close waits for that).
            _stop(process, ())
            log.seek(0)
            text = log.read().decode(errors="replace").strip()
            self.close()
            raise RuntimeError(
                f"{' '.join(command)} did not start: "
                + (text.splitlines()[-1] if text else f"it printed {line!r}")
            )
        host, _, port = line[len(_LISTENING) :].strip().rpartition(":")
        self.host = host.strip("[]")
        """The world's host (127.0.0.1)."""
        self.port = int(port)
        """The world's port."""

    @property
    def address(self) -> str:
        """``HOST:PORT``."""
        return f"{self.host}:{self.port}"

    @property
    def pid(self) -> int:
        """The world process's id."""
        return self._process.pid

    @property
    def running(self) -> bool:
        """Whether the world process is still running."""
        return self._process.poll() is None

    def connect(self, timeout: float | None = 10.0, **kwargs: Any) -> SimClient:
        """A :class:`~pushlearn.SimClient` connected to this world."""
        return SimClient.connect(self.host, self.port, timeout, **kwargs)

    def close(self) -> None:
        """Stops the world and waits for it; does nothing the second time."""
        self._finalizer()

    def __enter__(self) -> Self:
        return self

    def __exit__(
        self,
        exc_type: type[BaseException] | None,
        exc: BaseException | None,
        tb: TracebackType | None,
    ) -> None:
        self.close()

    def __repr__(self) -> str:
        state = "running" if self.running else "stopped"
        return f"LocalWorld(pid {self.pid}, {self.address}, {state})"


def _first_line(process: subprocess.Popen[bytes], name: str, timeout: float) -> str:
    """The world's first line on stdout, or what there is when it exits or the time is up."""
    assert process.stdout is not None
    fd = process.stdout.fileno()
    deadline = time.monotonic() + timeout
    data = b""
    while b"\n" not in data:
        left = deadline - time.monotonic()
        if left <= 0:
            raise TimeoutError(f"{name} printed no address within {timeout:g} s")
        ready, _, _ = select.select([fd], [], [], left)
        if ready:
            chunk = os.read(fd, 4096)
            if not chunk:
                break
            data += chunk
    return data.decode(errors="replace").split("\n", 1)[0]
