"""`afsmc diagram --strategy min:NAME|max:NAME` and `--witness [min:|max:]NAME`: a
strategy's floor/ceil ends and the most probable path, from `afsmc.verify.run`, as
overlays of the mission diagram."""

from __future__ import annotations

import argparse

from afsmc import verify as lib
from afsmc.backends.dot import Overlay
from afsmc.commands.common import overrides
from afsmc.model import ir
from afsmc.text import num
from afsmc.verify.policy import parse
from afsmc.verify.strategy import refuse


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("--strategy", metavar="min:NAME|max:NAME",
                   help="colour each action's edges by the end (floor, ceil) its interval "
                        "constants take in Storm's min or max strategy of property NAME, "
                        "where the end matters")
    p.add_argument("--witness", metavar="[min:|max:]NAME",
                   help="draw the most probable path into the target of property NAME "
                        "(for an MDP following its max strategy, or the one named)")


def overlay(args: argparse.Namespace, model: ir.Model) -> tuple[Overlay, list[str]]:
    """The overlay of --strategy and --witness, and the lines of the results box."""
    ends: dict[str, str] = {}
    path: list[tuple[int, int, str]] = []
    notes: list[str] = []
    if args.strategy:
        direction, name = parse(args.strategy)
        res = lib.run(args.file, consts=overrides(args), properties=[name], strategy=True,
                      uniform=False)
        p = res.property(name)
        entries = (p.strategy or {}).get(direction, [])
        for e in entries:
            if e.states:
                ends[e.action] = e.end if ends.get(e.action, e.end) == e.end else "floor+ceil"
        notes.append(f"{direction} strategy of {name}: {num(getattr(p, direction))}")
    if args.witness:
        way: str | None = None
        name = args.witness
        if ":" in args.witness:
            way, name = parse(args.witness)
        res = lib.run(args.file, consts=overrides(args), properties=[name],
                      witness=(name, 1), uniform=False,
                      witness_dir=way if model.is_nondeterministic else None)
        p = res.property(name)
        if not p.witnesses:
            raise refuse(f"--witness {args.witness}: no path into the target of {name}"
                         + (f" ({p.witness_note})" if p.witness_note else ""))
        w = p.witnesses[0]
        numbers = {m.name: m.number for m in model.modes}
        for s in w.steps:
            source = numbers[s.mode]
            target = numbers[str(s.changes["mode"])] if "mode" in s.changes else source
            path.append((source, target, s.hazard or s.action))
        notes.append(f"most probable path of {name}: {num(w.probability)}, "
                     f"{len(w.steps)} steps")
    return Overlay(ends=ends, path=path), notes
