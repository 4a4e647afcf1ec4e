"""`afsmc diagram --strategy min:NAME|max:NAME` and `--witness [min:|max:]NAME`: a
strategy's floor/ceil ends (and, in a composed mission whose agents' turns are a choice,
the actions it moves first) and the most probable path, from `afsmc.verify.run`, as
overlays of the mission diagram; in a composed mission, each agent's in its cluster."""

from __future__ import annotations

import argparse
from dataclasses import dataclass, field

from afsmc import verify as lib
from afsmc.backends.dot import Overlay
from afsmc.commands.common import overrides
from afsmc.diagnostics import CompileError, Diagnostic, Severity, codes
from afsmc.model import ir
from afsmc.model.names import did_you_mean
from afsmc.text import num, plural
from afsmc.verify.core.policy import parse
from afsmc.verify.outcome.strategy import has_choices
from afsmc.verify.outcome.witness import Witness

NOWHERE = (-1, -1, "")  # a step of the path that moves another agent


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("--strategy", metavar="min:NAME|max:NAME",
                   help="colour each action's edges by the end (floor, ceil) its interval "
                        "constants take in Storm's min or max strategy of property NAME, "
                        "where the end matters; in a composed mission whose agents' turns "
                        "are a choice, also the actions the strategy moves first")
    p.add_argument("--witness", metavar="[min:|max:]NAME",
                   help="draw the most probable path into the target of property NAME "
                        "(for an MDP following its max strategy, or the one named)")


@dataclass
class _Marks:
    """What one diagram (a machine's, or one agent's) gets drawn."""

    ends: dict[str, str] = field(default_factory=dict)
    moved: dict[str, int] = field(default_factory=dict)
    path: list[tuple[int, int, str]] = field(default_factory=list)

    def end(self, action: str, end: str) -> None:
        self.ends[action] = end if self.ends.get(action, end) == end else "floor+ceil"

    def overlay(self) -> Overlay:
        return Overlay(ends=self.ends, path=self.path, moved=self.moved)


def overlay(args: argparse.Namespace, model: ir.Model) -> tuple[Overlay, list[str]]:
    """The overlay of --strategy and --witness, and the lines of the results box."""
    comp = model.composition
    whole = _Marks()
    agents = {a.name: _Marks() for a in comp.agents} if comp is not None else {}
    notes: list[str] = []
    if args.strategy:
        direction, name = parse(args.strategy)
        res = lib.run(args.file, consts=overrides(args), properties=[name], strategy=True,
                      uniform=False)
        p = res.property(name)
        for e in (p.strategy or {}).get(direction, []):
            if e.states:
                for who in e.agents or [""]:
                    agents.get(who, whole).end(e.action, e.end)
        moved = 0
        for t in (p.turns or {}).get(direction, []):
            for who in t.agents:
                marks = agents[who].moved
                marks[t.local] = marks.get(t.local, 0) + t.states
                moved += t.states
        value, where = p.followed(direction)
        notes.append(f"{direction} strategy of {name}{where}: {num(value)}")
        if moved:
            notes.append("[moved: N states]: where the agents' order matters, the strategy "
                         "moves this action first")
    if args.witness:
        way: str | None = None
        name = args.witness
        if ":" in args.witness:
            way, name = parse(args.witness)
        _known(model, name)
        res = lib.run(args.file, consts=overrides(args), properties=[name],
                      witness=(name, 1), uniform=False,
                      witness_dir=way if has_choices(model) else None)
        p = res.property(name)
        if not p.witnesses:
            # nothing to draw; the diagram still says why
            notes.append(f"no path of {name}" + (f": {p.witness_note}" if p.witness_note
                                                  else ""))
        else:
            w = p.witnesses[0]
            if comp is None:
                whole.path = _path(model, w)
            else:
                for who, steps in _agent_paths(comp, w).items():
                    agents[who].path = steps
            # what was drawn, in verify --witness's words: a way to miss a requirement, or
            # a path into the target, and whose strategy it follows
            what = "way to miss" if p.witness_avoids else "path of"
            end = p.witness_of
            value, where = p.followed(end)
            follow = (f", following the {end} strategy{where} ({end} {num(value)})"
                      if end in ("min", "max") and value is not None else "")
            notes.append(f"most probable {what} {name}: {num(w.probability)}, "
                         f"{plural(len(w.steps), 'step')}{follow}")
    drawn = whole.overlay()
    if agents:
        drawn = Overlay(agents={who: m.overlay() for who, m in agents.items()})
    return drawn, notes


def _known(model: ir.Model, name: str) -> None:
    """E407 for a --witness naming no property, in --witness's words (the query names
    NAME_min and NAME_max are written min:NAME and max:NAME)."""
    names = [p.name for p in model.properties]
    if name in names:
        return
    base, _, end = name.rpartition("_")
    hint = (f"write {end}:{base} for the {end} strategy's path" if end in ("min", "max")
            and base in names else did_you_mean(name, names)
            or ("properties: " + ", ".join(names) if names else None))
    raise CompileError([Diagnostic(codes.E407, Severity.ERROR, f"--witness {name}: no "
                                   f"property named '{name}' in {model.source.path}", None,
                                   hint=hint)])


def _path(model: ir.Model, w: Witness) -> list[tuple[int, int, str]]:
    """A machine's path as (source mode, target mode, action or hazard) per step."""
    numbers = {m.name: m.number for m in model.modes}
    out = []
    for s in w.steps:
        source = numbers[s.mode]
        target = numbers[str(s.changes["mode"])] if "mode" in s.changes else source
        out.append((source, target, s.hazard or s.action))
    return out


def _agent_paths(comp: ir.Composition, w: Witness) -> dict[str, list[tuple[int, int, str]]]:
    """A composed mission's path, per agent: at each step of the mission, the agent's
    (source mode, target mode, action or hazard) if the step moved it, else NOWHERE."""
    numbers = {a.name: {m.name: m.number for m in a.model.modes} for a in comp.agents}
    now = {a.name: int(w.start.get(f"{a.name}.mode", a.model.initial_mode.number))
           for a in comp.agents}
    out: dict[str, list[tuple[int, int, str]]] = {a.name: [] for a in comp.agents}
    for s in w.steps:
        after = dict(now)
        for who in now:
            changed = s.changes.get(f"{who}.mode")
            if changed is not None:
                after[who] = numbers[who][str(changed)]
        took = dict(s.moved)
        for who, steps in out.items():
            steps.append((now[who], after[who], took[who]) if who in took else NOWHERE)
        now = after
    return out
