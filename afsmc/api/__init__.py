"""The Python API for people: load a mission, check, compile, verify, sweep, simulate and
draw it, with tables (pandas) and pictures that show inline in Jupyter.

>>> import afsmc                                           # doctest: +SKIP
>>> m = afsmc.load("examples/patrol.afsm")                 # a Mission
>>> m.verify().to_pandas()                                 # one row per property
>>> m.with_consts(CELLS=6).verify(["finish"])              # afsmc verify --const CELLS=6
>>> m.sweep("ROUNDS", "1:5:1").plot()                      # a matplotlib Figure
>>> m.simulate(runs=10_000).to_pandas()
>>> m.sim_check().to_pandas()                              # `from sim` constants judged
>>> m.conform(["runs.jsonl"]).ok                           # the robot's logs against the spec
>>> m.diagram()                                            # SVG in a notebook

One module per concept: ``mission`` (:class:`Mission`, :func:`load`, compiling), ``results``
(:class:`Results` of verify), ``sweep`` (:class:`Sweep`), ``simulate``
(:class:`Estimates`), ``sim_check`` (:class:`SimCheck`), ``conform`` (:class:`Conformance`),
``diagram`` (:class:`Diagram`), ``errors`` (:class:`AfsmError`).
The API is a top layer like the CLI: the commands call into it, never the reverse.
"""

from __future__ import annotations

import importlib
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from afsmc.api.conform import Conformance
    from afsmc.api.diagram import Diagram
    from afsmc.api.errors import AfsmError
    from afsmc.api.mission import Mission, load
    from afsmc.api.results import Results
    from afsmc.api.sim_check import SimCheck
    from afsmc.api.simulate import Estimates
    from afsmc.api.sweep import Sweep

# Each name's module, imported on first use: `afsmc check` loads through afsmc.api.mission
# and need not import Graphviz, Storm's wrappers or the simulator.
_HOME = {"AfsmError": "errors", "Conformance": "conform", "Diagram": "diagram",
         "Estimates": "simulate", "Mission": "mission", "Results": "results",
         "SimCheck": "sim_check", "Sweep": "sweep", "load": "mission"}
__all__ = ["AfsmError", "Conformance", "Diagram", "Estimates", "Mission", "Results",
           "SimCheck", "Sweep", "load"]


def __getattr__(name: str) -> Any:
    if name in _HOME:
        return getattr(importlib.import_module(f"afsmc.api.{_HOME[name]}"), name)
    raise AttributeError(f"module 'afsmc.api' has no attribute {name!r}")
