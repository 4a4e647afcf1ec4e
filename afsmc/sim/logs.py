"""Simulated runs in the robot's log format (docs/robot.md, "The log format"), the format
`afsmc conform` reads: one object per step with the mode the step starts in, the action,
the outcome (an index into the action's outcomes, or a hazard's name), the measured
value of the interval constants its updates read (`duration`) and the variables it
changed (`changes`, `mode` among them when it changes).

The simulator's sample runs (`--traces K`) are lists of states, each with the action
that led to it; :func:`outcomes` tells which outcome of the .afsm file each branch of a
lowered command is and the interval constants' values it takes, so that the runs can be
written as steps.
"""

from __future__ import annotations

import csv
import io
import itertools
import json
from typing import Any

from afsmc.lower.lowering import Lowered
from afsmc.model import expr as E
from afsmc.model import ir


def outcome_key(model: ir.Model, action: str, hazard: str | None, span: object) -> int | str:
    """How a log names the outcome written at `span`: its index among the action's
    outcomes, or the hazard's name (`H/j` for outcome j of a hazard of several)."""
    if hazard is not None:
        h = next(x for x in model.hazards if x.name == hazard)
        j = next(i for i, o in enumerate(h.outcomes) if o.span == span)
        return f"{hazard}/{j}" if len(h.outcomes) > 1 else hazard
    a = model.action(action)
    return next(i for i, o in enumerate(a.outcomes) if o.span == span)


def outcomes(low: Lowered) -> dict[tuple[int, int], dict[str, Any]]:
    """(command index, branch index) -> {"outcome": key, "duration": value} for every
    branch of an action's command (a duration only where the branch reads interval
    constants: a number for one, {NAME: value} for several). Empty for a composed
    mission, whose steps are the agents' (not in this format yet)."""
    if low.network is not None:
        return {}
    model = low.model
    out: dict[tuple[int, int], dict[str, Any]] = {}
    for i, cmd in enumerate(low.commands):
        if cmd.silent:
            continue
        for j, b in enumerate(cmd.branches):
            entry: dict[str, Any] = {"outcome": outcome_key(model, cmd.action, b.hazard, b.span)}
            used = sorted({low.bounds[n] for _, v in b.updates for n in E.consts_read(v)
                           if n in low.bounds})
            if len(used) == 1:
                entry["duration"] = used[0][1]
            elif used:
                entry["duration"] = dict(used)
            out[(i, j)] = entry
    return out


def steps(trace: list[dict[str, Any]], run: int) -> list[dict[str, Any]]:
    """One sample run (a list of states, as `simulate --traces` keeps them) as log steps."""
    out = []
    for before, after in itertools.pairwise(trace):
        action = after.get("action")
        if action is None or action.startswith("("):  # a final mode's or a deadlock's stay
            break
        step: dict[str, Any] = {"run": run, "step": before["step"], "mode": before["mode"],
                                "action": action}
        for key in ("outcome", "duration"):
            if key in after:
                step[key] = after[key]
        changes = {k: v for k, v in after["vars"].items() if before["vars"].get(k) != v}
        if after["mode"] != before["mode"]:
            changes["mode"] = after["mode"]
        step["changes"] = changes
        out.append(step)
    return out


def jsonl(traces: list[list[dict[str, Any]]]) -> str:
    """The runs as JSON Lines, one step a line, the runs numbered from 0."""
    return "".join(json.dumps(s, separators=(", ", ": ")) + "\n"
                   for r, tr in enumerate(traces) for s in steps(tr, r))


COLUMNS = ("run", "step", "mode", "action", "outcome", "duration", "changes")


def csv_text(traces: list[list[dict[str, Any]]]) -> str:
    """The runs as CSV with the same columns: `changes` and a duration of several
    constants as `NAME=VALUE` pairs separated by spaces."""
    buf = io.StringIO()
    w = csv.writer(buf, lineterminator="\n")
    w.writerow(COLUMNS)
    for r, tr in enumerate(traces):
        for s in steps(tr, r):
            row = []
            for c in COLUMNS:
                v = s.get(c, "")
                if isinstance(v, dict):
                    v = " ".join(f"{k}={_cell(x)}" for k, x in v.items())
                row.append(_cell(v) if not isinstance(v, str) else v)
            w.writerow(row)
    return buf.getvalue()


def _cell(v: Any) -> str:
    return ("true" if v else "false") if isinstance(v, bool) else str(v)
