"""Graphviz backend: the mission diagram (the paper's Figure 1) as DOT.

A pure function of the IR and its mode graph (`afsmc.check.modegraph.analyse`):

* one box per mode, `Name` over its number; the initial mode has a bold border and an
  arrow from a start dot; final modes are double boxes;
* one edge per (source mode, target mode), labelled with the actions that take it, and
  the probability where it is not 1 (outcomes of one action to the same mode summed);
  an outcome without `goto` is a self-loop;
* a hazard (probabilistic or preemptive) that leaves two or more modes for the same mode,
  and an ordinary action that does so from three or more, is drawn once: an ellipse
  listing the source modes like the paper (`{0..15}`, `{1..11, 14, 15}`) with one edge;
* the mode-graph findings: unreachable modes (W601) dashed and grey, modes from which the
  mission cannot end (W602) with a red border, actions that never fire (W603) as dashed
  grey edges marked "(never)".

Everything is emitted in sorted order, so the text is byte-identical across runs.
"""

from __future__ import annotations

import os
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field

import graphviz

from afsmc import __version__
from afsmc.check.modegraph import ModeGraph, analyse, compact
from afsmc.lower.lowering import Lowered
from afsmc.model import expr as E
from afsmc.model import ir
from afsmc.model.pretty import with_names
from afsmc.model.semantics import static_value
from afsmc.text import short

FONT = "Helvetica,Arial,sans-serif"
INK = "#3d4f66"  # borders and ordinary edges
FILL = "#eef3f9"
HAZARD = "#a93226"  # probabilistic hazards
PREEMPT = "#b9770e"  # preemptive hazards
DEAD = "#a0a0a0"  # what the mode graph says never happens
COLORS = {"action": INK, "preemptive": PREEMPT, "hazard": HAZARD}
GROUP_FILL = {"action": "#f4f6f8", "preemptive": "#fcf3e3", "hazard": "#fbeae8"}
ENDS = {"floor": "#1f6fb2", "ceil": "#c0392b", "floor+ceil": "#7d3c98"}  # --strategy
MOVED = "#117a65"  # --strategy: an action a composed mission's strategy moves first
PATH = "#1e8449"  # --witness


@dataclass(frozen=True)
class Overlay:
    """Numbers drawn on the diagram: a line per mode, and a box of property results."""

    modes: Mapping[int, str] = field(default_factory=dict)
    notes: Sequence[str] = ()
    caption: str = ""
    # a strategy (`diagram --strategy`): action -> the end its interval constants take
    # where it matters ("floor", "ceil" or "floor+ceil"), drawn in the edge's colour
    ends: Mapping[str, str] = field(default_factory=dict)
    # a path (`diagram --witness`): its steps as (source mode, target mode, action or
    # hazard), drawn bold with their step numbers
    path: Sequence[tuple[int, int, str]] = ()
    # a composed mission's strategy that chooses the agents' turns (`diagram --strategy`):
    # action -> in how many states the strategy moves it where the choice matters
    moved: Mapping[str, int] = field(default_factory=dict)
    # a composed mission: each agent's own overlay, drawn in its cluster (the path's steps
    # numbered over the whole mission: a step that moves another agent is (-1, -1, ""))
    agents: Mapping[str, Overlay] = field(default_factory=dict)


@dataclass(frozen=True)
class _Arc:
    source: int
    target: int
    via: str
    kind: str  # action | preemptive | hazard
    prob: E.Expr
    live: bool


def _html(text: str) -> str:
    return text.replace("&", "&amp;").replace("<", "&lt;").replace(">", "&gt;")


def _prob_text(prob: E.Expr, model: ir.Model) -> str:
    box = {c.name: c.prob_interval for c in model.prob_intervals
           if c.prob_interval is not None and c.name in E.consts_read(prob)}
    if box:
        # an interval probability: the range over its interval, not its midpoint, since
        # the verified bounds range over it too (docs/verification.md)
        ends = _over_box(prob, model, box)
        if ends is not None:
            return f"{short(ends[0], 3)}–{short(ends[1], 3)}"
    v = static_value(prob, model)
    if v is None:
        text = with_names(model.display_names())(prob)
        return text if len(text) <= 24 else text[:23] + "…"
    if abs(v - 1.0) < 1e-12:
        return ""
    return short(v, 3)


def _over_box(prob: E.Expr, model: ir.Model,
              box: Mapping[str, tuple[float, float]]) -> tuple[float, float] | None:
    """The least and greatest value of a state-free probability at the corners of the
    interval probabilities' box (exact for the products and complements a branch's
    probability is made of); None if it reads the state."""
    import itertools

    from afsmc.model.evaluate import EvalError, scalar

    if static_value(prob, model) is None:
        return None
    names = sorted(box)
    values = []
    for corner in itertools.product(*(box[n] for n in names)):
        try:
            values.append(float(scalar(prob, model.const_values | dict(zip(names, corner,
                                                                            strict=True)))))
        except (EvalError, ZeroDivisionError, OverflowError):
            return None
    return min(values), max(values)


def _item(arc: _Arc, model: ir.Model) -> str:
    p = _prob_text(arc.prob, model)
    text = arc.via + (f" ({p})" if p else "")
    return text if arc.live else text + " (never)"


def _arcs(mg: ModeGraph) -> list[_Arc]:
    """The mode graph's edges, plus those of actions in modes where they never fire."""
    model = mg.model
    arcs = [_Arc(e.source, e.target, e.via, e.kind, e.prob, True) for e in mg.edges]
    finals = {m.number for m in model.modes if m.final}
    for a in model.actions:
        for n in mg.never_fires(a):
            if n in finals:
                continue
            targets: dict[int, E.Expr] = {}
            for o in a.outcomes:
                t = next((u.value.number for u in o.updates
                          if u.var == "mode" and isinstance(u.value, E.ModeVal)), n)
                targets[t] = (E.Binary("+", targets[t], o.prob, E.Type.DOUBLE)
                              if t in targets else o.prob)
            arcs += [_Arc(n, t, a.name, a.kind, p, False) for t, p in sorted(targets.items())]
    return arcs


def _group_id(sources: tuple[int, ...], kind: str, live: bool) -> str:
    runs = "_".join(f"{lo}to{hi}" if hi > lo else str(lo) for lo, hi in E.runs(list(sources)))
    return f"grp_{runs}_{kind}" + ("" if live else "_never")


def diagram(model: ir.Model, overlay: Overlay | None = None) -> graphviz.Digraph:
    """The mission as a graphviz.Digraph (nothing is rendered here)."""
    if model.composition is not None:
        from afsmc.backends.dot_network import network

        return network(model, diagram, overlay or Overlay())
    mg = analyse(model)
    overlay = overlay or Overlay()
    g = _graph(model, overlay)
    unreachable = set(mg.unreachable)
    _mode_nodes(g, model, overlay, unreachable, set(mg.cannot_end))
    arcs = _arcs(mg)
    groups, group_edges, grouped = _groups(arcs)
    _group_nodes(g, model, groups)
    _edges(g, model, arcs, group_edges, grouped, unreachable, overlay)
    if overlay.notes:
        g.node("results", "".join(line + "\\l" for line in overlay.notes), shape="note",
               style="filled", fillcolor="#fffdf0", color="#b7a96b", fontsize="10",
               tooltip="results")
    return g


def _graph(model: ir.Model, overlay: Overlay) -> graphviz.Digraph:
    """An empty digraph with the caption and the default node and edge styles."""
    g = graphviz.Digraph(
        model.name,
        comment=f"Generated by afsmc {__version__} from {os.path.basename(model.source.path)} "
                f"(machine {model.name}). Render: dot -Tsvg FILE.dot -o FILE.svg")
    caption = f"<machine <b>{_html(model.name)}</b>" + (
        f'<br/><font point-size="10">{_html(overlay.caption)}</font>' if overlay.caption
        else "") + ">"
    g.attr("graph", rankdir="TB", label=caption, labelloc="t", fontname=FONT, fontsize="13",
           nodesep="0.35", ranksep="0.45", pad="0.2", bgcolor="white", newrank="true")
    g.attr("node", shape="box", style="rounded,filled", fillcolor=FILL, color=INK,
           fontname=FONT, fontsize="11", margin="0.12,0.05", penwidth="1.1")
    g.attr("edge", fontname=FONT, fontsize="9", color=INK, fontcolor="#2b2b2b",
           arrowsize="0.7", penwidth="1.0")
    return g


def _mode_nodes(g: graphviz.Digraph, model: ir.Model, overlay: Overlay, unreachable: set[int],
                cannot_end: set[int]) -> None:
    """The start point and one node per mode, styled by what the mode graph says of it."""
    init = model.initial_mode.number
    g.node("start", "", shape="point", width="0.09", color=INK, fillcolor=INK,
           tooltip="start")
    for m in sorted(model.modes, key=lambda m: m.number):
        lines = [m.name, str(m.number)]
        attrs: dict[str, str] = {"tooltip": f"mode {m.name} = {m.number}" + (
            " initial" if m.initial else "") + (" final" if m.final else "")}
        if m.number in overlay.modes:
            lines.append(overlay.modes[m.number])
        if m.number in unreachable:
            lines.append("(unreachable)")
            attrs.update(style="rounded,filled,dashed", fillcolor="#f4f4f4", color=DEAD,
                         fontcolor="#808080", tooltip=attrs["tooltip"] + ": unreachable (W601)")
        elif m.number in cannot_end:
            lines.append("(cannot end)")
            attrs.update(color=HAZARD, penwidth="1.8",
                         tooltip=attrs["tooltip"] + ": the mission cannot end from here (W602)")
        if m.number == init:
            attrs["penwidth"] = "2.2"
        if m.final:
            attrs["peripheries"] = "2"
        g.node(f"m{m.number}", "\\n".join(lines), **attrs)
    g.edge("start", f"m{init}", arrowsize="0.6")


_Groups = dict[str, tuple[tuple[int, ...], str, bool]]
_GroupEdges = dict[tuple[str, int, bool], list[_Arc]]
_Grouped = set[tuple[int, str, int, bool]]


def _groups(arcs: list[_Arc]) -> tuple[_Groups, _GroupEdges, _Grouped]:
    """Group the edges of one hazard (or widely shared action) into one ellipse node:
    the groups by id, their outgoing edges, and the (source, via, target, live) arcs they
    cover."""
    by_via: dict[tuple[str, str, int, bool], list[_Arc]] = {}
    for arc in arcs:
        if arc.source != arc.target:
            by_via.setdefault((arc.via, arc.kind, arc.target, arc.live), []).append(arc)
    grouped: _Grouped = set()
    groups: _Groups = {}
    group_edges: _GroupEdges = {}
    for (via, kind, target, live), items in by_via.items():
        sources = tuple(sorted({a.source for a in items}))
        if len(sources) < (3 if kind == "action" else 2):
            continue
        gid = _group_id(sources, kind, live)
        groups[gid] = (sources, kind, live)
        # One representative arc carries the label (the probability is the same in every
        # covered mode unless it reads the mode, which is rare; then the first is shown).
        group_edges.setdefault((gid, target, live), []).append(items[0])
        grouped |= {(a.source, via, target, live) for a in items}
    return groups, group_edges, grouped


def _group_nodes(g: graphviz.Digraph, model: ir.Model, groups: _Groups) -> None:
    for gid, (sources, kind, live) in sorted(groups.items()):
        names = ", ".join(model.mode_by_number(n).name for n in sources)
        g.node(gid, compact(sources), shape="ellipse", style="filled" if live else "filled,dashed",
               fillcolor=GROUP_FILL[kind] if live else "#f4f4f4",
               color=COLORS[kind] if live else DEAD, fontsize="10",
               tooltip=f"from any of: {names}")


def _node_key(nid: str) -> tuple[int, str]:
    """Modes first, by number; then group nodes by id."""
    return (0, f"{int(nid[1:]):09d}") if nid.startswith("m") else (1, nid)


def _edges(g: graphviz.Digraph, model: ir.Model, arcs: list[_Arc], group_edges: _GroupEdges,
           grouped: _Grouped, unreachable: set[int], overlay: Overlay) -> None:
    """One edge per (source node, target node, live), labelled with every arc it carries."""
    plain: dict[tuple[str, str, bool], list[_Arc]] = {}
    for arc in arcs:
        if (arc.source, arc.via, arc.target, arc.live) in grouped:
            continue
        plain.setdefault((f"m{arc.source}", f"m{arc.target}", arc.live), []).append(arc)
    for (gid, target, live), items in group_edges.items():
        plain.setdefault((gid, f"m{target}", live), []).extend(items)

    for (src, dst, live), items in sorted(plain.items(),
                                          key=lambda kv: (_node_key(kv[0][0]),
                                                          _node_key(kv[0][1]), not kv[0][2])):
        labels = sorted({_item(a, model) for a in items})
        kinds = {a.kind for a in items}
        kind = "action" if "action" in kinds else ("preemptive" if "preemptive" in kinds
                                                    else "hazard")
        attrs = {"label": "\\n".join(labels), "tooltip": "; ".join(_tooltip(a, model)
                                                                    for a in items)}
        if not live:
            attrs.update(style="dashed", color=DEAD, fontcolor="#808080")
        elif src.startswith("m") and int(src[1:]) in unreachable:
            attrs.update(color=DEAD, fontcolor="#808080")
        elif kind != "action":
            attrs.update(color=COLORS[kind], fontcolor=COLORS[kind])
        _overlaid(attrs, items, overlay)
        g.edge(src, dst, **attrs)


def _overlaid(attrs: dict[str, str], items: list[_Arc], overlay: Overlay) -> None:
    """A strategy's ends (colour, and the end in the label) and a path's steps (bold, with
    their numbers) on one edge."""
    ends = sorted({overlay.ends[a.via] for a in items if a.via in overlay.ends})
    if ends:
        end = ends[0] if len(ends) == 1 else "floor+ceil"
        attrs.update(color=ENDS[end], fontcolor=ENDS[end], penwidth="2.0",
                     label=attrs["label"] + f"\\n[{end}]")
    moved = sum(overlay.moved.get(via, 0) for via in {a.via for a in items})
    if moved:
        attrs.update(color=MOVED, fontcolor=MOVED, penwidth="2.0",
                     label=attrs["label"] + f"\\n[moved: {moved:,} states]")
    steps = [str(i) for i, (a, b, via) in enumerate(overlay.path, 1)
             if any((x.source, x.target, x.via) == (a, b, via) for x in items)]
    if steps:
        shown = ", ".join(steps) if len(steps) <= 4 else (
            f"{steps[0]}, {steps[1]} … {steps[-1]} ({len(steps)} times)")
        attrs.update(color=PATH, fontcolor=PATH, penwidth="3.0",
                     label=attrs["label"] + "\\nstep " + shown)


def _tooltip(arc: _Arc, model: ir.Model) -> str:
    p = with_names(model.display_names())
    if arc.kind == "hazard":
        h = next(h for h in model.hazards if h.name == arc.via)
        return f"hazard {h.name}: probability {p(h.prob)}"
    a = model.action(arc.via)
    parts = [("hazard " if a.kind == "preemptive" else "action ") + a.name]
    if not (isinstance(a.guard, E.Lit) and a.guard.value is True):
        parts.append(f"when {p(a.guard)}")
    if a.kind == "action" and not (isinstance(a.weight, E.Lit) and a.weight.value == 1):
        parts.append(f"weight {p(a.weight)}")
    return " ".join(parts)


def source(model: ir.Model, overlay: Overlay | None = None) -> str:
    text: str = diagram(model, overlay).source
    return text


def files(low: Lowered) -> dict[str, str]:
    """`afsmc compile -t dot`: the diagram's DOT source."""
    return {".dot": source(low.model)}
