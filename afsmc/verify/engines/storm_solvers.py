"""How Storm solves the equation systems of a check: the `--solver` choices and the
environment of each (the sound and exact ones are afsmc.verify.plan.precision's).

These functions run inside the Storm process (afsmc.verify.engines.storm).
"""

from __future__ import annotations

from typing import Any, Literal

from afsmc.verify.plan.precision import iterative_environment

# How Storm solves the equation systems on the sparse and hybrid engines. "auto": value
# iteration on hybrid; on sparse, one exact backward pass where the model is acyclic but for
# self-loops (afsmc.verify.arrays.acyclic, reported as "acyclic"), else Storm's topological solver,
# which on a mission whose clock only grows finds one component per state (on scenario 1,
# 137 s of a 394 s query that value iteration answered in 276 s; docs/benchmarks.md).
Solver = Literal["auto", "topological", "value-iteration"]
SOLVERS: tuple[Solver, ...] = ("auto", "topological", "value-iteration")
# Value iteration stops when no value changes by more than this, relative to itself (Storm's
# 1e-6 moved values in the ninth digit; 1e-10 equals the topological solver's to ~1e-14 on
# the UAV at no measurable cost: an acyclic model converges in its longest path's steps).
VI_PRECISION = "1/10000000000"

__all__ = ["SOLVERS", "VI_PRECISION", "Solver", "solver_for", "value_iteration"]


def solver_for(solver: Solver, engine: str) -> str:
    """The method `solver` means on `engine` (after "auto" has picked one); "" for the dd
    engine, which always iterates on decision diagrams, to Storm's own precision."""
    if engine == "dd":
        return ""
    if solver == "auto":
        return "value-iteration" if engine == "hybrid" else "topological"
    return solver


def value_iteration(stormpy: Any, dd_memory_mb: int) -> Any:
    """Storm's environment for checks by value iteration (Storm's default, None, is the
    topological solver). A DTMC's equations by Storm's own iterative solver, by plain
    iteration of x = Ax + b (its "power" method), which is value iteration without the
    choice (the 5x5 UAV's uniform DTMC: 2.4-4.8 s against 4.0-10.4 s per query with the
    topological solver)."""
    return iterative_environment(stormpy, dd_memory_mb, "VALUE_ITERATION", "POWER",
                                 VI_PRECISION, relative=True)
