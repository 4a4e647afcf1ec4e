"""Intervals for expected rewards that stay valid when the runs show no variation: a rare
event that no run observed (see docs/monte-carlo.md, "Rare events").

The normal approximation needs a spread: when every finished run earned the same total c
(0 for a reward that no run collected), the sample variance is 0 and its interval collapses
to [c, c], whatever the truth. Instead, with p the probability that a run's total differs
from c, none of m runs differing bounds p by the Clopper-Pearson upper end q for 0 of m
(1 - ((1 - confidence) / 2)^(1/m)); and if a run's total lies in [L, B], the mean
c + p (E[X | X != c] - c) lies in [c - q (c - L), c + q (B - c)]. [L, B] comes from the model
by interval arithmetic over the variables' ranges: the reward per step times the step bound
for `C<=k`, the state reward for `I=k`. `F` and an unbounded `C` have no B (a run may earn
without end), so the interval is one-sided, [c - q (c - L), inf], with the reason said.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from afsmc.model import expr as E
from afsmc.model import ir
from afsmc.model.bounds import bounds
from afsmc.sim import stats

NORMAL = "normal"  # the normal approximation of the sample mean
RANGE = "range"  # no variation seen: Clopper-Pearson on a differing run, within [L, B]
ONE_SIDED = "one-sided"  # the same with no upper bound B from the model
CLOPPER_PEARSON = "clopper-pearson"  # a probability

Range = tuple[float, float]


@dataclass(frozen=True)
class StepBounds:
    """What one step may add to a run's total of a reward structure: its state reward and
    its action reward, each an interval."""

    state: Range
    action: Range


def step_bounds(model: ir.Model, generated: dict[str, tuple[str, int]]) -> list[StepBounds]:
    """Per reward structure, the interval of each step's state and action reward: the sum
    over its items of their value's bounds, with 0 (an item whose guard fails) included."""
    drawn = {c.name for c in model.prob_intervals}
    out = []
    for r in model.rewards:
        ends = {True: [0.0, 0.0], False: [0.0, 0.0]}  # action item? -> [lo, hi]
        for it in r.items:
            if any(isinstance(n, E.ConstRef) and n.name in drawn for n in E.walk(it.value)):
                lo, hi = -math.inf, math.inf  # a value drawn per run: not bounded here
            else:
                lo, hi = bounds(it.value, model, generated=generated)
            end = ends[it.action is not None]
            end[0] += min(lo, 0.0)
            end[1] += max(hi, 0.0)
        out.append(StepBounds((ends[False][0], ends[False][1]), (ends[True][0], ends[True][1])))
    return out


def run_range(path: str, bound: float, step: StepBounds | None) -> Range:
    """The interval a run's total of an R property lies in: `path` F, C or I, `bound` its
    step bound (inf if none)."""
    if step is None:
        return 0.0, 0.0  # no reward structure: every total is 0
    if path == "I":
        return step.state
    lo, hi = (step.state[i] + step.action[i] for i in (0, 1))
    if path == "C" and math.isfinite(bound):
        return _times(lo, bound), _times(hi, bound)
    # F and C without a bound: a run may take any number of steps
    return (-math.inf if lo < 0 else 0.0), (math.inf if hi > 0 else 0.0)


def _times(v: float, k: float) -> float:
    return 0.0 if v == 0 else v * k


def no_variation(c: float, m: int, span: Range, confidence: float) -> tuple[float, float, str, str]:
    """(low, high, method, reason) of the mean when all `m` finished runs earned `c`, each
    run's total lying in `span` = (L, B)."""
    q = stats.clopper_pearson(0, m, confidence)[1]
    lo_end, hi_end = span
    low = c - q * (c - lo_end) if math.isfinite(lo_end) else -math.inf
    high = c + q * (hi_end - c) if math.isfinite(hi_end) else math.inf
    said = f"every one of {m:,} runs earned {c:g}"
    if math.isfinite(hi_end):
        return low, high, RANGE, (
            f"{said}: a run that differs has probability at most {q:.3g} (Clopper-Pearson), "
            f"and a run earns between {lo_end:g} and {hi_end:g}")
    return low, high, ONE_SIDED, (
        f"{said}, and the model bounds no run's total from above (a run may earn without "
        "end): the interval is one-sided; a step-bounded property (C<=k) has a bound")
