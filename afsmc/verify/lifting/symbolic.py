"""Which branch probabilities parameter lifting may take: those multilinear in the
interval probabilities (degree at most 1 in each, state or not).

Why it matters. On a box, a multilinear function reaches its extremes at the box's
corners, and it is the multilinear interpolation of its values there. So the explorer
needs each branch's values at the whole box's corners only (afsmc.verify.lifting.model);
its value anywhere, and each state's lifted extreme over a sub-box, follow from them
exactly. afsmc's probabilities are of this form (`P`, `1 - P`, a hazard's `P * (1 - Q)`);
one of another form (`P * P`, `pow(P, n)`, `min(P, x)`, `x / P`) is refused, and Storm's
parametric engine bounds the mission instead.
"""

from __future__ import annotations

from collections.abc import Set

from afsmc.model import expr as E

Degrees = dict[str, int]

_LINEAR = {"+", "-"}
_LOGICAL = {"==", "!=", "<", "<=", ">", ">=", "&&", "||", "=>"}


def degrees(e: E.Expr, params: Set[str]) -> Degrees | None:
    """The degree of `e` (formulas inlined) in each parameter it reads, or None where it
    is no polynomial in them (a parameter under a function, a comparison, a divisor)."""
    if isinstance(e, E.ConstRef):
        return {e.name: 1} if e.name in params else {}
    if isinstance(e, E.Unary):
        inner = degrees(e.operand, params)
        return inner if e.op == "-" or inner == {} else None
    if isinstance(e, E.Binary):
        left, right = degrees(e.left, params), degrees(e.right, params)
        if left is None or right is None:
            return None
        if e.op in _LINEAR:
            return {k: max(left.get(k, 0), right.get(k, 0)) for k in left | right}
        if e.op == "*":
            return {k: left.get(k, 0) + right.get(k, 0) for k in left | right}
        if e.op == "/" or e.op in _LOGICAL:
            return left if not right and (e.op == "/" or not left) else None
        return None
    if isinstance(e, E.Ite):
        cond, a, b = (degrees(x, params) for x in (e.cond, e.then, e.other))
        if cond != {} or a is None or b is None:
            return None
        return {k: max(a.get(k, 0), b.get(k, 0)) for k in a | b}
    parts = [degrees(x, params) for x in E.children(e)]
    return {} if all(p == {} for p in parts) else None


def multilinear(e: E.Expr, params: Set[str]) -> bool:
    """Whether `e` is a polynomial of degree at most 1 in each parameter."""
    d = degrees(e, params)
    return d is not None and all(k <= 1 for k in d.values())
