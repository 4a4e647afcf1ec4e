"""The guard of the builds that no state limit stops (the symbolic engines without
--max-states, `diagram --reach` without it, `regions`' parametric build): a variable with
more values than the default state limit is refused before Storm builds anything (E420).

Storm's symbolic builder (engines dd and hybrid, and "auto" above its sparse bound)
explores breadth-first, one step per level of the state graph, and reports nothing until
it is done. A counter over a range of n values is n levels deep, so a counter of 10^9
values (`--const CELLS=1000000000`) keeps it building for hours in a few hundred MB that
the memory guard never sees grow. With --max-states the build is explicit first and
stopped at the limit (afsmc.verify.engines.stopping); without it, a range beyond what that
default limit would allow is refused here, naming the variable, with the limit and how to
raise it.
"""

from __future__ import annotations

from afsmc.diagnostics import CompileError, Diagnostic, Severity, codes
from afsmc.lower.lowering import Lowered
from afsmc.model import expr as E


def refuse_deep(low: Lowered, engine: str, max_states: int | None, limit: int) -> None:
    """E420 for each variable of more than `limit` values (the default --max-states) that
    an update sets to a value computed from the state (a counter: `x += 1`), when a
    symbolic engine (`engine` once "auto" is settled for small models) would build `low`
    without a --max-states. A variable no update changes, or sets only to numbers, takes
    few values however wide its range."""
    if engine == "sparse" or max_states is not None:
        return
    _refuse(low, limit, f"the {engine} engine's symbolic build would take a step per value a "
            "counter reaches (hours, with no progress to watch)", HINT)


def refuse_deep_build(low: Lowered, what: str, limit: int, hint: str,
                      limit_name: str = "the default --max-states") -> None:
    """E420 for each such counter (see refuse_deep) before a build that no --max-states
    stops: `diagram --reach` without one, and `regions`' parametric build, which has none.
    Storm's explicit builder would go through the counter's values for as long as the memory
    holds them, growing slowly (a chain adds a state or two per value) before any guard trips."""
    _refuse(low, limit, f"{what} would go through every value a counter reaches before "
            "any limit stops it (hours on a long chain)", hint, limit_name)


def _refuse(low: Lowered, limit: int, why: str, hint: str,
            limit_name: str = "the default --max-states") -> None:
    wide = {v.name: v for v in low.model.variables if v.size > limit}
    computed = {var for c in low.commands for b in c.branches for var, value in b.updates
                if var in wide and not isinstance(value, E.Lit)}
    deep = [v for name, v in wide.items() if name in computed]
    if not deep:
        return
    raise CompileError([Diagnostic(
        codes.E420, Severity.ERROR,
        f"variable '{v.display}' has {v.size:,} values, more than {limit_name} "
        f"{limit:,}: {why}", v.span, hint=hint) for v in deep])


HINT = ("--max-states N raises the limit: the states are then counted by an explicit build "
        "that stops at N (e.g. --max-states 2000000); or check a smaller instance with --const")
