"""Most probable paths in mission terms: each step's mode, the action (or hazard) that
fired, the variables it changed and its probability.

Storm finds the paths as state sequences of the induced DTMC
(:mod:`afsmc.verify.strategy_storm`); here each step is replayed through the lowered
model's commands (the floor/ceil variant the scheduler chose): the branches that lead
from one valuation to the next name the action or hazard, and their probabilities must
add up to Storm's, or the path is reported as not confirmed.
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any

from afsmc.lower.lowering import Command, Lowered
from afsmc.model.evaluate import Env, evaluate
from afsmc.verify.strategy_compose import (
    action_text,
    agents,
    choice_owners,
    displays,
    mode_name,
    modes_text,
)
from afsmc.verify.strategy_storm import RawPath

# A replayed step's probability may differ from Storm's by rounding only.
TOLERANCE = 1e-9


@dataclass(frozen=True)
class Step:
    mode: str  # the mode the step starts in
    action: str  # the action that fired ("(final)": a final mode's self-loop)
    probability: float
    changes: dict[str, int | bool | str]  # variable (display name, "mode") -> new value
    choice: tuple[tuple[str, str], ...] = ()  # (interval constant, "floor"|"ceil") taken
    hazard: str | None = None  # the probabilistic hazard that happened instead

    def to_json(self) -> dict[str, object]:
        out: dict[str, object] = {"mode": self.mode, "action": self.action,
                                  "probability": self.probability,
                                  "changes": dict(self.changes),
                                  "choice": {c: end for c, end in self.choice}}
        if self.hazard is not None:
            out["hazard"] = self.hazard
        return out


@dataclass(frozen=True)
class Witness:
    probability: float
    steps: tuple[Step, ...]
    start: dict[str, int | bool] = field(default_factory=dict)  # initial variable values
    end_mode: str = ""
    confirmed: bool = True  # every step replayed through the lowered model

    def to_json(self) -> dict[str, object]:
        return {"probability": self.probability, "end_mode": self.end_mode,
                "confirmed": self.confirmed, "steps": [s.to_json() for s in self.steps]}

    def trace(self, start_mode: str) -> list[dict[str, Any]]:
        """The path as `afsmc simulate --traces-out` writes a run: one entry per state
        (step number, mode, the action and hazard that led to it, every variable)."""
        mode = start_mode
        vars_: dict[str, int | bool | str] = dict(self.start)
        out: list[dict[str, Any]] = [{"step": 0, "mode": mode, "vars": dict(vars_)}]
        for i, s in enumerate(self.steps, 1):
            mode = str(s.changes.get("mode", mode))
            vars_ |= {k: v for k, v in s.changes.items() if k != "mode"}
            entry: dict[str, Any] = {"step": i, "mode": mode, "action": s.action}
            if s.hazard is not None:
                entry["hazard"] = s.hazard
            entry["vars"] = dict(vars_)
            out.append(entry)
        return out


def _env(low: Lowered, valuation: dict[str, int]) -> Env:
    model = low.model
    consts: dict[str, Any] = dict(model.const_values)
    for gen, (_, value) in low.bounds.items():
        consts[gen] = value
    box: list[Env] = []
    env = Env(vars={k: v for k, v in valuation.items() if k != "mode"},
              mode=valuation.get("mode"), consts=consts,
              formulas={f.name: f.value for f in model.formulas},
              labels={lb.name: lb.value for lb in model.labels},
              weight=lambda a: evaluate(low.weights[a], box[0]))
    box.append(env)
    return env


def _replay(low: Lowered, cmd: Command, here: dict[str, int],
            there: dict[str, int]) -> tuple[float, str | None]:
    """The probability of going from `here` to `there` by `cmd`, and the hazard of the
    branches that do (None: the action's own)."""
    env = _env(low, here)
    total, hazards = 0.0, set()
    for b in cmd.branches:
        new = dict(here)
        for var, expr in b.updates:
            v = evaluate(expr, env)
            new[var] = int(v)
        if new == there:
            total += float(evaluate(b.prob, env))
            hazards.add(b.hazard)
    named = {h for h in hazards if h is not None}
    return total, (named.pop() if len(named) == 1 and None not in hazards else None)


def describe(paths: Sequence[RawPath], variables: Sequence[str], low: Lowered) -> list[Witness]:
    """Storm's paths as mission traces, each step replayed through the lowered model."""
    model = low.model
    display = {v.name: v.display for v in model.variables} | {"mode": "mode"}
    composed = model.composition is not None
    if composed:
        display |= displays(low)
    booleans = {v.name for v in model.variables if v.type.name == "BOOL"}
    names = list(variables)
    out = []
    for p in paths:
        vals = [dict(zip(names, s, strict=True)) for s in p.states]
        steps, ok = [], True
        for i, (here, there) in enumerate(itertools.pairwise(vals)):
            cmd = low.commands[p.commands[i]] if p.commands[i] >= 0 else None
            hazard = None
            if cmd is not None:
                replayed, hazard = _replay(low, cmd, here, there)
                ok = ok and math.isclose(replayed, p.steps[i], rel_tol=TOLERANCE,
                                         abs_tol=TOLERANCE)
            else:
                ok = False
            action = "(no enabled action)" if cmd is None or cmd.kind == "deadlock" else (
                "(final)" if cmd.kind == "final" else
                action_text(low, cmd) if composed else cmd.action)
            changes: dict[str, int | bool | str] = {}
            for k in names:
                if there[k] != here[k]:
                    changes[display.get(k, k) if k != "mode" else "mode"] = _value(
                        low, k, there[k], booleans)
            owners = choice_owners(low, cmd) if composed and cmd is not None else ()
            # a synchronised action's ends by the partner that took each: "T_TAKEOFF[uav1]"
            choice = tuple((f"{c}[{owners[j]}]" if owners else c,
                            "floor" if e == "lo" else "ceil")
                           for j, (c, e) in enumerate(cmd.choice if cmd is not None else ()))
            steps.append(Step(_mode(low, here), action, p.steps[i], changes, choice, hazard))
        start: dict[str, int | bool] = {display.get(k, k): (bool(v) if k in booleans else v)
                                        for k, v in vals[0].items() if k != "mode"}
        ok = ok and math.isclose(math.prod(p.steps), p.probability, rel_tol=1e-6)
        out.append(Witness(p.probability, tuple(steps), start, _mode(low, vals[-1]), ok))
    return out


def _mode(low: Lowered, values: dict[str, int]) -> str:
    """The mode of a state: a composed mission's, each agent's ("uav1: Search, uav2:
    Home")."""
    if low.model.composition is not None:
        return modes_text(low, values)
    return low.model.mode_by_number(values["mode"]).name


def _value(low: Lowered, var: str, v: int, booleans: set[str]) -> int | bool | str:
    if var == "mode":
        return low.model.mode_by_number(v).name
    agent = next((a for a in agents(low) if a.mode_var == var), None)
    if agent is not None:
        return mode_name(agent, v)
    return bool(v) if var in booleans else v
