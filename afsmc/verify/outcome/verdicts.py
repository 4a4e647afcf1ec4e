"""Requirements: the verdict of `P>=0.65 [ ... ]` from the bounds and their error.

The engines are asked for the values (`=?`); afsmc judges them here, once, and every
front-end renders the verdict it gets. The bounds judged are a property's `min` and `max`
over everything the mission leaves uncertain (docs/verification.md, "What a result
means"): the interval constants' floor/ceil choices, the order in which agents move, and
every fixed value of the interval probabilities. With each bound known to within `error`
(0 for exact values):

- `holds`: the bound that counts meets the threshold for sure, so every resolution does
  (the min for `>=`/`>`, the max for `<=`/`<`; a DTMC's one value);
- `fails`: the other bound misses it for sure, so every resolution does;
- `depends`: the bound that counts misses it and the other meets it (an MDP only): some
  resolutions meet it, others do not; `broken_by` names the bound that misses;
- `undecided`: the threshold lies within the error of a value that decides, so no verdict
  is sure. A finer `--precision` or `--exact` decides it.

Reference points (the uniform resolution, the interval probabilities' midpoint) are
reported, never judged: each is one resolution among many.
"""

from __future__ import annotations

import dataclasses
import math
import operator
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from fractions import Fraction
from typing import TYPE_CHECKING, Any, Literal

from afsmc.model import ir
from afsmc.text import num

if TYPE_CHECKING:
    from afsmc.verify.outcome.results import PropertyResult

Kind = Literal["holds", "fails", "depends", "undecided"]
VERDICTS: tuple[Kind, ...] = ("holds", "fails", "depends", "undecided")

_CMP: dict[str, Callable[[Any, Any], bool]] = {
    ">=": operator.ge, ">": operator.gt, "<=": operator.le, "<": operator.lt}


@dataclass(frozen=True)
class Verdict:
    kind: Kind
    reason: str  # one sentence for people: the values against the threshold
    broken_by: str | None = None  # "min" | "max" for `depends`: the bound that misses it
    # the bound the verdict rests on: "min" | "max", or "value" (a single value: a DTMC
    # with nothing uncertain). `holds`: the worst bound; `fails`: the best one;
    # `depends`: the one that misses (as broken_by); `undecided`: the one too near.
    decided_by: str | None = None


Number = Fraction | float


def _number(value: float, exact: str | None) -> Number:
    """The value as an exact fraction where it is one (exact mode, or any finite double)."""
    if exact is not None:
        return Fraction(exact)
    return Fraction(value) if math.isfinite(value) else value


def _surely(v: Number, e: Number, op: str, t: Fraction) -> bool:
    """Every value within `e` of `v` meets `op t`."""
    worst = v - e if op in (">=", ">") else v + e
    return _CMP[op](worst, t)


def _surely_not(v: Number, e: Number, op: str, t: Fraction) -> bool:
    """No value within `e` of `v` meets `op t`."""
    best = v + e if op in (">=", ">") else v - e
    return not _CMP[op](best, t)


def judge(threshold: ir.Threshold, lo: float, hi: float, error: float | None,
          exact_lo: str | None = None, exact_hi: str | None = None) -> Verdict:
    """The verdict of `threshold` given the min `lo` and the max `hi` over the resolutions
    (a DTMC: its value twice), each within `error` of the true one (None: no guarantee,
    judged as if exact; afsmc never judges so, see afsmc.verify.core.api)."""
    op, t = threshold.op, Fraction(threshold.exact)
    e: Number = Fraction(0) if error is None else Fraction(repr(error))
    a, b = _number(lo, exact_lo), _number(hi, exact_hi)
    upward = op in (">=", ">")
    worst, best = (a, b) if upward else (b, a)
    wname, bname = ("min", "max") if upward else ("max", "min")
    single = lo == hi and exact_lo == exact_hi
    written = f"{op} {threshold.exact}"
    pm = f" ± {num(error)}" if error else ""

    def said(v: float, name: str) -> str:
        return f"{num(v)}{pm}" if single else f"the {name} {num(v)}{pm}"

    worst_v, best_v = (lo, hi) if upward else (hi, lo)
    if _surely(worst, e, op, t):
        return Verdict("holds", f"{said(worst_v, wname)} is {written}"
                       + ("" if single else ": every resolution meets it"),
                       decided_by="value" if single else wname)
    if _surely_not(best, e, op, t):
        return Verdict("fails", f"{said(best_v, bname)} is not {written}"
                       + ("" if single else ": no resolution meets it"),
                       decided_by="value" if single else bname)
    if not single and _surely_not(worst, e, op, t) and _surely(best, e, op, t):
        return Verdict("depends", f"the {wname} {num(worst_v)}{pm} is not {written}, the "
                       f"{bname} {num(best_v)}{pm} is: it holds in some resolutions only",
                       broken_by=wname, decided_by=wname)
    near_worst = not _surely_not(worst, e, op, t) or single
    near = worst_v if near_worst else best_v
    return Verdict("undecided", f"{threshold.exact} lies within the error of "
                   f"{num(near)}{pm}: ask with a finer --precision or --exact",
                   decided_by="value" if single else wname if near_worst else bname)


def judge_all(results: Sequence[PropertyResult], error: float | None,
              errors: Mapping[str, float] | None = None) -> list[PropertyResult]:
    """The results with their `error` (the bound the values were computed to: 0 exact,
    None without a guarantee; `errors`: a property's own, by name, where its bounds came
    from another engine, as over interval probabilities) and each requirement's
    `verdict`."""
    out = []
    for r in results:
        e = (errors or {}).get(r.name, error)
        t = r.threshold
        verdict = None
        if t is not None and r.value is not None:
            verdict = judge(t, r.value, r.value, e, r.exact.get("value"), r.exact.get("value"))
        elif t is not None and r.min is not None and r.max is not None:
            verdict = judge(t, r.min, r.max, e, r.exact.get("min"), r.exact.get("max"))
        out.append(dataclasses.replace(r, error=e, verdict=verdict))
    return out


def failing(results: Sequence[PropertyResult]) -> list[PropertyResult]:
    """The requirements that do not hold (their verdict is not `holds`, or missing)."""
    return [r for r in results if r.threshold is not None
            and (r.verdict is None or r.verdict.kind != "holds")]


def requirement_json(threshold: ir.Threshold | None, verdict: Verdict | None,
                     error: float | None, exact: dict[str, str]) -> dict[str, object]:
    """A property's JSON keys for requirements: `threshold` and `verdict` (null for `=?`),
    `error` (the bound on every value's error; null: none guaranteed), `exact` (--exact)."""
    out: dict[str, object] = {
        "threshold": None if threshold is None else {"op": threshold.op,
                                                     "bound": threshold.bound},
        "verdict": None if verdict is None else verdict.kind,
        "error": error}
    if verdict is not None:
        out["reason"] = verdict.reason
        if verdict.broken_by is not None:
            out["broken_by"] = verdict.broken_by
        out["decided_by"] = verdict.decided_by
    if exact:
        out["exact"] = dict(sorted(exact.items()))
    return out
