"""Definition 2 of the paper: in every state the enabled actions' weights are pairwise
distinct and lie in [0, 1]; and every non-final mode has an enabled action (no deadlock)."""

from __future__ import annotations

import itertools

from afsmc.check.undefined import defined
from afsmc.diagnostics import Related, Reporter, codes
from afsmc.model import expr as E
from afsmc.model import ir
from afsmc.model.bounds import bounds
from afsmc.model.evaluate import Env, EvalError, evaluate
from afsmc.model.expr import Type
from afsmc.model.pretty import number
from afsmc.model.search import Witness, deadlock_witness, find
from afsmc.model.semantics import TIE, competitors, enabled, inline, weights_tie


def _value_at(model: ir.Model, e: E.Expr, w: Witness, mode: int) -> str:
    by_display = {v.display: v.name for v in model.variables}
    env = Env(vars={by_display[n]: val for n, val in w.values}, mode=mode,
              consts=model.const_values)
    try:
        return number(evaluate(inline(e, model), env))
    except EvalError as exc:
        return f"undefined ({exc})"
    except KeyError:
        return "?"


def _same(a: str, b: str) -> bool:
    """Equal values, however written (`0` and `0.0`)."""
    try:
        return a == b or float(a) == float(b)
    except ValueError:
        return False


def check_weight_range(model: ir.Model, rep: Reporter) -> None:
    for a in model.actions:
        lo, hi = bounds(a.weight, model)
        if lo >= 0 and hi <= 1:
            continue  # interval arithmetic is conservative: no state can leave [0, 1]
        for mode in a.modes:
            w = a.weight
            # Where the weight is undefined (0 / 0) E306 says so; elsewhere it is a number.
            bad = E.disj(E.Binary("<", w, E.lit(0), Type.BOOL), E.Binary(">", w, E.lit(1), Type.BOOL))
            wit = find(model, mode, E.conj(enabled(model, a, mode), defined(w, model), bad))
            if wit is not None:
                value = _value_at(model, w, wit, mode)
                where = "" if value.startswith("undefined") or value == "nan" else ", outside [0, 1],"
                rep.error(codes.E302, f"the weight of {a.name} is {value}{where} in the state {wit}",
                          a.weight_span or a.name_span, hint="Definition 2 maps weights into [0, 1]")
                break


def check_weight_uniqueness(model: ir.Model, rep: Reporter) -> None:
    reported: set[tuple[str, str]] = set()
    for m in model.modes:
        if m.final:
            continue
        acts = model.actions_in(m.number)
        for a, b in itertools.combinations(acts, 2):
            if a.kind != b.kind or (a.name, b.name) in reported or b not in competitors(model, a, m.number):
                continue
            if _apart(bounds(a.weight, model), bounds(b.weight, model)):
                continue  # the weights' ranges do not meet: they cannot tie in any state
            tie = E.conj(enabled(model, a, m.number), enabled(model, b, m.number),
                         *(defined(x, model) for x in (a.guard, b.guard, a.weight, b.weight)),
                         weights_tie(a.weight, b.weight))
            wit = find(model, m.number, tie)
            if wit is None:
                continue
            reported.add((a.name, b.name))
            va = _value_at(model, a.weight, wit, m.number)
            vb = _value_at(model, b.weight, wit, m.number)
            both = f"both {va}" if _same(va, vb) else f"{va} and {vb} are equal within {TIE:g}"
            rep.error(
                codes.E301,
                f"weights of {a.name} and {b.name} tie ({both}) in the state {wit}",
                a.weight_span or a.name_span,
                hint="in every state the enabled actions need distinct weights, so that one "
                     "action fires; give one a larger weight or make their guards exclusive",
                related=[Related(f"the weight of {b.name}", b.weight_span or b.name_span)])


def _apart(a: tuple[float, float], b: tuple[float, float]) -> bool:
    # Weights equal within TIE count as a tie: keep a margin.
    return a[1] < b[0] - 1e-9 or b[1] < a[0] - 1e-9


def check_deadlock(model: ir.Model, rep: Reporter) -> None:
    for m in model.modes:
        if m.final:
            continue
        acts = model.actions_in(m.number)
        if not acts:
            rep.warning(codes.W301, f"mode {m.name} has no actions: the machine stops there",
                        m.span, hint=f"mark it final ('mode {m.name} final;') if it ends the mission")
            continue
        wit = deadlock_witness(model, m.number)
        if wit is not None:
            names = ", ".join(a.name for a in acts)
            # The search covers every value of the variables, not only the reachable states:
            # the message says so, and how to silence it for a state that cannot occur.
            rep.warning(codes.W302, f"no action is enabled in the state {wit}: the machine stops "
                        f"there if it can reach it (actions of {m.name}: {names})", m.span,
                        hint="add an action for this case, or widen a guard. The check looks at "
                             "every value of the variables, so the state may be unreachable; "
                             "if it is, widen a guard to cover it or narrow the variable's "
                             "range, and the warning goes")


def check_weight_refs(model: ir.Model, rep: Reporter) -> None:
    """W306: `w(B)` in the weight of an action that shares no mode with B is 0 in every
    state where it is read (w(B) is B's weight where B is enabled, 0 elsewhere): likely the
    wrong action or the wrong modes."""
    by_name = {a.name: a for a in model.actions}
    names = model.mode_names
    for a in model.actions:
        seen: set[str] = set()
        for n in E.walk(a.weight):  # w() stands in weights only, not in formulas (E232)
            if not isinstance(n, E.WeightRef) or n.action in seen:
                continue
            seen.add(n.action)
            target = by_name.get(n.action)
            if target is None or set(target.modes) & set(a.modes):
                continue
            rep.warning(codes.W306, f"w({n.action}) in the weight of {a.name} is always 0: "
                        f"{n.action} acts in none of {a.name}'s modes "
                        f"({', '.join(names[m] for m in a.modes)})",
                        n.span or a.weight_span or a.name_span,
                        hint=f"w() reads an action of the same mode; check the name, or the "
                             f"modes of {n.action}")
