"""E310: no expression nests deeper, once its formulas are inlined, than Storm evaluates.

Storm compiles the expressions of a model for its explicit builder with ExprTk, which
stops at a stack depth of 10,000, about two per level of nesting: a label `x + x + ... > 100`
with 4,998 `+` fails to build (E403) through PRISM and JANI, and a guard with 4,997 through
JANI, though the parser takes 5,000 levels (E113). afsmc's output inlines formulas, so a
short expression that uses a deep formula nests as deeply as both together.
"""

from __future__ import annotations

from afsmc.check.undefined import sites
from afsmc.diagnostics import Reporter, codes
from afsmc.model import expr as E
from afsmc.model import ir

# Below every failure measured (4,997 levels): the lowering adds a few levels to a guard
# (the weight comparisons of the mode's other actions, one per action).
STORM_DEPTH = 4_900


def check_storm_depth(model: ir.Model, rep: Reporter) -> None:
    inlined: dict[str, int] = {}

    def formula_depth(name: str) -> int:
        if name not in inlined:
            inlined[name] = E.depth(model.formula(name).value, formula_depth)
        return inlined[name]

    seen: set[tuple[str, object]] = set()
    for site in sites(model):
        d = E.depth(site.expr, formula_depth)
        key = (site.what, site.expr.span)
        if d <= STORM_DEPTH or key in seen:
            continue
        seen.add(key)
        uses = any(isinstance(n, E.FormulaRef) for n in E.walk(site.expr))
        rep.error(codes.E310, f"{site.what} nests {d:,} levels deep"
                  f"{' once its formulas are inlined' if uses else ''}; Storm evaluates at "
                  f"most {STORM_DEPTH:,}", site.expr.span,
                  hint="shorten it or the formulas it uses (each operator of a chain like "
                       "'a + b + c' is one level); Storm's expression evaluator stops at "
                       "a stack depth of 10,000, two per level")
