"""The mode graph: which mode can follow which, and what that says about the mission.

Nodes are modes; an edge `M -> N` exists when some action (or hazard) can fire in M and
one of its outcomes moves to N (an outcome without `goto` stays: a self-loop). Only
actions that can fire contribute edges: an action fires in a mode iff some state of the
mode satisfies `fire_condition` (enabled, and beating every enabled competitor), decided
exactly by `afsmc.model.search.find`. A tie of weights (E301) counts as a state where
either action may fire, so that no warning here contradicts the tie. Probabilistic hazards are woven into the commands
of their modes, so they move a mode only where some action of it fires. Final modes are
absorbing: nothing leaves them. Outcomes whose probability is the constant 0 are dropped.

The graph over-approximates the state space (a mode edge may need a state the machine
never reaches), so every conclusion below is sound for a warning:

* W601: a mode no path from the initial mode reaches is never entered.
* W602: a mode, reachable from the initial mode, from which no *terminal* mode is
  reachable: the mission cannot end once it gets there. Terminal modes are the final
  modes and the modes whose only way out is to stay (no edge to another mode: e.g. a
  deadlocked mode, which W301/W302 already report, or an implicit sink).
* W603: an action that can never fire in some (or all) of its modes: its guard is
  unsatisfiable there, a preemptive hazard always disables it, or a competitor always
  beats it.

The analysis is kept with the model (`model.memo.modegraph`), so `afsmc check` and the
diagram share one computation.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Literal

import networkx as nx

from afsmc.diagnostics import Reporter, Span, codes
from afsmc.model import expr as E
from afsmc.model import ir
from afsmc.model.search import exists
from afsmc.model.semantics import competitors, enabled, fire_condition, static_value

EdgeKind = Literal["action", "preemptive", "hazard"]


@dataclass(frozen=True)
class Edge:
    source: int
    target: int
    via: str  # the action's or hazard's name
    kind: EdgeKind
    # The probability of moving to `target` when `via` fires (outcomes to the same target
    # summed); for a probabilistic hazard, the hazard's probability times its outcome's.
    prob: E.Expr
    span: Span  # the name of the action or hazard


@dataclass(frozen=True)
class ModeGraph:
    model: ir.Model
    edges: tuple[Edge, ...]  # sorted by (source, target, kind, via)
    fires: dict[tuple[str, int], bool]  # (action, mode) -> can fire there
    reachable: frozenset[int]  # from the initial mode
    terminal: frozenset[int]
    cannot_end: tuple[int, ...]  # reachable, non-terminal, no path to a terminal mode

    @property
    def unreachable(self) -> tuple[int, ...]:
        return tuple(m.number for m in self.model.modes if m.number not in self.reachable)

    def never_fires(self, action: ir.Action) -> tuple[int, ...]:
        return tuple(m for m in action.modes if not self.fires.get((action.name, m), False))

    def digraph(self) -> Any:
        """The graph as a networkx DiGraph (an edge per source/target pair)."""
        g = nx.DiGraph()
        g.add_nodes_from(m.number for m in self.model.modes)
        g.add_edges_from((e.source, e.target) for e in self.edges)
        return g


def _sum(a: E.Expr, b: E.Expr) -> E.Expr:
    return E.Binary("+", a, b, E.Type.DOUBLE)


def _outcome_edges(model: ir.Model, source: int, via: str, kind: EdgeKind,
                   outcomes: tuple[ir.Outcome, ...], span: Span,
                   scale: E.Expr | None) -> list[Edge]:
    by_target: dict[int, E.Expr] = {}
    for o in outcomes:
        target = source
        for u in o.updates:
            if u.var == "mode" and isinstance(u.value, E.ModeVal):
                target = u.value.number
        prob = o.prob if scale is None else E.mul(scale, o.prob)
        by_target[target] = _sum(by_target[target], prob) if target in by_target else prob
    out = []
    for target, prob in sorted(by_target.items()):
        if static_value(prob, model) == 0:
            continue
        out.append(Edge(source, target, via, kind, prob, span))
    return out


def analyse(model: ir.Model) -> ModeGraph:
    known = model.memo.modegraph
    if isinstance(known, ModeGraph):
        return known
    finals = {m.number for m in model.modes if m.final}
    fires: dict[tuple[str, int], bool] = {}
    edges: list[Edge] = []
    for a in model.actions:
        for mode in a.modes:
            ok = mode not in finals and exists(model, mode,
                                               fire_condition(model, a, mode, ties=True))
            fires[(a.name, mode)] = ok
            if ok:
                edges += _outcome_edges(model, mode, a.name, a.kind, a.outcomes, a.name_span, None)
    for h in model.hazards:
        if static_value(h.prob, model) == 0:
            continue
        for mode in h.modes:
            # woven into every command of the mode, preemptive hazards' included
            if any(fires.get((a.name, mode), False) for a in model.actions_in(mode)):
                edges += _outcome_edges(model, mode, h.name, "hazard", h.outcomes, h.name_span,
                                        h.prob)
    order = {"action": 0, "preemptive": 1, "hazard": 2}
    edges.sort(key=lambda e: (e.source, e.target, order[e.kind], e.via))

    g = nx.DiGraph()
    g.add_nodes_from(m.number for m in model.modes)
    g.add_edges_from((e.source, e.target) for e in edges)
    init = model.initial_mode.number
    reachable = frozenset(nx.descendants(g, init) | {init})
    terminal = frozenset(m.number for m in model.modes
                         if m.final or all(t == m.number for t in g.successors(m.number)))
    can_end: set[int] = set(terminal)
    for t in terminal:
        can_end |= nx.ancestors(g, t)
    cannot_end = tuple(m.number for m in model.modes
                       if m.number in reachable and m.number not in can_end)
    result = ModeGraph(model, tuple(edges), fires, reachable, terminal, cannot_end)
    model.memo.modegraph = result
    return result


def compact(numbers: list[int] | tuple[int, ...]) -> str:
    """Mode numbers the way the paper writes them: `{0..15}`, `{1..11, 14, 15}`."""
    parts: list[str] = []
    for lo, hi in E.runs(sorted(set(numbers))):
        if hi - lo >= 2:
            parts.append(f"{lo}..{hi}")
        else:
            parts += [str(n) for n in range(lo, hi + 1)]
    return "{" + ", ".join(parts) + "}"


def _names(model: ir.Model, numbers: tuple[int, ...]) -> str:
    return ", ".join(model.mode_by_number(n).name for n in numbers)


def check_unreachable(model: ir.Model, rep: Reporter) -> None:
    mg = analyse(model)
    for n in mg.unreachable:
        m = model.mode_by_number(n)
        rep.warning(codes.W601, f"mode {m.name} ({n}) is unreachable from the initial mode "
                    f"{model.initial_mode.name}", m.span,
                    hint="no action or hazard that can fire leads here; add a 'goto "
                         f"{m.name}' or remove the mode")


def check_cannot_end(model: ir.Model, rep: Reporter) -> None:
    mg = analyse(model)
    if not mg.cannot_end:
        return
    g = mg.digraph()
    for n in mg.cannot_end:
        m = model.mode_by_number(n)
        region = sorted(nx.descendants(g, n) | {n})
        rep.warning(codes.W602, f"the mission cannot end once in mode {m.name} ({n}): no path "
                    "leads to a final mode, nor to a mode the machine stays in for good", m.span,
                    hint=f"every path from here stays among modes {compact(region)}; mark a "
                         "mode 'final' or add a way out")


def _why(mg: ModeGraph, a: ir.Action, modes: tuple[int, ...]) -> str:
    """Tell a guard that never holds from a competitor that always wins."""
    model = mg.model
    if not any(exists(model, n, enabled(model, a, n)) for n in modes):
        if a.kind == "preemptive":
            return "its condition never holds"
        if any(b.kind == "preemptive" for n in modes for b in model.actions_in(n)):
            return "its guard never holds while no preemptive hazard does"
        return "its guard never holds"
    beaters = [(b, n) for n in modes for b in competitors(model, a, n)]
    # only the competitors enabled together with it somewhere: a rival with a disjoint
    # guard is not what beats it
    rivals = sorted({b.name for b, n in beaters if mg.fires.get((b.name, n), False)
                     and exists(model, n, E.Binary("&&", enabled(model, a, n),
                                                   enabled(model, b, n), E.Type.BOOL))}) \
        or sorted({b.name for b, _ in beaters})
    return "an enabled competitor always has a larger weight (" + ", ".join(rivals) + ")"


def check_never_fires(model: ir.Model, rep: Reporter) -> None:
    mg = analyse(model)
    finals = {m.number for m in model.modes if m.final}
    for a in model.actions:
        what = "hazard" if a.kind == "preemptive" else "action"
        never = tuple(n for n in mg.never_fires(a) if n not in finals)
        if not never:
            continue
        live = [n for n in a.modes if n not in finals]
        where = "" if len(never) == len(live) else f" in mode(s) {_names(model, never)}"
        rep.warning(codes.W603, f"{what} {a.name} can never fire{where}: {_why(mg, a, never)}",
                    a.name_span, hint="its outcomes are left out of the mode graph; check its "
                    "guard and weight against the other actions of " + _names(model, never))


RULES = (check_unreachable, check_cannot_end, check_never_fires)
