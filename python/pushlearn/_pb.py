"""The generated message modules, typed as ``Any`` for the type checker.

``pushlearn._proto.*_pb2`` build their classes at import time from the
schemas' descriptors, so a type checker cannot see the message classes;
importing them through this module keeps ``mypy --strict`` meaningful for
the rest of the package without stub files that could drift from the
schemas.
"""

from typing import Any

try:
    from ._proto import learner_pb2 as _learner_pb2
    from ._proto import pushlearn_pb2 as _pushlearn_pb2
except ModuleNotFoundError as missing:
    if missing.name is None or not missing.name.startswith("google"):
        raise
    raise ImportError(
        "pushlearn needs the protobuf package (4.21 or newer, as pyproject.toml "
        "says): python3 -m pip install 'protobuf>=4.21'"
    ) from None

learner_pb2: Any = _learner_pb2
"""``proto/learner.proto``'s messages (package ``pushlearn.learner``)."""
pushlearn_pb2: Any = _pushlearn_pb2
"""``proto/pushlearn.proto``'s messages (package ``pushlearn``)."""
