"""``python -m pushlearn.serve MODULE:CLASS [--listen HOST:PORT] [LEARNER ARGS...]``.

Serves a learner over the learner protocol: on stdin/stdout (how the
experiment driver runs it, ``pushlearn experiment push-task --learner
"python -m pushlearn.serve mymodule:MyLearner"``), or, with ``--listen``, as
a TCP daemon giving every connection a fresh learner (it prints
``listening on HOST:PORT`` to stdout once bound; port 0 picks a free one).

``MODULE`` is an importable module (the current directory is on the path)
or a ``.py`` file; ``CLASS`` a :class:`pushlearn.Learner` subclass or a
function returning a learner. The arguments after ``MODULE:CLASS`` (and
after this command's own options, which may come right after it; ``--``
ends them) go to the class's ``from_args(argv)``.

Exit status: 0 when the driver ended the session, 1 after a learner error,
2 for a command line that cannot be used.
"""

from __future__ import annotations

import importlib
import importlib.util
import os
import sys
import traceback
from collections.abc import Callable
from pathlib import Path
from typing import Any

from .learner import Learner, UsageError, serve, serve_tcp

__all__ = ["load_factory", "main", "parse_listen"]

USAGE = "usage: python -m pushlearn.serve MODULE:CLASS [--listen HOST:PORT] [LEARNER ARGS...]"


def parse_listen(text: str) -> tuple[str, int]:
    """``HOST:PORT`` (``[HOST]:PORT`` for IPv6) as ``(host, port)``; ``UsageError`` if malformed."""
    host, sep, port_text = text.rpartition(":")
    if not sep or not host:
        raise UsageError(f"--listen needs HOST:PORT, got {text!r}")
    if host.startswith("[") and host.endswith("]"):
        host = host[1:-1]
    try:
        port = int(port_text)
    except ValueError:
        raise UsageError(f"--listen: {port_text!r} is not a port number") from None
    if not 0 <= port <= 65535:
        raise UsageError(f"--listen: port {port} is not in 0 … 65535")
    return host, port


def _import(module_name: str) -> Any:
    if module_name.endswith(".py"):
        path = Path(module_name)
        if not path.is_file():
            raise UsageError(f"{module_name}: no such file")
        spec = importlib.util.spec_from_file_location(path.stem, path)
        if spec is None or spec.loader is None:
            raise UsageError(f"{module_name}: cannot be loaded as a Python module")
        module = importlib.util.module_from_spec(spec)
        sys.modules[path.stem] = module
        spec.loader.exec_module(module)
        return module
    try:
        return importlib.import_module(module_name)
    except ModuleNotFoundError as err:
        if err.name is not None and (
            module_name == err.name or module_name.startswith(err.name + ".")
        ):
            raise UsageError(
                f"cannot import {module_name!r}: no module named {err.name!r} (is its directory "
                f"the current one, or on PYTHONPATH?)"
            ) from None
        raise


def load_factory(spec: str, argv: list[str]) -> Callable[[], Learner]:
    """Imports ``MODULE:CLASS`` and returns a function making the learner from ``argv``.

    A wrong name raises :class:`UsageError` here; the options are parsed
    (and can raise it) each time the function makes a learner.
    """
    module_name, sep, attribute = spec.partition(":")
    if not sep or not module_name or not attribute:
        raise UsageError(f"the learner must be given as MODULE:CLASS, got {spec!r}")
    module = _import(module_name)
    target: Any = module
    for part in attribute.split("."):
        try:
            target = getattr(target, part)
        except AttributeError:
            raise UsageError(
                f"module {module_name!r} has no attribute {attribute!r}"
            ) from None
    if isinstance(target, type) and issubclass(target, Learner):
        cls = target
        return lambda: cls.from_args(list(argv))
    if isinstance(target, type):
        raise UsageError(
            f"{spec} is the class {target.__name__}, not a pushlearn.Learner subclass"
        )
    if not callable(target):
        raise UsageError(
            f"{spec} is a {type(target).__name__}, not a Learner class or factory"
        )
    if argv:
        raise UsageError(
            f"{spec} is a function, which takes no command-line arguments (got {' '.join(argv)})"
        )
    function = target

    def make() -> Learner:
        learner = function()
        if not isinstance(learner, Learner):
            raise TypeError(
                f"{spec}() returned {type(learner).__name__}, not a pushlearn.Learner"
            )
        return learner

    return make


def _split(argv: list[str]) -> tuple[str, str | None, list[str]]:
    """(MODULE:CLASS, --listen value, learner arguments)."""
    listen: str | None = None
    spec: str | None = None
    rest: list[str] = []
    i = 0
    while i < len(argv):
        arg = argv[i]
        if arg in ("-h", "--help") and not rest:
            raise SystemExit(_help())
        if arg == "--":
            rest.extend(argv[i + 1 :])
            break
        if arg == "--listen" or arg.startswith("--listen="):
            if arg == "--listen":
                if i + 1 >= len(argv):
                    raise UsageError("--listen needs HOST:PORT")
                listen = argv[i + 1]
                i += 2
            else:
                listen = arg.split("=", 1)[1]
                i += 1
            continue
        if spec is None and not arg.startswith("-"):
            spec = arg
            i += 1
            continue
        if spec is None:
            raise UsageError(f"unknown option {arg!r} before MODULE:CLASS")
        rest.extend(argv[i:])
        break
    if spec is None:
        raise UsageError("no learner given (MODULE:CLASS)")
    return spec, listen, rest


def _help() -> int:
    print(USAGE)
    print()
    print(__doc__.split("\n\n", 1)[1].strip())
    return 0


def _raising(error: BaseException) -> Callable[[], Learner]:
    def make() -> Learner:
        raise error

    return make


def main(argv: list[str] | None = None) -> int:
    """Runs the command line ``argv`` (default ``sys.argv[1:]``); returns the exit status.

    The learner is made once before serving, so that a wrong option exits at
    once with status 2. On stdin/stdout that learner is the one served; if
    making it fails otherwise, the error is logged and also sent to the
    driver as the answer to its Start (status 1). With ``--listen`` it is
    only a trial: every connection gets a fresh learner.
    """
    args = list(sys.argv[1:] if argv is None else argv)
    try:
        spec, listen, rest = _split(args)
        address = parse_listen(listen) if listen is not None else None
        if "" not in sys.path and os.getcwd() not in sys.path:
            sys.path.insert(0, os.getcwd())
        factory = load_factory(spec, rest)
    except UsageError as err:
        print(f"pushlearn.serve: {err}\n{USAGE}", file=sys.stderr)
        return 2
    except Exception:  # noqa: BLE001  (the user's module failed: show where)
        print(f"pushlearn.serve: importing {spec} failed:", file=sys.stderr)
        traceback.print_exc(file=sys.stderr)
        return 1
    try:
        learner = factory()
    except UsageError as err:
        print(f"pushlearn.serve: {err}\n{USAGE}", file=sys.stderr)
        return 2
    except Exception as err:  # noqa: BLE001  (reported, and sent to the driver)
        print(
            f"pushlearn.serve: cannot make the learner {spec}: {type(err).__name__}: {err}",
            file=sys.stderr,
        )
        if address is not None:
            return 1
        serve(_raising(err))  # the driver learns why, in the answer to its Start
        return 1
    if address is None:
        return serve(learner)
    try:
        serve_tcp(factory, *address)
    except OSError as err:
        print(
            f"pushlearn.serve: cannot listen on {listen}: {err.strerror or err}",
            file=sys.stderr,
        )
        return 1
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
