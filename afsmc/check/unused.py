"""Declarations nothing uses are usually mistakes: report them as warnings."""

from __future__ import annotations

from afsmc.diagnostics import Reporter, codes
from afsmc.model import expr as E
from afsmc.model import ir


def _exprs(model: ir.Model) -> list[E.Expr]:
    out: list[E.Expr] = []
    for a in model.actions:
        out += [a.guard, a.weight]
        for o in a.outcomes:
            out.append(o.prob)
            out += [u.value for u in o.updates]
    for h in model.hazards:
        out.append(h.prob)
        for o in h.outcomes:
            out.append(o.prob)
            out += [u.value for u in o.updates]
    out += [f.value for f in model.formulas] + [lb.value for lb in model.labels]
    for r in model.rewards:
        out += [x for it in r.items for x in (it.guard, it.value)]
    for p in model.properties:
        path = p.path
        out += [x for x in (getattr(path, "target", None), getattr(path, "left", None),
                            getattr(path, "bound", None)) if x is not None]
    return out


def check_unused(model: ir.Model, rep: Reporter, used_names: frozenset[str] = frozenset()) -> None:
    """W303/W304. `used_names`: what the source refers to where the IR keeps no reference
    (a constant's value, a variable's range), `Resolved.used_names`."""
    read: set[str] = set(used_names)
    for e in _exprs(model):
        for n in E.walk(e):
            if isinstance(n, (E.VarRef, E.ConstRef, E.FormulaRef)):
                read.add(n.name)
    for v in model.variables:
        if v.name not in read:
            rep.warning(codes.W303, f"variable {v.display} is never read", v.span,
                        hint="it only multiplies the state space; remove it or use it")
    for c in model.constants:
        if c.name not in read and not c.is_param:
            rep.warning(codes.W304, f"constant {c.name} is never used", c.span)
    for f in model.formulas:
        if f.name not in read:
            rep.warning(codes.W304, f"formula {f.name} is never used", f.span)
