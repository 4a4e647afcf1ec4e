"""No integer expression leaves 64 bits: `x * BIG` or `pow(2, n)` whose value, by the
ranges of the variables it reads, can pass 2^63 - 1 (or fall below -2^63).

Storm and the simulator compute integers with 64 bits and wrap around without a word, so
such an expression would silently turn a guard or an update into another one (and the
exact state search of the other checks would disagree with both). Constant-only parts are
E245 already (resolve). The test is interval arithmetic over the variables' ranges, which
is exact for independent operands; an interval that interval arithmetic cannot bound (a
division near zero, which E306 covers) is not taken as an overflow.
"""

from __future__ import annotations

import math

from afsmc.check.undefined import node_key, sites
from afsmc.diagnostics import Reporter, codes
from afsmc.model import expr as E
from afsmc.model import ir
from afsmc.model.bounds import bounds
from afsmc.model.expr import Type
from afsmc.model.limits import INT64
from afsmc.model.pretty import with_names

_STATE_FREE = (E.Lit, E.ConstRef, E.Unary, E.Binary, E.Ite, E.Call)


def _beyond(lo: float, hi: float) -> float | None:
    """The end of [lo, hi] that lies outside 64 bits (finite), or None."""
    if math.isfinite(hi) and hi > INT64[1]:
        return hi
    if math.isfinite(lo) and lo < INT64[0]:
        return lo
    return None


def _exact(e: E.Expr, model: ir.Model,
           memo: dict[int, tuple[int, int] | None]) -> tuple[int, int] | None:
    """The interval of `e` in exact integers, for the few operations whose float bounds
    can straddle 2^63 by rounding alone; None for anything else."""
    if id(e) in memo:
        return memo[id(e)]
    got: tuple[int, int] | None = None
    if isinstance(e, E.Lit) and isinstance(e.value, int) and not isinstance(e.value, bool):
        got = (e.value, e.value)
    elif isinstance(e, E.ConstRef):
        c = model.constant(e.name)
        if c.interval is not None:
            got = c.interval
        elif isinstance(c.value, int) and not isinstance(c.value, bool):
            got = (c.value, c.value)
    elif isinstance(e, E.VarRef) and e.type is Type.INT:
        v = model.variable(e.name)
        got = (int(v.lo), int(v.hi))
    elif isinstance(e, (E.Unary, E.Binary, E.Ite, E.Call)) and e.type is Type.INT:
        parts = (e.then, e.other) if isinstance(e, E.Ite) else E.children(e)
        kids = [_exact(k, model, memo) for k in parts]
        if all(k is not None for k in kids):
            ks = [k for k in kids if k is not None]
            if isinstance(e, E.Unary) and e.op == "-":
                got = (-ks[0][1], -ks[0][0])
            elif isinstance(e, E.Binary) and e.op == "+":
                got = (ks[0][0] + ks[1][0], ks[0][1] + ks[1][1])
            elif isinstance(e, E.Binary) and e.op == "-":
                got = (ks[0][0] - ks[1][1], ks[0][1] - ks[1][0])
            elif isinstance(e, E.Binary) and e.op == "*":
                prods = [x * y for x in ks[0] for y in ks[1]]
                got = (min(prods), max(prods))
            elif isinstance(e, E.Call) and e.func in ("min", "max"):
                pick = min if e.func == "min" else max
                got = (pick(k[0] for k in ks), pick(k[1] for k in ks))
            elif isinstance(e, E.Ite):
                got = (min(ks[0][0], ks[1][0]), max(ks[0][1], ks[1][1]))
    memo[id(e)] = got
    return got


def _min_mod_minus_one(n: E.Expr, model: ir.Model, memo: dict[int, tuple[float, float]]) -> bool:
    if not (isinstance(n, E.Call) and n.func == "mod" and n.type is Type.INT):
        return False
    a, b = (bounds(arg, model, memo=memo) for arg in n.args)
    return a[0] <= INT64[0] and b[0] <= -1 <= b[1]


def check_overflow(model: ir.Model, rep: Reporter) -> None:
    show = with_names(model.display_names())
    reported: set[tuple[int, int] | int] = set()
    for site in sites(model):
        x = site.inlined
        if not isinstance(x, (E.Unary, E.Binary, E.Ite, E.Call)):
            continue  # a number, constant or variable: nothing is computed
        # One pass, inner parts first (an outer expression overflows because an inner one
        # does), with each node's facts computed from its children's: linear in the size
        # of the expression (a node that walked its subtree would make a 2000-term sum take 12 s).
        memo: dict[int, tuple[float, float]] = {}
        exact: dict[int, tuple[int, int] | None] = {}
        free: dict[int, bool] = {}  # made of numbers and constants only
        tainted: dict[int, bool] = {}  # holds a node already reported
        for n in reversed(list(E.walk(x))):
            kids = E.children(n)
            if not kids and not isinstance(n, E.Call):  # a leaf computes nothing
                free[id(n)] = isinstance(n, _STATE_FREE)
                tainted[id(n)] = node_key(n) in reported
                continue
            free[id(n)] = isinstance(n, _STATE_FREE) and all(free[id(c)] for c in kids)
            key = node_key(n)
            below = key in reported or any(tainted[id(c)] for c in kids)
            tainted[id(n)] = below
            if not below and _min_mod_minus_one(n, model, memo):
                # -2^63 mod -1 is 0, but the 64-bit division behind it traps: Storm's JANI
                # route dies of SIGFPE (constants too: no other check sees them so).
                reported.add(key)
                tainted[id(n)] = True
                rep.error(codes.E307, f"{show(n)} divides -2^63 by -1 in some state, which "
                          f"overflows a 64-bit integer (Storm stops with a floating-point "
                          f"exception), where {site.what} is evaluated",
                          n.span if n.span is not None else site.expr.span,
                          hint="keep the first operand above -2^63 or the second away from -1")
                continue
            # An integer the machine computes (not a variable, constant or literal, whose
            # own ranges are checked where they are declared).
            if below or n.type is not Type.INT or free[id(n)] or not isinstance(
                    n, (E.Unary, E.Binary, E.Call)):
                continue
            lo, hi = bounds(n, model, memo=memo)
            end: float | int | None = _beyond(lo, hi)
            if any(abs(abs(b) - 2.0 ** 63) <= 2.0 ** 33 for b in (lo, hi)):
                # Floats round 2^63 - 2 up to 2^63 (and a sum of rounded parts may fall
                # short of it): near the edge, ask exact integers where they can be had.
                got = _exact(n, model, exact)
                if got is not None:
                    end = got[1] if got[1] > INT64[1] else got[0] if got[0] < INT64[0] else None
            if end is None:
                continue
            reported.add(key)
            tainted[id(n)] = True
            shown = str(end) if isinstance(end, int) else f"{end:.3g}"
            ranges = ", ".join(f"{v.display} in [{v.lo}..{v.hi}]" for v in model.variables
                               if v.name in E.vars_read(n))
            rep.error(codes.E307, f"{show(n)} can reach {shown} ({ranges}), beyond a 64-bit "
                      f"integer, where {site.what} is evaluated",
                      n.span if n.span is not None else site.expr.span,
                      hint="Storm and the simulator compute integers with 64 bits and would "
                           "wrap around silently; bound the operands with min/max, or compute "
                           "in doubles (e.g. '1.0 * x * BIG')")
