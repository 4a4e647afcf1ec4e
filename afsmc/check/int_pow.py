"""An update of an integer variable does not take the value of an integer `pow` with a
negative exponent: `y := pow(2, x - 3)` is 0.25 at x = 1, which is no integer.

Storm's engines disagree on it (the sparse engine truncates the value to 0, the decision
diagram engine loses the transition), so afsmc would verify a model other than the one
written. Where the power only feeds a comparison (`pow(2, -x) > 0.1`) or a weight, its
fractional value is meant and is fine: the search stops at comparisons.
"""

from __future__ import annotations

from collections.abc import Iterator

from afsmc.check.undefined import sites
from afsmc.diagnostics import Reporter, codes
from afsmc.model import expr as E
from afsmc.model import ir
from afsmc.model.bounds import bounds
from afsmc.model.expr import Type
from afsmc.model.pretty import with_names
from afsmc.model.search import find

_NOT_ARITHMETIC = {"==", "!=", "<", "<=", ">", ">=", "&&", "||", "=>"}


def _powers(e: E.Expr) -> Iterator[E.Call]:
    """The integer powers whose value flows into `e`'s own value."""
    if isinstance(e, E.Binary) and e.op in _NOT_ARITHMETIC:
        return
    if isinstance(e, E.Ite):
        yield from _powers(e.then)
        yield from _powers(e.other)
        return
    if isinstance(e, E.Call) and e.func in ("floor", "ceil"):
        return  # rounded explicitly
    if isinstance(e, E.Call) and e.func == "pow" and e.type is Type.INT:
        yield e
    for c in E.children(e):
        yield from _powers(c)


def check_int_pow(model: ir.Model, rep: Reporter) -> None:
    show = with_names(model.display_names())
    for site in sites(model):
        if site.target is None or model.variable(site.target).type is not Type.INT:
            continue
        for p in _powers(site.inlined):
            k = p.args[1]
            if bounds(k, model)[0] >= 0:
                continue
            negative = E.Binary("<", k, E.lit(0), Type.BOOL)
            hit = next(((m, w) for m, cond in site.when.items()
                        if (w := find(model, m, E.conj(cond, negative))) is not None), None)
            if hit is None:
                continue
            var = model.variable(site.target).display
            rep.error(codes.E308, f"{show(p)} is a fraction where {show(k)} < 0, as in the state "
                      f"{hit[1]}, but {site.what} assigns it to the integer variable {var}",
                      p.span if p.span is not None else site.expr.span,
                      hint="Storm's engines disagree on such a value; keep the exponent >= 0, "
                           "or compute in doubles and round: floor(pow(2.0, ...))")
            break
