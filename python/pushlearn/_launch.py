"""The ``pushlearn`` and ``pushlearn-sim`` console scripts: the executables the wheel carries.

The wheel puts the two Rust executables into ``pushlearn/_bin/``
(``build_backend/pushlearn_build.py``); the console scripts pip writes
onto PATH call :func:`pushlearn` and :func:`pushlearn_sim`, which *replace*
this Python process by the executable (``os.execv``), not start a child.
That matters: the command line starts its worker processes and finds
``pushlearn-sim`` through its own path (``current_exe``), which must be the
real executable inside ``_bin/``, not Python; and a signal sent to the
script's process id (a ``LocalWorld`` stopping its world) reaches the
executable itself.
"""

from __future__ import annotations

import os
import sys
from pathlib import Path
from typing import NoReturn

BIN_DIR = Path(__file__).resolve().parent / "_bin"
"""Where a wheel's executables are."""


def packaged(name: str) -> Path:
    """The path of the executable ``name`` in this installation (it may not exist)."""
    return BIN_DIR / name


def _exec(name: str) -> NoReturn:
    binary = packaged(name)
    if not binary.is_file():
        sys.stderr.write(
            f"error: this installation of the pushlearn package has no {name} "
            f"executable (looked for {binary})\n"
            "hint: a wheel built with `pip wheel .` or `pip install .` carries it; "
            "an editable install does not: run "
            "`cargo build --release -p pushlearn-cli -p sim-plugin --bins` in the "
            f"repository and use target/release/{name}\n"
        )
        raise SystemExit(1)
    try:
        os.execv(binary, [str(binary), *sys.argv[1:]])
    except OSError as err:
        sys.stderr.write(f"error: cannot run {binary}: {err}\n")
        raise SystemExit(1) from err


def pushlearn() -> NoReturn:
    """The ``pushlearn`` console script."""
    _exec("pushlearn")


def pushlearn_sim() -> NoReturn:
    """The ``pushlearn-sim`` console script."""
    _exec("pushlearn-sim")
