"""The guard of the symbolic engines without --max-states: a variable with more values
than the default state limit is refused before Storm builds anything (E420).

Storm's symbolic builder (engines dd and hybrid, and "auto" above its sparse bound)
explores breadth-first, one step per level of the state graph, and reports nothing until
it is done. A counter over a range of n values is n levels deep, so a variable of 10^9
values (`--const CELLS=1000000000`) keeps it building for hours in a few hundred MB that
the memory guard never sees grow. With --max-states the build is explicit first and
stopped at the limit (afsmc.verify.stopping); without it, a range beyond what that
default limit would allow is refused here, naming the variable, with the limit and how to
raise it.
"""

from __future__ import annotations

from afsmc.diagnostics import CompileError, Diagnostic, Severity, codes
from afsmc.model import ir


def refuse_deep(model: ir.Model, engine: str, max_states: int | None, limit: int) -> None:
    """E420 for each variable of more than `limit` values (the default --max-states) when
    a symbolic engine (`engine` after "auto" is settled for small models) would build
    without a --max-states."""
    if engine == "sparse" or max_states is not None:
        return
    deep = [v for v in model.variables if v.size > limit]
    if not deep:
        return
    raise CompileError([Diagnostic(
        codes.E420, Severity.ERROR,
        f"variable '{v.display}' has {v.size:,} values, more than the default --max-states "
        f"{limit:,}: the {engine} engine's symbolic build would take a step per value a "
        "counter reaches (hours, with no progress to watch)",
        v.span, hint=HINT) for v in deep])


HINT = ("--max-states N raises the limit: the states are then counted by an explicit build "
        "that stops at N (e.g. --max-states 2000000); or check a smaller instance with --const")
