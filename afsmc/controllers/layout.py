"""What a generated controller holds, read from the checked IR before the lowering and its
reductions (the robot's variables, not the model's): the decision logic of Definition 2
as the verified model states it, in the shape both emitters (Python and C) print.

- an action is *enabled* in a state when the mode is one of its modes and its guard holds
  and, for an ordinary action, no preemptive hazard of the mode holds (a preemptive hazard
  is enabled when its guard holds): :func:`afsmc.model.semantics.enabled`;
- the controller *chooses* the enabled action of the largest weight (the checks proved
  that enabled actions never tie, E301);
- its *outcomes* are the action's own, each with its probability, after the probabilistic
  hazards of the mode are woven in, in declaration order, as the lowering weaves them
  (:func:`afsmc.lower.lowering._weave`): hazard 1 happens with p1, hazard 2 with
  (1 - p1) p2, the action's own outcome i with (1 - p1)(1 - p2) q_i;
- an outcome's updates are simultaneous; a `clamp` variable saturates at its range's
  ends; an interval constant the updates read takes the value the robot measured.
"""

from __future__ import annotations

from dataclasses import dataclass

from afsmc.diagnostics import CompileError, Diagnostic, Severity, codes
from afsmc.model import expr as E
from afsmc.model import ir
from afsmc.model.semantics import effective_weight


@dataclass(frozen=True)
class Outcome:
    """One outcome of an action or of a probabilistic hazard. `key`: how a log and `apply`
    name it: the action's own outcomes by their index (0 for the first one written), a
    hazard's by the hazard's name (`Fault`), or `Fault/1` for a hazard of several."""

    key: int | str
    prob: E.Expr
    updates: tuple[tuple[str, E.Expr], ...]  # (variable or "mode", new value), written order
    intervals: tuple[str, ...]  # the interval constants its updates read, sorted


@dataclass(frozen=True)
class Choice:
    """An action, or a preemptive hazard (kind "preemptive"), as the controller sees it."""

    name: str
    index: int
    modes: tuple[int, ...]
    kind: str  # "action" | "preemptive"
    guard: E.Expr
    weight: E.Expr
    outcomes: tuple[Outcome, ...]


@dataclass(frozen=True)
class Hazard:
    name: str
    index: int
    modes: tuple[int, ...]
    prob: E.Expr
    outcomes: tuple[Outcome, ...]


@dataclass(frozen=True)
class Layout:
    model: ir.Model
    choices: tuple[Choice, ...]
    hazards: tuple[Hazard, ...]
    # w(B) as a value: B's weight where B is enabled, else 0 (effective_weight)
    weight_refs: dict[str, E.Expr]

    @property
    def intervals(self) -> tuple[ir.Constant, ...]:
        return self.model.interval_constants

    def preemptive_in(self, mode: int) -> tuple[Choice, ...]:
        return tuple(c for c in self.choices if c.kind == "preemptive" and mode in c.modes)

    def hazards_in(self, mode: int) -> tuple[Hazard, ...]:
        return tuple(h for h in self.hazards if mode in h.modes)


def refuse_composed(model: ir.Model, what: str) -> None:
    """A composed mission has no controller yet: E701, at its `compose` line. `what`: the
    command's part, "'compile -t c' writes the controller of one machine"."""
    if model.composition is None:
        return
    span = model.composition.span
    raise CompileError([Diagnostic(
        codes.E701, Severity.ERROR,
        f"{what}; {model.name} is a mission of {len(model.composition.agents)} agents", span,
        hint="compile each agent as a machine of its own file, or use -t prism / -t jani "
             "for the composed model")])


def layout(model: ir.Model) -> Layout:
    choices = tuple(
        Choice(a.name, i, a.modes, a.kind, a.guard, a.weight,
               tuple(_outcome(model, i_o, o.prob, o.updates) for i_o, o in enumerate(a.outcomes)))
        for i, a in enumerate(model.actions))
    hazards = []
    for i, h in enumerate(model.hazards):
        several = len(h.outcomes) > 1
        hazards.append(Hazard(h.name, i, h.modes, h.prob, tuple(
            _outcome(model, f"{h.name}/{j}" if several else h.name, o.prob, o.updates)
            for j, o in enumerate(h.outcomes))))
    refs: dict[str, E.Expr] = {}
    for e in _all_exprs(choices, tuple(hazards), model):
        for n in E.walk(e):
            if isinstance(n, E.WeightRef) and n.action not in refs:
                refs[n.action] = effective_weight(model, model.action(n.action))
    # a weight reference's own expression may name further ones
    pending = list(refs.values())
    while pending:
        for n in E.walk(pending.pop()):
            if isinstance(n, E.WeightRef) and n.action not in refs:
                refs[n.action] = effective_weight(model, model.action(n.action))
                pending.append(refs[n.action])
    return Layout(model, choices, tuple(hazards), refs)


def _outcome(model: ir.Model, key: int | str, prob: E.Expr,
             updates: tuple[ir.Update, ...]) -> Outcome:
    intervals = {c.name for c in model.interval_constants}
    used = sorted({n for u in updates for n in E.consts_read(u.value)} & intervals)
    return Outcome(key, prob, tuple((u.var, u.value) for u in updates), tuple(used))


def _all_exprs(choices: tuple[Choice, ...], hazards: tuple[Hazard, ...],
               model: ir.Model) -> list[E.Expr]:
    out: list[E.Expr] = []
    for c in choices:
        out += [c.guard, c.weight]
        for o in c.outcomes:
            out += [o.prob, *(v for _, v in o.updates)]
    for h in hazards:
        out.append(h.prob)
        for o in h.outcomes:
            out += [o.prob, *(v for _, v in o.updates)]
    return out


def used_formulas(lay: Layout) -> list[str]:
    """The formulas the controller reads (directly, or through formulas and weight
    references), in declaration order: a C compiler warns of an unused static function."""
    model = lay.model
    todo = [*_all_exprs(lay.choices, lay.hazards, model), *lay.weight_refs.values()]
    seen: set[str] = set()
    while todo:
        for n in E.walk(todo.pop()):
            if isinstance(n, E.FormulaRef) and n.name not in seen:
                seen.add(n.name)
                todo.append(model.formula(n.name).value)
    return [f.name for f in model.formulas if f.name in seen]
