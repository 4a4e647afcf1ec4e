"""No expression is undefined where it is evaluated: a division by zero (`2 / x` at x = 0,
likewise `mod(a, 0)`, `pow(0, -1)` and `pow(-8, 0.5)`) in a guard, weight, probability, update, label,
reward or property.

Storm computes such a value as infinite or NaN and goes on (`!(2 / x > 0)` is false at
x = 0, so an action silently disappears), the simulator stops with E506, and a constant
one (`1 / 0`) crashes Storm. So each partial operation is checked where its value matters:
in the states of the modes where the expression is evaluated, under the context that
decides whether it counts (`x > 0 && 2 / x > 1`, `x == 0 ? 0 : 1 / x`). A divisor that is
zero there is E306 (with the state), or E245 when it is made of constants only.
"""

from __future__ import annotations

import itertools
from collections.abc import Callable, Iterator
from dataclasses import dataclass, field
from functools import cached_property, partial
from typing import Any

from afsmc.diagnostics import Reporter, codes
from afsmc.model import expr as E
from afsmc.model import ir
from afsmc.model.bounds import bounds
from afsmc.model.expr import Type
from afsmc.model.pretty import with_names
from afsmc.model.search import find
from afsmc.model.semantics import enabled, fire_condition, inline

ZERO_POWER = "zero to a negative power"
FRACTIONAL_POWER = "a negative number to a fractional power"


@dataclass(frozen=True)
class Partial:
    """A partial operation: `node` is undefined where `context` and `zero` hold."""

    node: E.Expr
    divisor: E.Expr  # the operand that must not be zero (the base, for pow)
    zero: E.Expr
    context: E.Expr
    why: str


def interval_choices(model: ir.Model, e: E.Expr) -> list[dict[str, int]]:
    """Every floor/ceil choice of the interval constants `e` uses ({} if none)."""
    used = [c for c in model.interval_constants if c.name in E.consts_read(e)]
    choices = []
    for ends in itertools.product((0, 1), repeat=len(used)):
        choices.append({c.name: c.interval[end] for c, end in zip(used, ends, strict=True)
                        if c.interval is not None})
    return choices


def _is_zero(d: E.Expr) -> E.Expr:
    # Exact (evaluate's == has a tolerance for doubles), and true for a NaN divisor too.
    return E.conj(E.neg(E.Binary("<", d, E.lit(0), Type.BOOL)),
                  E.neg(E.Binary(">", d, E.lit(0), Type.BOOL)))


def partials(e: E.Expr, context: E.Expr = E.TRUE) -> Iterator[Partial]:
    """The partial operations of `e` (inner ones first), each with the condition under which
    its value decides the value of `e`: the right side of `a && b` and `a => b` counts
    where `a` holds, of `a || b` where it does not, the branches of `?:` where chosen."""
    if isinstance(e, E.Binary) and e.op in ("&&", "||", "=>"):
        yield from partials(e.left, context)
        left = E.neg(e.left) if e.op == "||" else e.left
        yield from partials(e.right, E.conj(context, left))
        return
    if isinstance(e, E.Ite):
        yield from partials(e.cond, context)
        yield from partials(e.then, E.conj(context, e.cond))
        yield from partials(e.other, E.conj(context, E.neg(e.cond)))
        return
    for c in E.children(e):
        yield from partials(c, context)
    if isinstance(e, E.Binary) and e.op == "/":
        yield Partial(e, e.right, _is_zero(e.right), context, "division by zero")
    elif isinstance(e, E.Call) and e.func == "mod":
        yield Partial(e, e.args[1], _is_zero(e.args[1]), context, "mod by zero")
    elif isinstance(e, E.Call) and e.func == "pow":
        base, power = e.args
        yield Partial(e, base, E.conj(_is_zero(base), E.Binary("<", power, E.lit(0), Type.BOOL)),
                      context, ZERO_POWER)
        if power.type is Type.DOUBLE:
            # NaN in Storm (and numpy): pow(-8, 1/3) is no real number here.
            fractional = E.Binary("!=", E.Call("floor", (power,), Type.INT), power, Type.BOOL)
            yield Partial(e, base, E.conj(E.Binary("<", base, E.lit(0), Type.BOOL), fractional),
                          context, FRACTIONAL_POWER)


def _never_zero(p: Partial, model: ir.Model) -> bool:
    """Interval arithmetic says the operation is defined in every state (the fast path)."""
    if p.why == FRACTIONAL_POWER:
        return bounds(p.divisor, model)[0] >= 0
    if p.why == ZERO_POWER and bounds(p.node.args[1], model)[0] >= 0:  # type: ignore[union-attr]
        return True
    lo, hi = bounds(p.divisor, model)
    return lo > 0 or hi < 0


def defined(e: E.Expr, model: ir.Model) -> E.Expr:
    """Where `e` (formulas and weights inlined) is defined: no partial operation that
    counts is undefined. The checks of values (E301-E305) ask only there, so that the
    enumeration (NaN compares false) and the SMT solver (x / 0 is any number) agree, and
    an undefined value is reported once, as such (E306)."""
    parts = [E.neg(E.conj(p.context, p.zero)) for p in partials(inline(e, model))
             if not _never_zero(p, model)]
    return E.conj(*parts)


Conditions = Callable[[], dict[int, E.Expr]]


@dataclass(frozen=True)
class Site:
    what: str  # "the guard of action Go"
    expr: E.Expr
    # mode -> where in it the expression is evaluated, computed when first asked: the
    # checks ask only at a site where something may go wrong, and building them for every
    # site was a tenth of a large file's check
    conditions: Conditions
    target: str | None = None  # the variable an update assigns
    model: ir.Model | None = field(default=None, compare=False, repr=False)

    @cached_property
    def when(self) -> dict[int, E.Expr]:
        return self.conditions()

    @cached_property
    def inlined(self) -> E.Expr:
        """The expression with formulas and weights inlined (each check reads it)."""
        assert self.model is not None
        return inline(self.expr, self.model)


class _Once:
    """A function of no arguments whose value is computed at the first call only (the
    conditions several sites share), lighter than functools.cache."""

    def __init__(self, fn: Conditions) -> None:
        self.fn: Conditions | None = fn
        self.value: dict[int, E.Expr] = {}

    def __call__(self) -> dict[int, E.Expr]:
        if self.fn is not None:
            self.value, self.fn = self.fn(), None
        return self.value


def _guard_when(model: ir.Model, a: ir.Action) -> dict[int, E.Expr]:
    # An ordinary action's guard counts where no preemptive hazard of the mode holds.
    return {m: E.conj(*(E.neg(h.guard) for h in model.actions_in(m)
                        if a.kind == "action" and h.kind == "preemptive")) for m in a.modes}


def _weight_when(model: ir.Model, a: ir.Action) -> dict[int, E.Expr]:
    return {m: enabled(model, a, m) for m in a.modes}


def _fires(model: ir.Model, a: ir.Action) -> dict[int, E.Expr]:
    return {m: fire_condition(model, a, m, ties=True) for m in a.modes}


def _hazard_when(model: ir.Model, h: ir.Hazard) -> dict[int, E.Expr]:
    return {m: E.disj(*(enabled(model, a, m) for a in model.actions_in(m))) for m in h.modes}


def _reward_when(model: ir.Model, item: ir.RewardItem, all_modes: dict[int, E.Expr]
                 ) -> dict[int, E.Expr]:
    if item.action is None:
        return all_modes
    acts = [a for a in model.actions if a.name == item.action]
    return _fires(model, acts[0]) if acts else all_modes


def _reward_value_when(model: ir.Model, item: ir.RewardItem, all_modes: dict[int, E.Expr]
                       ) -> dict[int, E.Expr]:
    return {m: E.conj(c, item.guard) for m, c in _reward_when(model, item, all_modes).items()}


def sites(model: ir.Model) -> Iterator[Site]:
    """Every expression the machine evaluates, with the modes (and conditions) where.
    Made once per model and shared by the checks, with what they compute on a site (its
    conditions, its expression inlined): kept while the model's parts are the same
    objects (`dataclasses.replace` shares the memo)."""
    parts = (model.modes, model.actions, model.hazards, model.labels, model.rewards,
             model.properties, model.formulas, model.constants, model.variables)
    known: Any = model.memo.lookups.get("check.sites")
    if known is not None and all(a is b for a, b in zip(known[0], parts, strict=True)):
        return iter(known[1])
    made = list(_sites(model))
    model.memo.lookups["check.sites"] = (parts, made)
    return iter(made)


def _sites(model: ir.Model) -> Iterator[Site]:
    all_modes: dict[int, E.Expr] = {m.number: E.TRUE for m in model.modes}
    everywhere: Conditions = lambda: all_modes  # noqa: E731
    for a in model.actions:
        kind = "hazard" if a.kind == "preemptive" else "action"
        yield Site(f"the guard of {kind} {a.name}", a.guard, partial(_guard_when, model, a), model=model)
        yield Site(f"the weight of {kind} {a.name}", a.weight, partial(_weight_when, model, a), model=model)
        yield from _outcome_sites(f"{kind} {a.name}", a.outcomes, _Once(partial(_fires, model, a)),
                                  model)
    for h in model.hazards:
        when = _Once(partial(_hazard_when, model, h))
        yield Site(f"the probability of hazard {h.name}", h.prob, when, model=model)
        yield from _outcome_sites(f"hazard {h.name}", h.outcomes, when, model)
    for lb in model.labels:
        yield Site(f"label {lb.name}", lb.value, everywhere, model=model)
    for r in model.rewards:
        for item in r.items:
            yield Site(f"reward structure {r.name}", item.guard,
                       partial(_reward_when, model, item, all_modes), model=model)
            yield Site(f"reward structure {r.name}", item.value,
                       partial(_reward_value_when, model, item, all_modes), model=model)
    for p in model.properties:
        for e in (p.path.target, getattr(p.path, "left", None)):
            if e is not None:
                yield Site(f"property {p.name}", e, everywhere, model=model)


def _outcome_sites(owner: str, outcomes: tuple[ir.Outcome, ...], when: Conditions,
                   model: ir.Model) -> Iterator[Site]:
    for o in outcomes:
        yield Site(f"an outcome probability of {owner}", o.prob, when, model=model)
        for u in o.updates:
            if u.var != "mode":
                yield Site(f"an update of {owner}", u.value, when, u.var, model=model)


def node_key(n: E.Expr) -> tuple[int, int] | int:
    """One key per node as written: the same source part reached through two sites (a
    formula used twice) is reported once."""
    return (n.span.start, n.span.end) if n.span is not None else id(n)


def check_undefined(model: ir.Model, rep: Reporter) -> None:
    show = with_names(model.display_names())
    reported: set[tuple[int, int] | int] = set()
    for site in sites(model):
        x = site.inlined
        for p in partials(x):
            if node_key(p.node) in reported or _never_zero(p, model):
                continue
            if any(node_key(n) in reported for n in E.walk(p.node)):
                continue  # undefined because an inner part is, which is said already
            for consts in interval_choices(model, x):
                hit = next(((m, w) for m, cond in site.when.items()
                            if (w := find(model, m, E.conj(cond, p.context, p.zero), consts))
                            is not None), None)
                if hit is None:
                    continue
                reported.add(node_key(p.node))
                span = p.node.span if p.node.span is not None else site.expr.span
                chosen = "".join(f", {k} = {v}" for k, v in consts.items())
                if E.state_free(p.divisor):
                    rep.error(codes.E245, f"this expression cannot be compiled: {show(p.node)} is "
                              f"undefined ({p.why}), where {site.what} is evaluated", span,
                              hint="Storm fails on a constant part it cannot compute; "
                                   "check the constants it uses")
                else:
                    d = show(p.divisor)
                    ok, bad = (">= 0", "< 0") if p.why == FRACTIONAL_POWER else ("!= 0", "== 0")
                    rep.error(codes.E306, f"{show(p.node)} is undefined ({p.why}) in the state "
                              f"{hit[1]}{chosen}, where {site.what} is evaluated", span,
                              hint="Storm would go on with an infinite or NaN value and verify "
                                   "another model than the simulator runs; exclude the state, "
                                   f"e.g. '{d} {ok} && ...' or '{d} {bad} ? ... : ...'")
                break
