"""Requirements: the verdict of `P>=0.65 [ ... ]` from the values Storm gave and their error.

Storm is asked for the values (`=?`: for an MDP the min and the max over every resolution
of the interval constants); afsmc judges them. With each value known to within `error` (0
for exact values):

- `holds`: the bound that counts meets the threshold for sure, so every resolution does
  (the min for `>=`/`>`, the max for `<=`/`<`; a DTMC's one value);
- `fails`: the other bound misses it for sure, so every resolution does;
- `depends`: the bound that counts misses it and the other meets it (an MDP only): some
  resolutions meet it, others do not; `broken_by` names the bound that misses;
- `undecided`: the threshold lies within the error of a value that decides, so no verdict
  is sure. A finer `--precision` or `--exact` decides it.

The uniform resolution's value is reported, never judged: it is one resolution among many.
"""

from __future__ import annotations

import math
import operator
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from fractions import Fraction
from typing import TYPE_CHECKING, Any, Literal

from afsmc.model import ir
from afsmc.text import num

if TYPE_CHECKING:
    from afsmc.verify.results import PropertyResult

Kind = Literal["holds", "fails", "depends", "undecided"]
VERDICTS: tuple[Kind, ...] = ("holds", "fails", "depends", "undecided")

_CMP: dict[str, Callable[[Any, Any], bool]] = {
    ">=": operator.ge, ">": operator.gt, "<=": operator.le, "<": operator.lt}


@dataclass(frozen=True)
class Verdict:
    kind: Kind
    reason: str  # one sentence for people: the values against the threshold
    broken_by: str | None = None  # "min" | "max" for `depends`: the bound that misses it

    def to_json(self) -> dict[str, object]:
        return {"verdict": self.kind, "reason": self.reason, "broken_by": self.broken_by}


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
    judged as if exact; afsmc never judges so, see afsmc.verify.api)."""
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
                       + ("" if single else ": every resolution meets it"))
    if _surely_not(best, e, op, t):
        return Verdict("fails", f"{said(best_v, bname)} is not {written}"
                       + ("" if single else ": no resolution meets it"))
    if not single and _surely_not(worst, e, op, t) and _surely(best, e, op, t):
        return Verdict("depends", f"the {wname} {num(worst_v)}{pm} is not {written}, the "
                       f"{bname} {num(best_v)}{pm} is: it holds in some resolutions only",
                       broken_by=wname)
    near = worst_v if not _surely_not(worst, e, op, t) or single else best_v
    return Verdict("undecided", f"{threshold.exact} lies within the error of "
                   f"{num(near)}{pm}: ask with a finer --precision or --exact")


def judge_all(results: Sequence[PropertyResult], error: float | None) -> None:
    """Set each requirement's `verdict` and every result's `error` (the bound the values
    were computed to: 0 exact, None without a guarantee)."""
    for r in results:
        r.error = error
        t = r.threshold
        if t is None:
            continue
        if r.value is not None:
            r.verdict = judge(t, r.value, r.value, error, r.exact.get("value"),
                              r.exact.get("value"))
        elif r.min is not None and r.max is not None:
            r.verdict = judge(t, r.min, r.max, error, r.exact.get("min"), r.exact.get("max"))


def judge_over(results: Sequence[PropertyResult], bounds: Mapping[str, tuple[float, float]],
               error: float, what: str) -> None:
    """Judge the requirements again over wider bounds, a property's (lo, hi) by name, each
    within `error`: the min and max over every fixed interval probability, which contain
    the floor/ceil MDP's at the midpoint. `what` says over what, in the reason."""
    for r in results:
        if r.threshold is None or r.name not in bounds:
            continue
        lo, hi = bounds[r.name]
        v = judge(r.threshold, lo, hi, error)
        r.verdict = Verdict(v.kind, f"{v.reason} ({what})", v.broken_by)


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
    if exact:
        out["exact"] = dict(sorted(exact.items()))
    return out
