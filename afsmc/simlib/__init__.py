"""Built-in library of small-scale simulation models for abstract actions.

Specs reference an output as ``"<simulator>.<output>"`` (e.g. ``"uav.approach.duration"``);
see :mod:`afsmc.simlib.registry` and ``docs/simulation.md``.
"""

from afsmc.simlib.registry import (
    ENTRY_POINT_GROUP,
    KINDS,
    Simulator,
    UnknownSimulator,
    available,
    kind,
    lookup,
    reload,
    sample,
    simulate,
    simulators,
)

__all__ = [
    "ENTRY_POINT_GROUP",
    "KINDS",
    "Simulator",
    "UnknownSimulator",
    "available",
    "kind",
    "lookup",
    "reload",
    "sample",
    "simulate",
    "simulators",
]
