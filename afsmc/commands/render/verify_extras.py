"""`afsmc verify --strategy` and `--witness K`: their options, tables and traces."""

from __future__ import annotations

import argparse
import json
import math

from afsmc.commands.common import integer
from afsmc.files import write_atomic
from afsmc.text import literal, num, plural
from afsmc.verify import VerifyResult
from afsmc.verify.outcome.results import PropertyResult
from afsmc.verify.outcome.strategy import DIRECTIONS, MAX_WITNESSES


def add_arguments(p: argparse.ArgumentParser) -> None:
    g = p.add_argument_group("strategies and failure paths")
    g.add_argument("--strategy", action="store_true",
                   help="for an MDP, show Storm's min and max strategies in the mission's "
                        "terms: which interval constant takes its floor or its ceiling, in "
                        "which action and mode, in how many states (sparse engine)")
    g.add_argument("--witness", type=integer(1, MAX_WITNESSES), metavar="K",
                   help="the K most probable paths into the target of the property (name "
                        f"it with -p NAME), as mission traces; K from 1 to {MAX_WITNESSES:,}")
    g.add_argument("--witness-dir", choices=DIRECTIONS, metavar="{min,max}",
                   help="for an MDP, the strategy the --witness paths follow (default: "
                        "max, or the property's own Pmin/Pmax)")
    g.add_argument("--traces-out", metavar="PATH",
                   help="write the --witness paths as JSON traces, in the format of "
                        "`afsmc simulate --traces-out`")


def witness(args: argparse.Namespace) -> tuple[str | None, int] | None:
    """The --witness request: (the property named with -p, or None for the only one, K)."""
    if args.witness is None:
        return None
    return (args.property[0] if len(args.property) == 1 else None, args.witness)


def render(res: VerifyResult) -> str:
    """The strategies' table and the witness paths, after verify's own table ("" if none)."""
    lines: list[str] = []
    asked = any(p.strategy is not None for p in res.properties)
    for p in res.properties:
        ends = p.strategy is not None and any(p.strategy.values())
        if p.strategy is not None:
            if ends or p.turns is None:
                # else a composed mission whose strategies resolve no interval constant:
                # its turns below are all they choose
                lines += ["", *strategy_lines(p)]
        elif asked:
            lines += ["", f"strategies of {p.name} ({p.formula}): none, as it is step-bounded "
                      "(its strategies count the steps; Storm gives no scheduler for them)"]
        if p.turns is not None:
            lines += ["", *turn_lines(p)]
        if p.witnesses is not None:
            lines += ["", *witness_lines(p)]
    return "\n".join(lines)


def strategy_lines(p: PropertyResult) -> list[str]:
    from afsmc.commands.verify import table

    assert p.strategy is not None
    out = [f"strategies of {p.name} ({p.formula}): the end each interval constant takes, "
           "in the states the strategy reaches where the end matters (either: further "
           "states where both ends give the same value)"]
    rows = [["strategy", "constant", "end", "action", "mode", "states", "either", "when"]]
    for opt in ("min", "max"):
        for e in p.strategy.get(opt, []):
            rows.append([opt, e.constant, f"{e.value} ({e.end})", e.action, e.mode,
                         f"{e.states:,}", f"{e.indifferent:,}", e.when or "-"])
    if len(rows) == 1:
        out.append("  (no choice matters: in every state the strategies reach, both ends of "
                   "each interval constant give the same value)")
        return out
    out += ["  " + line for line in table(rows, {5, 6})]
    return out


def turn_lines(p: PropertyResult) -> list[str]:
    """A composed mission's turns: which agent each strategy moves where it matters."""
    from afsmc.commands.verify import table

    assert p.turns is not None
    out = [f"turns of {p.name} ({p.formula}): the agent each strategy moves, in the states "
           "it reaches where the choice matters"]
    rows = [["strategy", "moves", "mode", "states"]]
    for opt in ("min", "max"):
        rows += [[opt, e.action, e.mode, f"{e.states:,}"] for e in p.turns.get(opt, [])]
    if len(rows) == 1:
        return [*out, "  (no choice: in every state the strategies reach, who moves first "
                "makes no difference)"]
    return out + ["  " + line for line in table(rows, {3})]


def witness_lines(p: PropertyResult) -> list[str]:
    assert p.witnesses is not None
    value, where = p.followed(p.witness_of)
    ws = p.witnesses
    mass = math.fsum(w.probability for w in ws)
    follow = (f" following the {p.witness_of} strategy" if p.witness_of in DIRECTIONS
              else "") + where
    of = f"{p.witness_of}{where} {num(value)}" if value is not None else ""
    if p.witness_avoids and value is not None:  # the paths that miss it: 1 - value in all
        value, of = 1.0 - value, f"1 - {of} = {num(1.0 - value)}"
    share = f", {100 * mass / value:.1f}% of {of}" if value else ""
    what = "ways to miss" if p.witness_avoids else "paths of"
    if not ws:
        return [f"no {what} {p.name} ({p.formula}){follow}"
                + (f": {p.witness_note}" if p.witness_note else "")]
    many = f"the {len(ws)} most probable {what}" if len(ws) > 1 else \
        f"the most probable {what.replace('ways', 'way').replace('paths', 'path')}"
    out = [f"{many} {p.name} ({p.formula}){follow}: total {num(mass)}{share}"]
    if p.witness_note:
        out.append(f"  ({p.witness_note})")
    for i, w in enumerate(ws, 1):
        check = "" if w.confirmed else " (NOT confirmed by replaying it through the model)"
        out.append(f"path {i}: probability {num(w.probability)}, {plural(len(w.steps), 'step')}, "
                   f"ends in {w.end_mode}{check}")
        for j, s in enumerate(w.steps, 1):
            changes = " ".join(f"{k}={literal(v)}" for k, v in s.changes.items())
            how = s.action + (f" [hazard {s.hazard}]" if s.hazard else "")
            ends = "".join(f" {c}={e}" for c, e in s.choice)
            out.append(f"  {j:>4}  {s.mode}: {how}{ends}  p={num(s.probability)}  {changes}"
                       .rstrip())
    return out


def write_traces(path: str, res: VerifyResult, source: str) -> None:
    """The witness paths as `simulate --traces-out` writes runs: a JSON list of traces."""
    traces = [w.trace(w.steps[0].mode if w.steps else w.end_mode)
              for p in res.properties for w in p.witnesses or []]
    write_atomic(path, json.dumps(traces, indent=1) + "\n", protect=(source,))
