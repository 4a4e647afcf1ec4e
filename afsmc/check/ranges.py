"""An update must not take a variable out of its declared range (unless it clamps).

Checked where the action actually fires (after the weights pick it), for every
floor/ceil choice of the interval constants it uses.
"""

from __future__ import annotations

import math

from afsmc.check.undefined import defined, interval_choices
from afsmc.diagnostics import Reporter, codes
from afsmc.model import expr as E
from afsmc.model import ir
from afsmc.model.bounds import bounds
from afsmc.model.evaluate import Env, EvalError, evaluate
from afsmc.model.expr import Type
from afsmc.model.pretty import number, with_names
from afsmc.model.search import Witness, find
from afsmc.model.semantics import enabled, fire_condition, inline


def value_at(model: ir.Model, e: E.Expr, w: Witness, mode: int,
             consts: dict[str, int] | None = None) -> str:
    """`e`'s value in a witness state, for a message ("?" if it cannot be computed)."""
    by_display = {v.display: v.name for v in model.variables}
    env = Env(vars={by_display[n]: val for n, val in w.values}, mode=mode,
              consts=model.const_values | (consts or {}))
    try:
        return short(evaluate(inline(e, model), env))
    except (EvalError, KeyError):
        return "?"


def short(v: int | float | bool) -> str:
    """A value for a message: -0.2, not -0.19999999999999996, but with the digits that keep
    it on the same side of every integer (1.0000000000001 stays outside [0, 1])."""
    if isinstance(v, int) or not math.isfinite(v):  # bool is an int
        return number(v)
    for digits in range(12, 18):
        text = f"{v:.{digits}g}"
        back = float(text)
        if math.floor(back) == math.floor(v) and (back == int(back)) == (v == int(v)):
            return number(back)
    return number(v)


def _check_updates(model: ir.Model, rep: Reporter, when: dict[int, E.Expr],
                   outcomes: tuple[ir.Outcome, ...]) -> None:
    show = with_names(model.display_names())
    for o in outcomes:
        for u in o.updates:
            if u.var == "mode":
                continue
            var = model.variable(u.var)
            if var.clamp or var.type is not Type.INT:
                continue
            # Interval arithmetic over every state is conservative: inside the range there,
            # no state can leave it, and the exact search (the slow part) is not needed.
            lo, hi = bounds(u.value, model)
            if var.lo <= lo and hi <= var.hi:
                continue
            out = E.conj(defined(u.value, model),  # undefined: E306
                         E.disj(E.Binary("<", u.value, E.lit(var.lo), Type.BOOL),
                                E.Binary(">", u.value, E.lit(var.hi), Type.BOOL)))
            done = False
            for consts in interval_choices(model, u.value):
                for mode, cond in when.items():
                    # `out` alone reads few variables: when no state at all leaves the range,
                    # the search under the (large) firing condition is not needed.
                    if find(model, mode, out, consts) is None:
                        continue
                    wit = find(model, mode, E.conj(cond, out), consts)
                    if wit is None:
                        continue
                    chosen = "".join(f", {k} = {v}" for k, v in consts.items())
                    value = value_at(model, u.value, wit, mode, consts)
                    written = show(u.value)
                    # `cell := 7`, not "7 = 7"
                    what = f"{written} = {value}" if written != value else \
                        f"{var.display} := {value}"
                    rep.error(
                        codes.E303,
                        f"this update can take {var.display} out of its range [{var.lo}..{var.hi}]: "
                        f"{what} in the state {wit}{chosen}",
                        u.span,
                        hint="guard the action, bound the value with min/max, or declare "
                             + (f"'{var.display}' with 'clamp' to saturate at the range's ends"
                                if "." not in var.display else
                                # clamp is the whole tuple's: every field saturates then
                                f"the tuple '{var.display.split('.')[0]}' with 'clamp' to "
                                "saturate its fields at their ranges' ends"))
                    done = True
                    break
                if done:
                    break


def check_update_ranges(model: ir.Model, rep: Reporter) -> None:
    for a in model.actions:
        _check_updates(model, rep, {m: fire_condition(model, a, m, ties=True) for m in a.modes},
                       a.outcomes)
    for h in model.hazards:
        when = {m: E.disj(*(enabled(model, a, m) for a in model.actions_in(m))) for m in h.modes}
        _check_updates(model, rep, when, h.outcomes)
