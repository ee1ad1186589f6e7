"""pushlearn's PEP 517 build backend: maturin's, with the two executables inside.

The wheel carries the ``pushlearn`` and ``pushlearn-sim`` executables as
well as the extension module, so that ``pip install`` of one wheel gives
the command line and the world daemon, with no Rust toolchain on the
installing machine. Before maturin builds the wheel, :func:`build_wheel`
runs ``cargo build --release --locked -p pushlearn-cli -p sim-plugin
--bins`` (the command ``scripts/test.sh`` and the README run, so that after
them it builds nothing) and copies the two executables into
``python/pushlearn/_bin/`` (not in git), which ``[tool.maturin] include``
puts into the wheel; ``pushlearn._launch`` (the console scripts) executes
them. Everything else is maturin's backend, unchanged.

An editable install (``pip install -e .``) stages nothing: its package is the
source tree, and the console scripts say where to build the executables.
"""

from __future__ import annotations

import json
import shutil
import subprocess
import sys
from collections.abc import Mapping
from pathlib import Path
from typing import Any

import maturin
from maturin import (
    build_editable,
    build_sdist,
    get_requires_for_build_editable,
    get_requires_for_build_sdist,
    get_requires_for_build_wheel,
    prepare_metadata_for_build_editable,
    prepare_metadata_for_build_wheel,
)

__all__ = [
    "build_editable",
    "build_sdist",
    "build_wheel",
    "get_requires_for_build_editable",
    "get_requires_for_build_sdist",
    "get_requires_for_build_wheel",
    "prepare_metadata_for_build_editable",
    "prepare_metadata_for_build_wheel",
]

EXECUTABLES = ("pushlearn", "pushlearn-sim")
"""The executables the wheel carries, as cargo names them."""

CARGO_BUILD = [
    "cargo",
    "build",
    "--release",
    "--locked",
    "-p",
    "pushlearn-cli",
    "-p",
    "sim-plugin",
    "--bins",
]
"""The command line of scripts/test.sh and the README: the same features, so
that after either of them the build is a no-op."""

ROOT = Path(__file__).resolve().parent.parent
"""The repository's root (pyproject.toml's folder)."""

STAGE = ROOT / "python" / "pushlearn" / "_bin"
"""Where the executables are copied for maturin's ``include``."""


class BuildError(RuntimeError):
    """The executables could not be built or found; the message says which and why."""


def built_executables() -> dict[str, Path]:
    """Runs cargo and returns each executable's path, as cargo reports it.

    The paths come from cargo's JSON messages, not from a guessed
    ``target/release``: ``CARGO_TARGET_DIR`` and cargo's configuration move
    the target folder, and cargo knows where it put them.
    """
    command = [*CARGO_BUILD, "--message-format=json-render-diagnostics"]
    print(f"pushlearn build: running `{' '.join(CARGO_BUILD)}`", flush=True)
    try:
        # Diagnostics and progress go to stderr, as cargo prints them; stdout
        # carries the JSON messages only.
        done = subprocess.run(
            command, cwd=ROOT, stdout=subprocess.PIPE, text=True, check=False
        )
    except FileNotFoundError as err:
        raise BuildError(
            "cannot run cargo, which builds the `pushlearn` and `pushlearn-sim` "
            f"executables the wheel carries ({err}): install the Rust toolchain "
            "and put cargo on PATH"
        ) from err
    if done.returncode != 0:
        raise BuildError(
            f"`{' '.join(CARGO_BUILD)}` failed with exit status {done.returncode} "
            "(its errors are above): the wheel needs the `pushlearn` and "
            "`pushlearn-sim` executables"
        )
    found: dict[str, Path] = {}
    for line in done.stdout.splitlines():
        try:
            message = json.loads(line)
        except json.JSONDecodeError:
            continue  # not a message (a build script's stray output)
        if not isinstance(message, dict):
            continue
        executable = message.get("executable")
        target = message.get("target")
        if (
            message.get("reason") == "compiler-artifact"
            and isinstance(executable, str)
            and isinstance(target, dict)
            and target.get("name") in EXECUTABLES
        ):
            found[str(target["name"])] = Path(executable)
    missing = [name for name in EXECUTABLES if name not in found]
    if missing:
        raise BuildError(
            f"`{' '.join(CARGO_BUILD)}` succeeded but reported no executable "
            f"named {', '.join(missing)}: has a binary target been renamed?"
        )
    return found


def stage_executables() -> None:
    """Builds the executables and copies them into :data:`STAGE`, replacing what was there."""
    executables = built_executables()
    if STAGE.exists():
        shutil.rmtree(STAGE)
    STAGE.mkdir(parents=True)
    for name, source in executables.items():
        # copy2 keeps the mode: the executable bit is what maturin records
        # in the wheel, and what pip restores on install.
        shutil.copy2(source, STAGE / name)
        print(f"pushlearn build: staged {source} as {STAGE / name}", flush=True)


def build_wheel(
    wheel_directory: str,
    config_settings: Mapping[str, Any] | None = None,
    metadata_directory: str | None = None,
) -> str:
    """maturin's ``build_wheel``, after :func:`stage_executables`."""
    try:
        stage_executables()
    except BuildError as err:
        sys.stderr.write(f"error: {err}\n")
        sys.exit(1)
    return str(
        maturin.build_wheel(wheel_directory, config_settings, metadata_directory)
    )
