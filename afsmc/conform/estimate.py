"""The spec's figures estimated from the logged steps, and judged by sim-check's rules
(afsmc.sim.evidence.judge, docs/monte-carlo.md) as if the logs were a simulation:

- a **probability constant** `P` that is the whole probability of an outcome (`P:` or
  `1 - P:`) or of a probabilistic hazard (`with probability P`): its trials are the
  steps where it was drawn, its successes those that ended in its outcome, and `P` is
  consistent when it lies in their Clopper-Pearson interval (an interval probability
  `[lo, hi]` when it covers that interval). A hazard's trials are the steps of an action
  in its modes where no hazard tried before it happened (hazards are tried in
  declaration order); an outcome's trials are its action's steps where no hazard
  happened. A probability written otherwise (`(gusty ? P : 0)`, `P * Q`) is not
  estimated;
- an **interval constant** `[lo, hi]`: its samples are the durations the steps that read
  it measured, and `[lo, hi]` is consistent when it is the integer hull of their central
  95% (by default), as sim-check judges a simulated duration.

A constant no step exercises is not estimated (listed apart).
"""

from __future__ import annotations

import dataclasses
from collections import defaultdict
from typing import Any

import numpy as np

from afsmc.conform.replay import Trial
from afsmc.model import expr as E
from afsmc.model import ir
from afsmc.sim.evidence import Evidence, judge

ORIGIN = "logs"




def probability_of(e: E.Expr) -> tuple[str, bool] | None:
    """(P, True) for a probability written `P`, (P, False) for `1 - P`, else None."""
    if isinstance(e, E.ConstRef):
        return e.name, True
    if isinstance(e, E.Binary) and e.op == "-" and isinstance(e.left, E.Lit) \
            and e.left.value == 1 and isinstance(e.right, E.ConstRef):
        return e.right.name, False
    return None


def samples(model: ir.Model, trials: list[Trial]) -> dict[str, list[float]]:
    """Each estimable constant's samples: 1/0 per trial of a probability, the measured
    values of an interval constant."""
    out: dict[str, list[float]] = defaultdict(list)
    for t in trials:
        for name, d in t.durations.items():
            out[name].append(d)
        if t.outcome is None:  # the changes fit several outcomes: no evidence of which
            continue
        fired = t.outcome.split("/")[0] if isinstance(t.outcome, str) else None
        for h in model.hazards_in(model.mode(t.mode).number):
            pc = probability_of(h.prob)
            if pc is not None:
                out[pc[0]].append(float((fired == h.name) == pc[1]))
            if fired == h.name:
                break
        else:
            _action(model.action(t.action), t.outcome, out)
    return out


def _action(action: ir.Action, outcome: Any, out: dict[str, list[float]]) -> None:
    """The trial of each probability constant of the action's outcomes."""
    direct: dict[str, list[int]] = defaultdict(list)
    complement: dict[str, int] = {}
    for i, o in enumerate(action.outcomes):
        pc = probability_of(o.prob)
        if pc is None:
            continue
        if pc[1]:
            direct[pc[0]].append(i)
        else:
            complement.setdefault(pc[0], i)
    for name, indexes in direct.items():
        out[name].append(float(outcome in indexes))
    for name, i in complement.items():
        if name not in direct:
            out[name].append(float(outcome != i))


def judged(model: ir.Model, trials: list[Trial], origin: str,
           confidence: float | None = None) -> tuple[list[Evidence], list[str]]:
    """The evidence of each constant the logs exercise, in declaration order, and the
    names of those they could have estimated but do not exercise."""
    found = samples(model, trials)
    estimable = _estimable(model)
    evidence: list[Evidence] = []
    idle: list[str] = []
    for c in model.constants:
        if c.name not in estimable:
            continue
        probability = not c.is_interval
        x = found.get(c.name)
        if not x:
            idle.append(c.name)
            continue
        stand_in = dataclasses.replace(
            c, source=ir.SimSource(ORIGIN, c.source.policy if c.source else (), c.span,
                                   column=ORIGIN),
            declared_type="prob" if probability and c.declared_type == "double"
            else c.declared_type)
        e = judge(stand_in, len(x), 0, samples=np.asarray(x, dtype=np.float64),
                  confidence=confidence, kind="duration" if c.is_interval else "probability")
        evidence.append(dataclasses.replace(e, ref=origin, seed=None))
    return evidence, idle


def _estimable(model: ir.Model) -> set[str]:
    """The constants a log can estimate: interval constants, and probabilities written as
    an outcome's or a hazard's whole probability."""
    out = {c.name for c in model.interval_constants}
    for h in model.hazards:
        if (pc := probability_of(h.prob)) is not None:
            out.add(pc[0])
    for a in model.actions:
        for o in a.outcomes:
            if (pc := probability_of(o.prob)) is not None:
                out.add(pc[0])
    return out
