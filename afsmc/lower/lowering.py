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
from typing import Any, Literal

from afsmc.diagnostics import Span
from afsmc.model import expr as E
from afsmc.model import ir
from afsmc.model.bounds import bounds
from afsmc.model.expr import Type
from afsmc.model.search import Undecided, deadlock_witness
from afsmc.model.semantics import effective_weight, fire_condition, stuck

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
class SymmetryNote:
    """What the symmetry reduction (afsmc.lower.symmetry) did to a mission with alike
    agents: the groups of agents it keeps in a canonical order, or why it did not (and the
    property, label or reward that breaks the symmetry, if one does)."""

    groups: tuple[tuple[str, ...], ...]  # the agents of each group reduced; () if not
    reason: str | None = None  # why not, when not applied
    where: Span | None = None


@dataclass(frozen=True)
class Lowered:
    model: ir.Model
    commands: tuple[Command, ...]
    resolution: Resolution
    weights: dict[str, E.Expr]  # action -> effective weight w(s, a) (0 where not enabled)
    bounds: dict[str, tuple[str, int]] = field(default_factory=dict)  # generated const -> (interval const, value)
    reductions: tuple[str, ...] = ()  # exact reductions applied (afsmc.lower.reduce)
    # constants the backends leave undefined, for Storm's parametric engine
    # (afsmc.verify.engines.parametric): interval probabilities and params given as regions
    parameters: tuple[str, ...] = ()
    # A composed mission: its agents' commands apart (afsmc.lower.compose.Network), for
    # the backends that write one module per agent; `commands` are then their product.
    network: Any = None
    # the symmetry reduction's outcome, where there was one to tell (afsmc.lower.symmetry)
    symmetry: SymmetryNote | None = None

    @property
    def kind(self) -> Literal["dtmc", "mdp"]:
        net = self.network
        if net is not None and ((net.kind == "interleaving" and len(net.parts) > 1
                                 and net.ties != "uniform")
                                or (net.kind == "timed" and net.ties == "nondet")):
            return "mdp"
        return "mdp" if self.resolution == "nondet" and self.model.is_nondeterministic else "dtmc"


def lower(model: ir.Model, resolution: Resolution = "nondet") -> Lowered:
    if model.composition is not None:
        from afsmc.lower.compose import lower_composed

        return lower_composed(model, resolution)
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
    # The checks (W301/W302) ask the same question: deadlock_witness keeps the answer.
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
