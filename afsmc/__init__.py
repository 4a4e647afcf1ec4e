"""afsmc: a compiler for autonomous probabilistic finite-state machines.

The Python API (afsmc.api) is here at the top: ``afsmc.load(path_or_text)`` returns a
:class:`Mission` to check, compile, verify, sweep, simulate and draw; failures raise
:class:`AfsmError`. It is imported on first use, so that `python -m afsmc` and the
pipeline's own modules do not pay for it.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

__version__ = "0.1.0"

if TYPE_CHECKING:
    from afsmc.api import (
        AfsmError,
        Conformance,
        Diagram,
        Estimates,
        Mission,
        Results,
        SimCheck,
        Sweep,
        load,
    )

__all__ = [
    "AfsmError",
    "Conformance",
    "Diagram",
    "Estimates",
    "Mission",
    "Results",
    "SimCheck",
    "Sweep",
    "__version__",
    "load",
]


def __getattr__(name: str) -> Any:
    if name in __all__ and name != "__version__":
        from afsmc import api

        return getattr(api, name)
    raise AttributeError(f"module 'afsmc' has no attribute {name!r}")
