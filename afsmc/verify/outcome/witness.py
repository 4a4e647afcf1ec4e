"""Most probable paths in mission terms: each step's mode, the action (or hazard) that
fired, the variables it changed and its probability.

Storm finds the paths as state sequences of the induced DTMC
(:mod:`afsmc.verify.engines.strategy_storm`); here each step is replayed through the lowered
model's commands (the floor/ceil variant the scheduler chose): the branches that lead
from one valuation to the next name the action or hazard, and their probabilities must
add up to Storm's, or the path is reported as not confirmed.

A step shows what the mission did: the variables its action or hazard wrote. The exact
reductions (afsmc.lower.reduce) reset a variable that is dead in the mode entered to its
initial value, so that states differing only in it merge; those resets are the
reductions', not the mission's, and the step leaves them out: each step's values are the
mission's, its branch's updates evaluated on the mission's values before it, in the model
lowered again without the reductions (whose commands and branches are those of the
reduced one, one for one). A dead variable is never read before it is written, so the
updates read the same values in both.
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any

from afsmc.lower.lowering import Command, Lowered, lower
from afsmc.model.evaluate import Env, EvalError, evaluate
from afsmc.verify.engines.strategy_storm import RawPath
from afsmc.verify.outcome.strategy_compose import (
    action_text,
    agents,
    choice_owners,
    displays,
    mode_name,
    modes_text,
    mover,
)

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
    # a composed mission: each agent the step moved, with its own action or hazard
    # ("uav1", "Look"), for the diagram's path (not in the JSON: `action` names them)
    moved: tuple[tuple[str, str], ...] = ()

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
            there: dict[str, int]) -> tuple[float, str | None, int | None]:
    """The probability of going from `here` to `there` by `cmd`, the hazard of the
    branches that do (None: the action's own), and the most probable of those branches
    (None: none does)."""
    env = _env(low, here)
    total, hazards = 0.0, set()
    best: tuple[float, int] | None = None
    for i, b in enumerate(cmd.branches):
        new = dict(here)
        for var, expr in b.updates:
            v = evaluate(expr, env)
            new[var] = int(v)
        if new == there:
            p = float(evaluate(b.prob, env))
            total += p
            hazards.add(b.hazard)
            if best is None or p > best[0]:
                best = (p, i)
    named = {h for h in hazards if h is not None}
    return (total, (named.pop() if len(named) == 1 and None not in hazards else None),
            None if best is None else best[1])


def _unreduced(low: Lowered) -> Lowered | None:
    """The model lowered again without the reductions, if they reset dead variables and
    its commands and branches are the reduced model's one for one (else None: every
    change shows, as the states have it)."""
    if not any("dead-variable reset" in r for r in low.reductions):
        return None
    plain = lower(low.model, low.resolution)
    if len(plain.commands) != len(low.commands) or any(
            a.action != b.action or len(a.branches) != len(b.branches)
            for a, b in zip(plain.commands, low.commands, strict=True)):
        return None
    return plain


def _mission(plain: Lowered | None, command: int, branch: int | None,
             real: dict[str, int], there: dict[str, int]) -> dict[str, int]:
    """The mission's values after a step from `real` (its values before): the unreduced
    branch's updates evaluated there, every other variable as it was. Where it is not
    known (no reductions, a step not replayed): the state's values, `there`."""
    if plain is None or branch is None or command < 0:
        return dict(there)
    env = _env(plain, real)
    b = plain.commands[command].branches[branch]
    try:
        return real | {var: int(evaluate(expr, env)) for var, expr in b.updates}
    except EvalError:  # not expected (the updates read live values only): as the state has it
        return dict(there)


def _moved(low: Lowered, cmd: Command | None, hazard: str | None) -> tuple[tuple[str, str], ...]:
    """A composed mission's step: each agent it moved, by its own action or hazard."""
    if cmd is None or cmd.silent or low.model.composition is None:
        return ()
    who, action = mover(low, cmd)
    return tuple((a.name, hazard if hazard is not None and any(
        h.name == hazard for h in a.model.hazards) else action) for a in who)


def describe(paths: Sequence[RawPath], variables: Sequence[str], low: Lowered) -> list[Witness]:
    """Storm's paths as mission traces, each step replayed through the lowered model."""
    model = low.model
    display = {v.name: v.display for v in model.variables} | {"mode": "mode"}
    composed = model.composition is not None
    if composed:
        display |= displays(low)
    booleans = {v.name for v in model.variables if v.type.name == "BOOL"}
    names = list(variables)
    plain = _unreduced(low) if paths else None
    out = []
    for p in paths:
        vals = [dict(zip(names, s, strict=True)) for s in p.states]
        steps, ok = [], True
        real = dict(vals[0])  # the mission's values: without the reductions' resets
        for i, (here, there) in enumerate(itertools.pairwise(vals)):
            cmd = low.commands[p.commands[i]] if p.commands[i] >= 0 else None
            hazard, branch = None, None
            if cmd is not None:
                replayed, hazard, branch = _replay(low, cmd, here, there)
                ok = ok and math.isclose(replayed, p.steps[i], rel_tol=TOLERANCE,
                                         abs_tol=TOLERANCE)
            else:
                ok = False
            action = "(no enabled action)" if cmd is None or cmd.kind == "deadlock" else (
                "(final)" if cmd.kind == "final" else
                action_text(low, cmd) if composed else cmd.action)
            before, real = real, _mission(plain, p.commands[i], branch, real, there)
            changes: dict[str, int | bool | str] = {
                display.get(k, k) if k != "mode" else "mode": _value(low, k, real[k], booleans)
                for k in names if real[k] != before[k]}
            owners = choice_owners(low, cmd) if composed and cmd is not None else ()
            # a synchronised action's ends by the partner that took each: "T_TAKEOFF[uav1]"
            choice = tuple((f"{c}[{owners[j]}]" if owners else c,
                            "floor" if e == "lo" else "ceil")
                           for j, (c, e) in enumerate(cmd.choice if cmd is not None else ()))
            steps.append(Step(_mode(low, here), action, p.steps[i], changes, choice, hazard,
                              _moved(low, cmd, hazard)))
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
