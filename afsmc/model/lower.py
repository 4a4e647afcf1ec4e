"""Lowering: the APFSM's weights, hazards and interval constants become plain guarded
commands, the common input of every backend (PRISM, JANI, the simulator).

* Weights -> guards (Definition 2): action `a` of mode M fires iff it is enabled and no
  other enabled action of M has a larger weight. Weights are checked to be distinct, so
  exactly the arg-max fires.
* Preemptive hazards (`hazard H from {...} when c`) are actions that, while `c` holds,
  disable every ordinary action of the modes they cover.
* Probabilistic hazards (`with probability p`) are woven into every command of the modes
  they cover: with probability p the hazard's outcome replaces the action's.
* Interval constants `[lo, hi]`: a command whose updates use some become one command per
  floor/ceil combination (an MDP, as in the paper), or one command that picks each
  combination uniformly (a DTMC, the paper's third curve), or a fixed end.
"""

from __future__ import annotations

import itertools
from dataclasses import dataclass, field
from typing import Literal

from afsmc.diagnostics import Span
from afsmc.model import expr as E
from afsmc.model import ir
from afsmc.model.bounds import bounds
from afsmc.model.evaluate import EvalError, scalar
from afsmc.model.expr import Type

Resolution = Literal["nondet", "uniform", "lo", "hi"]
RESOLUTIONS: tuple[Resolution, ...] = ("nondet", "uniform", "lo", "hi")


@dataclass(frozen=True)
class Branch:
    prob: E.Expr
    updates: tuple[tuple[str, E.Expr], ...]  # (variable or "mode", new value)
    span: Span
    hazard: str | None = None  # the probabilistic hazard this branch comes from


@dataclass(frozen=True)
class Command:
    action: str
    modes: tuple[int, ...]
    guard: E.Expr  # complete: mode, the action's guard, priority over competitors
    branches: tuple[Branch, ...]
    span: Span  # the action's declaration
    choice: tuple[tuple[str, str], ...] = ()  # (interval constant, "lo"|"hi") fixed here
    # "final": a final mode's self-loop; "deadlock": the self-loop of the states of a
    # non-final mode where no action is enabled (W301/W302)
    kind: Literal["action", "preemptive", "final", "deadlock"] = "action"

    @property
    def silent(self) -> bool:
        """A self-loop no action labels: it earns no action reward."""
        return self.kind in ("final", "deadlock")


@dataclass(frozen=True)
class Lowered:
    model: ir.Model
    commands: tuple[Command, ...]
    resolution: Resolution
    weights: dict[str, E.Expr]  # action -> effective weight w(s, a) (0 where not enabled)
    bounds: dict[str, tuple[str, int]] = field(default_factory=dict)  # generated const -> (interval const, value)
    reductions: tuple[str, ...] = ()  # exact reductions applied (afsmc.model.reduce)

    @property
    def kind(self) -> Literal["dtmc", "mdp"]:
        return "mdp" if self.resolution == "nondet" and self.model.is_nondeterministic else "dtmc"


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
    memo = model.cache.setdefault("inline", {})
    assert isinstance(memo, dict)

    def fn(n: E.Expr) -> E.Expr | None:
        if isinstance(n, E.FormulaRef):
            key = "f:" + n.name
            if key not in memo:
                memo[key] = inline(model.formula(n.name).value, model)
            return memo[key]  # type: ignore[no-any-return]
        if isinstance(n, E.WeightRef):
            key = "w:" + n.action
            if key not in memo:
                memo[key] = inline(effective_weight(model, model.action(n.action)), model)
            return memo[key]  # type: ignore[no-any-return]
        if isinstance(n, E.LabelRef):
            key = key_label(n.name)
            if key not in memo:
                memo[key] = inline(model.label(n.name).value, model)
            return memo[key]  # type: ignore[no-any-return]
        return None

    return E.transform(e, fn)


def key_label(name: str) -> str:
    return "label:" + name


def static_value(e: E.Expr, model: ir.Model) -> float | None:
    """The value of a state-free expression, or None if it depends on the state."""
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


# Weights closer than this tie, as evaluate's `==` on doubles has it: 0.1 + 0.2 ties with
# 0.3. E301 rejects a tie of enabled competitors; without one, `<` and "smaller by more
# than TIE" agree in every state, so the lowering keeps plain `<`.
TIE = 1e-12


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


def lower(model: ir.Model, resolution: Resolution = "nondet") -> Lowered:
    names = model.mode_names
    commands: list[Command] = []
    bounds: dict[str, tuple[str, int]] = {}
    taken = {c.name for c in model.constants} | {v.name for v in model.variables} | {
        f.name for f in model.formulas}

    def bound_name(const: str, end: str, value: int) -> str:
        base = f"{const}_{end}"
        name = base
        while name in taken and bounds.get(name) != (const, value):
            name += "_"
        bounds[name] = (const, value)
        taken.add(name)
        return name

    for action in model.actions:
        # Group modes that lower identically: same competitors, hazards and preemptions.
        groups: dict[tuple[object, ...], list[int]] = {}
        for mode in action.modes:
            key = (tuple(b.name for b in model.actions_in(mode) if b is not action),
                   tuple(h.name for h in model.hazards_in(mode)))
            groups.setdefault(key, []).append(mode)
        for modes in groups.values():
            rep = modes[0]
            guard = E.conj(E.mode_in(set(modes), names), fire_condition(model, action, rep))
            branches = tuple(Branch(o.prob, _updates(model, o.updates), o.span)
                             for o in action.outcomes)
            branches = _weave(model, branches, model.hazards_in(rep))
            for choice, bs in _resolve_intervals(model, branches, resolution, bound_name):
                commands.append(Command(action.name, tuple(modes), guard, bs, action.span, choice,
                                        action.kind))
    for m in model.modes:
        stay = (Branch(E.Lit(1, Type.INT), (), m.span),)
        if m.final:
            commands.append(Command(
                f"{m.name}", (m.number,), E.mode_in({m.number}, names),
                stay, m.span, (), "final"))
        elif _can_deadlock(model, m.number):
            # A state with no enabled action stays where it is, like a final one. Left to
            # Storm, its engines disagree: the sparse one gives such a state no reward,
            # the symbolic ones its state reward; the simulator must match one semantics.
            commands.append(Command(
                f"{m.name}", (m.number,), E.conj(E.mode_in({m.number}, names),
                                                 stuck(model, m.number)),
                stay, m.span, (), "deadlock"))
    weights = {a.name: effective_weight(model, a) for a in model.actions}
    return Lowered(model, tuple(commands), resolution, weights, bounds)


def _can_deadlock(model: ir.Model, mode: int) -> bool:
    # The checks (W301/W302) ask the same question; they come first in the pipeline but
    # use this module, hence the late import.
    from afsmc.check.search import Undecided
    from afsmc.check.weights import deadlock_witness

    if not model.actions_in(mode):
        return True
    try:
        return deadlock_witness(model, mode) is not None
    except Undecided:
        return True  # a self-loop whose guard never holds changes nothing


def _updates(model: ir.Model, updates: tuple[ir.Update, ...]) -> tuple[tuple[str, E.Expr], ...]:
    order = {"mode": -1} | {v.name: i for i, v in enumerate(model.variables)}
    out = []
    for u in sorted(updates, key=lambda u: order[u.var]):
        value = u.value
        if u.var != "mode":
            var = model.variable(u.var)
            if var.clamp:
                value = _clamp(value, var, model)
        out.append((u.var, value))
    return tuple(out)


def _clamp(value: E.Expr, var: ir.Variable, model: ir.Model) -> E.Expr:
    """Saturate at the range's ends; only an end the update can pass is emitted."""
    lo, hi = bounds(value, model)
    if value.type is E.Type.INT and var.lo <= lo and hi <= var.hi:
        return value
    if hi > var.hi:
        value = E.Call("min", (value, E.Lit(var.hi, Type.INT)), Type.INT)
    if lo < var.lo:
        value = E.Call("max", (value, E.Lit(var.lo, Type.INT)), Type.INT)
    return value


def _weave(model: ir.Model, branches: tuple[Branch, ...],
           hazards: tuple[ir.Hazard, ...]) -> tuple[Branch, ...]:
    current = list(branches)
    for h in reversed(hazards):
        woven = [Branch(E.mul(h.prob, o.prob), _updates(model, o.updates), o.span, h.name)
                 for o in h.outcomes]
        rest = E.sub(E.Lit(1, Type.INT), h.prob)
        woven += [Branch(E.mul(rest, b.prob), b.updates, b.span, b.hazard) for b in current]
        current = woven
    return tuple(current)


def _interval_consts(model: ir.Model, branches: tuple[Branch, ...]) -> list[str]:
    used: set[str] = set()
    for b in branches:
        for _, v in b.updates:
            used |= E.consts_read(v)
    return sorted(c.name for c in model.interval_constants if c.name in used)


def _resolve_intervals(model: ir.Model, branches: tuple[Branch, ...], resolution: Resolution,
                       bound_name: object) -> list[tuple[tuple[tuple[str, str], ...],
                                                         tuple[Branch, ...]]]:
    consts = _interval_consts(model, branches)
    if not consts:
        return [((), branches)]
    assert callable(bound_name)

    def fix(bs: tuple[Branch, ...], ends: tuple[str, ...], scale: E.Expr | None) -> tuple[Branch, ...]:
        sub: dict[str, E.Expr] = {}
        for name, end in zip(consts, ends, strict=True):
            c = model.constant(name)
            assert c.interval is not None
            value = c.interval[0] if end == "lo" else c.interval[1]
            sub[name] = E.ConstRef(bound_name(name, end, value), Type.INT)

        def swap(n: E.Expr) -> E.Expr | None:
            return sub.get(n.name) if isinstance(n, E.ConstRef) else None

        return tuple(Branch(b.prob if scale is None else E.mul(scale, b.prob),
                            tuple((v, E.transform(x, swap)) for v, x in b.updates), b.span, b.hazard)
                     for b in bs)

    if resolution in ("lo", "hi"):
        ends: tuple[str, ...] = tuple(resolution for _ in consts)
        return [(tuple(zip(consts, ends, strict=True)), fix(branches, ends, None))]
    combos = list(itertools.product(("lo", "hi"), repeat=len(consts)))
    if resolution == "nondet":
        return [(tuple(zip(consts, ends, strict=True)), fix(branches, ends, None))
                for ends in combos]
    scale = E.Binary("/", E.Lit(1, Type.INT), E.Lit(len(combos), Type.INT), Type.DOUBLE)
    # Branches that do the same under every choice (e.g. a hazard's) are merged.
    merged: dict[tuple[tuple[str, E.Expr], ...], Branch] = {}
    for ends in combos:
        for b in fix(branches, ends, scale):
            if b.updates in merged:
                old = merged[b.updates]
                merged[b.updates] = Branch(E.Binary("+", old.prob, b.prob, Type.DOUBLE),
                                           b.updates, old.span, old.hazard)
            else:
                merged[b.updates] = b
    return [((), tuple(merged.values()))]
