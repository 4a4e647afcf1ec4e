"""Conservative bounds of expressions over all states (interval arithmetic)."""

from __future__ import annotations

import math

from afsmc.model import expr as E
from afsmc.model import ir
from afsmc.model.pretty import show

Bounds = tuple[float, float]


def bounds(e: E.Expr, model: ir.Model, env: dict[str, Bounds] | None = None,
           generated: dict[str, tuple[str, int]] | None = None,
           memo: dict[int, Bounds] | None = None) -> Bounds:
    """A conservative interval of the values of `e` over every state (interval arithmetic).
    `generated`: the lowering's interval-bound constants (`Lowered.bounds`). `memo` (by node
    identity; the nodes must outlive it): for a caller that asks for every subexpression of
    one expression, so that this is linear rather than quadratic in its size."""
    if memo is None:
        return _bounds(e, model, env, generated, None)
    got = memo.get(id(e))
    if got is None:
        got = memo[id(e)] = _bounds(e, model, env, generated, memo)
    return got


def _bounds(e: E.Expr, model: ir.Model, env: dict[str, Bounds] | None,
            generated: dict[str, tuple[str, int]] | None,
            memo: dict[int, Bounds] | None) -> Bounds:
    inf = float("inf")
    env = env if env is not None else {v.name: (float(v.lo), float(v.hi)) for v in model.variables}
    if isinstance(e, E.Lit):
        v = float(e.value)
        return v, v
    if isinstance(e, E.ConstRef):
        if generated and e.name in generated:
            v = float(generated[e.name][1])
            return v, v
        c = model.constant(e.name)
        if c.interval is not None:
            return float(c.interval[0]), float(c.interval[1])
        v = float(c.value)
        return v, v
    if isinstance(e, E.VarRef):
        return env.get(e.name, (-inf, inf))
    if isinstance(e, E.FormulaRef):
        return bounds(model.formula(e.name).value, model, env, generated, memo)
    if isinstance(e, E.ModeVal):
        return float(e.number), float(e.number)
    if isinstance(e, E.Unary) and e.op == "-":
        lo, hi = bounds(e.operand, model, env, generated, memo)
        return -hi, -lo
    if isinstance(e, E.Binary) and e.op in ("+", "-", "*"):
        a, b = bounds(e.left, model, env, generated, memo), bounds(e.right, model, env, generated, memo)
        if e.op == "+":
            return _sane(a[0] + b[0], a[1] + b[1])
        if e.op == "-":
            return _sane(a[0] - b[1], a[1] - b[0])
        prods = [x * y for x in a for y in b if not ((abs(x) == inf and y == 0) or (abs(y) == inf and x == 0))]
        return (min(prods), max(prods)) if prods else (-inf, inf)
    if isinstance(e, E.Ite):
        a, b = bounds(e.then, model, env, generated, memo), bounds(e.other, model, env, generated, memo)
        return min(a[0], b[0]), max(a[1], b[1])
    if isinstance(e, E.Call) and e.func in ("min", "max"):
        parts = [bounds(x, model, env, generated, memo) for x in e.args]
        pick = min if e.func == "min" else max
        lo, hi = pick(p[0] for p in parts), pick(p[1] for p in parts)
        if e.func == "max" and _is_abs(e):
            lo = max(lo, 0.0)  # max(a - b, b - a) = |a - b|
        return lo, hi
    if isinstance(e, E.Call) and e.func in ("floor", "ceil"):
        lo, hi = bounds(e.args[0], model, env, generated, memo)
        return (float(math.floor(lo)) if math.isfinite(lo) else lo,
                float(math.ceil(hi)) if math.isfinite(hi) else hi)
    if isinstance(e, E.Call) and e.func == "pow" and e.type is E.Type.INT:
        (bl, bh), (kl, kh) = (bounds(x, model, env, generated, memo) for x in e.args)
        if kl >= 0 and all(map(math.isfinite, (bl, bh, kl, kh))):
            return _int_pow(bl, bh, kl, kh)
    return -inf, inf


def _int_pow(bl: float, bh: float, kl: float, kh: float) -> Bounds:
    """b ** k for b in [bl, bh], integer k in [kl, kh], k >= 0. For b >= 0 the extremes lie
    at the corners (monotone in each argument); a negative base may flip the sign, so then
    +- the largest magnitude."""
    def p(b: float, k: float) -> float:
        try:
            return float(float(b) ** k)
        except OverflowError:
            return math.inf
    if bl >= 0:
        corners = [p(b, k) for b in (bl, bh) for k in (kl, kh)]
        return min(corners), max(corners)
    top = max(p(abs(bl), kh), p(abs(bh), kh), p(abs(bl), kl), p(abs(bh), kl), 1.0)
    return -top, top


def static(e: E.Expr, model: ir.Model,
            generated: dict[str, tuple[str, int]] | None = None) -> float | None:
    lo, hi = bounds(e, model, {}, generated)
    return lo if lo == hi else None




def _is_abs(e: E.Call) -> bool:
    if len(e.args) != 2:
        return False
    a, b = e.args
    if not (isinstance(a, E.Binary) and isinstance(b, E.Binary) and a.op == b.op == "-"):
        return False
    return show(a.left) == show(b.right) and show(a.right) == show(b.left)


def _sane(lo: float, hi: float) -> Bounds:
    """inf - inf is nan: unbounded then."""
    return (-math.inf if math.isnan(lo) else lo, math.inf if math.isnan(hi) else hi)
