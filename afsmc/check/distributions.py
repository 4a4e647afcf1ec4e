"""Outcome probabilities lie in [0, 1] and sum to 1, in every state where the action or
hazard can happen."""

from __future__ import annotations

from afsmc.check.ranges import value_at
from afsmc.check.undefined import defined
from afsmc.diagnostics import Reporter, Span, codes
from afsmc.model import expr as E
from afsmc.model import ir
from afsmc.model.expr import Type
from afsmc.model.search import find
from afsmc.model.semantics import enabled, static_value

EPSILON = 1e-9


def _check(model: ir.Model, rep: Reporter, owner: str, when: dict[int, E.Expr],
           outcomes: tuple[ir.Outcome, ...], span: Span) -> None:
    for o in outcomes:
        if isinstance(o.prob, E.Lit) and 0 <= o.prob.value <= 1:
            continue  # a number in [0, 1] (a plain outcome's 1): no state to look for
        bad = E.disj(E.Binary("<", o.prob, E.lit(0), Type.BOOL),
                     E.Binary(">", o.prob, E.lit(1), Type.BOOL))
        for mode, cond in when.items():
            wit = find(model, mode, E.conj(cond, defined(o.prob, model), bad))
            if wit is not None:
                rep.error(codes.E304, f"a probability of {owner} is "
                          f"{value_at(model, o.prob, wit, mode)}, outside [0, 1], in the state {wit}",
                          o.prob.span or o.span)
                break
    total: E.Expr = outcomes[0].prob
    for o in outcomes[1:]:
        total = E.Binary("+", total, o.prob, Type.DOUBLE)
    # Point at the outcomes, from the first to the last.
    first, last = outcomes[0].span, outcomes[-1].span
    if first.source is last.source and last.end > first.start:
        span = Span.at_offset(first.source, first.start, last.end)
    static = static_value(total, model)
    if static is not None:
        if abs(static - 1.0) > EPSILON:
            rep.error(codes.E305, f"the outcome probabilities of {owner} sum to {static:.12g}, not 1",
                      span, hint="make the last outcome '1 - ...' of the others")
        return
    off = E.disj(E.Binary(">", total, E.lit(1 + EPSILON), Type.BOOL),
                 E.Binary("<", total, E.lit(1 - EPSILON), Type.BOOL))
    for mode, cond in when.items():
        wit = find(model, mode, E.conj(cond, defined(total, model), off))
        if wit is not None:
            rep.error(codes.E305, f"the outcome probabilities of {owner} sum to "
                      f"{value_at(model, total, wit, mode)}, not 1, in the state {wit}", span,
                      hint="make the last outcome '1 - ...' of the others")
            return


def check_distributions(model: ir.Model, rep: Reporter) -> None:
    for a in model.actions:
        when = {m: enabled(model, a, m) for m in a.modes}
        _check(model, rep, f"{'hazard' if a.kind == 'preemptive' else 'action'} {a.name}", when,
               a.outcomes, a.span)
    for h in model.hazards:
        when = {m: E.disj(*(enabled(model, a, m) for a in model.actions_in(m))) for m in h.modes}
        bad = E.disj(E.Binary("<", h.prob, E.lit(0), Type.BOOL),
                     E.Binary(">", h.prob, E.lit(1), Type.BOOL))
        for mode, cond in when.items():
            wit = find(model, mode, E.conj(cond, defined(h.prob, model), bad))
            if wit is not None:
                rep.error(codes.E304, f"the probability of hazard {h.name} is "
                          f"{value_at(model, h.prob, wit, mode)}, outside [0, 1], in the "
                          f"state {wit}", h.prob.span or h.span)
                break
        _check(model, rep, f"hazard {h.name}", when, h.outcomes, h.span)
