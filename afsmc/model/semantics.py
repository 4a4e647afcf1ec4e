"""Definition 2 of the paper as expressions: when an action is enabled, its effective
weight w(s, a), when it fires (it beats every enabled competitor), and formulas, labels and
weight references inlined. Pure expression builders over the IR: the state search, the
checks, the lowering and the backends all build on them.
"""

from __future__ import annotations

import dataclasses

from afsmc.model import expr as E
from afsmc.model import ir
from afsmc.model.evaluate import EvalError, scalar
from afsmc.model.expr import Type
from afsmc.model.kernel import TOLERANCE


def enabled(model: ir.Model, action: ir.Action, mode: int) -> E.Expr:
    """A(s) for one mode: the guard, and for ordinary actions no preemptive hazard firing."""
    parts = [action.guard]
    if action.kind == "action":
        parts += [E.neg(h.guard) for h in model.actions_in(mode) if h.kind == "preemptive"]
    return E.conj(*parts)


def stuck(model: ir.Model, mode: int) -> E.Expr:
    """No action of the mode is enabled (true if it has none)."""
    return E.conj(*(E.neg(enabled(model, a, mode)) for a in model.actions_in(mode)))


def competitors(model: ir.Model, action: ir.Action, mode: int) -> tuple[ir.Action, ...]:
    return tuple(b for b in model.actions_in(mode) if b is not action and b.kind == action.kind)


def effective_weight(model: ir.Model, action: ir.Action) -> E.Expr:
    """w(s, a): the weight where `a` is enabled, else 0 (Definition 2: w > 0 => enabled)."""
    names = model.mode_names
    if action.kind == "action" and any(h.kind == "preemptive" for m in action.modes
                                       for h in model.actions_in(m)):
        # enabled also needs no preemptive hazard of the mode to hold: per mode
        when = E.disj(*(E.conj(E.mode_in({m}, names), enabled(model, action, m))
                        for m in action.modes))
    else:
        when = E.conj(E.mode_in(set(action.modes), names), action.guard)
    if isinstance(when, E.Lit) and when.value is True:
        return action.weight
    return E.Ite(when, action.weight, E.Lit(0, Type.INT), Type.DOUBLE
                 if action.weight.type is Type.DOUBLE else Type.INT)


def inline(e: E.Expr, model: ir.Model) -> E.Expr:
    """Replace formulas and weight references by what they stand for."""
    # What a name stands for depends on the model only: the checks and reductions inline
    # the same formulas hundreds of times, so the model keeps them.
    memo = model.memo.inline

    def fn(n: E.Expr) -> E.Expr | None:
        if isinstance(n, E.FormulaRef):
            key = "f:" + n.name
            if key not in memo:
                memo[key] = inline(model.formula(n.name).value, model)
            return memo[key]
        if isinstance(n, E.WeightRef):
            key = "w:" + n.action
            if key not in memo:
                memo[key] = inline(effective_weight(model, model.action(n.action)), model)
            return memo[key]
        if isinstance(n, E.LabelRef):
            key = key_label(n.name)
            if key not in memo:
                memo[key] = inline(model.label(n.name).value, model)
            return memo[key]
        return None

    return E.transform(e, fn)


def key_label(name: str) -> str:
    return "label:" + name


def static_value(e: E.Expr, model: ir.Model) -> float | None:
    """The value of a state-free expression, or None if it depends on the state."""
    if isinstance(e, E.Lit):  # (a plain outcome's probability 1, a weight 1)
        return float(e.value)
    for n in E.walk(e):
        if isinstance(n, (E.VarRef, E.CurrentMode, E.WeightRef, E.LabelRef)):
            return None
        if isinstance(n, E.FormulaRef):
            return None
        if isinstance(n, E.ConstRef) and model.constant(n.name).is_interval:
            return None
    try:
        v = scalar(e, model.const_values)
    except EvalError:
        return None
    return float(v)


# Weights closer than this tie, as the kernel's `==` on doubles has it: 0.1 + 0.2 ties with
# 0.3. E301 rejects a tie of enabled competitors; without one, `<` and "smaller by more
# than TIE" agree in every state, so the lowering keeps plain `<`.
TIE = TOLERANCE


def weights_tie(a: E.Expr, b: E.Expr) -> E.Expr:
    """|a - b| <= TIE, written so that enumeration and the SMT solver decide it alike."""
    if a.type is Type.INT and b.type is Type.INT:
        return E.Binary("==", a, b, Type.BOOL)
    return E.conj(_at_most_tie(a, b), _at_most_tie(b, a))


def _at_most_tie(a: E.Expr, b: E.Expr) -> E.Expr:
    """a - b <= TIE: `a` is below `b` or ties with it."""
    if a.type is Type.INT and b.type is Type.INT:
        return E.Binary("<=", a, b, Type.BOOL)  # integers tie only when equal
    return E.Binary("<=", E.sub(a, b), E.Lit(TIE, Type.DOUBLE), Type.BOOL)


def fire_condition(model: ir.Model, action: ir.Action, mode: int, *,
                   ties: bool = False) -> E.Expr:
    """Without the mode test: `a` is enabled and beats every enabled competitor. With
    `ties`, also where it ties with one: what the checks use, so that what they conclude
    holds however a tie (an E301 error) were settled."""
    parts = [enabled(model, action, mode)]
    wa = static_value(action.weight, model)
    for b in competitors(model, action, mode):
        en_b = enabled(model, b, mode)
        wb = static_value(b.weight, model)
        if wa is not None and wb is not None:
            if (wb - wa <= TIE) if ties else (wb < wa):
                continue
            parts.append(E.neg(en_b))
        elif ties:
            parts.append(E.disj(E.neg(en_b), _at_most_tie(b.weight, action.weight)))
        else:
            parts.append(E.disj(E.neg(en_b),
                                E.Binary("<", b.weight, action.weight, Type.BOOL)))
    return E.conj(*parts)


def bounded_globally(p: ir.Property) -> bool:
    """`P [ G<=k φ ]`: Storm has no step-bounded G (neither its PRISM nor its JANI reader)."""
    return isinstance(p.path, ir.Path) and p.path.kind == "G" and p.path.bound is not None


def globally_dual(p: ir.Property, name: str) -> ir.Property:
    """The property that gives `P [ G<=k φ ]` as 1 - its value, exactly: `P [ F<=k !φ ]`,
    and for an MDP the minimum of one is 1 - the maximum of the other."""
    assert isinstance(p.path, ir.Path) and p.path.bound is not None
    return dataclasses.replace(p, name=name,
                               opt="max" if p.opt == "min" else "min" if p.opt else "",
                               path=ir.Path("F", E.neg(p.path.target), bound=p.path.bound))
