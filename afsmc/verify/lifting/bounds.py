"""A property's bounds over the interval probabilities' box by parameter lifting, refined
by splitting the box until they are within the precision (afsmc.verify.lifting).

For a minimum (a maximum is the mirror):

* **outer**: the lifted bound of a box (afsmc.verify.lifting.passes) is at most the value
  at every valuation in it. Over a partition of the box into sub-boxes, the least of
  their lifted bounds is a sound lower bound of the true minimum.
* **inner**: the value at a concrete valuation (a corner, the midpoint, the corner a
  sub-box's lifted policy picks at the initial state) is attained, so the true minimum
  is at most the least value found.
* **refinement**: while the gap between the two exceeds the precision, the sub-box of
  the least lifted bound is halved along its widest side (relative to the whole box),
  each half lifted and evaluated at its pick; a sub-box whose lifted bound is no better
  than the best attained value by more than the precision is settled. The refinement
  stops when the gap is within the precision, or after MAX_BOXES sub-boxes (then the gap
  is reported as the error).

When the outer bound equals an attained value, the bound is exact: the usual case for a
value monotone in each parameter, where every state picks the same corner. Where they are
apart by more than the precision, the value may still be monotone with states that prefer
different corners: before splitting, a slope pass (afsmc.verify.lifting.monotone) tries
to prove it monotone in every parameter over the whole box, and if it does, the bound is
the exact value at the corner its signs name.
"""

from __future__ import annotations

import dataclasses
import heapq
import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass

from afsmc.verify.engines.parametric import Extreme
from afsmc.verify.lifting import monotone
from afsmc.verify.lifting.model import Box, Lifted, Query, corners_of
from afsmc.verify.lifting.passes import attained, lifted_bounds

VALUE_BYTES = 1 << 29  # the most a region pass's values take (states x boxes)
MAX_BOXES = 1000  # sub-boxes lifted per bound before the refinement gives up on the gap


@dataclass(frozen=True)
class Bound:
    """One end of a property's bounds: `outer` sound, `attained` a value at `at`, and
    the gap between them."""

    outer: float
    attained: float
    at: dict[str, float]
    boxes: int

    @property
    def gap(self) -> float:
        return abs(self.attained - self.outer) if math.isfinite(self.outer) else 0.0


def _split(box: Box, whole: Box, mixed: Sequence[str]
           ) -> tuple[dict[str, tuple[float, float]], ...]:
    """`box` halved along its widest side relative to `whole`, among the parameters the
    lifted choices disagree on (`mixed`; all of them if none)."""
    name = max(mixed or box,
               key=lambda n: (box[n][1] - box[n][0]) / ((whole[n][1] - whole[n][0]) or 1))
    lo, hi = box[name]
    mid = (lo + hi) / 2
    return ({**box, name: (lo, mid)}, {**box, name: (mid, hi)})


def _lift(lifted: Lifted, q: Query, box: Box) -> tuple[float, dict[str, float], list[str]]:
    """The lifted bound of `box`, the corner the choices' votes pick, and the parameters
    they disagree on."""
    cs = corners_of(lifted.names, box)
    values, picks, mixed = lifted_bounds(lifted, [q], lifted.values_at(cs))
    return (float(values[0]), cs[int(picks[0])],
            [n for n, m in zip(lifted.names, mixed[:, 0], strict=True) if m])


def refine(lifted: Lifted, q: Query, precision: float, outer: tuple[float, list[str]],
           start: tuple[float, dict[str, float]]) -> Bound:
    """The bound of `q` over the whole box, refined until within `precision`. `outer`:
    the whole box's lifted bound and the parameters its choices disagree on; `start`:
    the best attained value known and where."""
    sign = 1.0 if q.end == "min" else -1.0
    whole = lifted.box
    best, at = start
    if math.isinf(outer[0]) or math.isinf(best):
        return Bound(outer[0], best, at, 1)
    if sign * best - sign * outer[0] > precision:
        exact = _monotone(lifted, q)
        if exact is not None:
            return exact
    heap = [(sign * outer[0], 0, dict(whole), outer[1])]
    settled = math.inf  # the least signed lifted bound of the sub-boxes settled
    count = 1
    while heap and sign * best - heap[0][0] > precision and count < MAX_BOXES:
        _, _, box, mixed = heapq.heappop(heap)
        for half in _split(box, whole, mixed):
            count += 1
            bound, pick, disagree = _lift(lifted, q, half)
            value = float(attained(lifted, [q], lifted.values_at([pick]))[0])
            if sign * value < sign * best:
                best, at = value, pick
            if sign * best - sign * bound > precision:
                heapq.heappush(heap, (sign * bound, count, half, disagree))
            else:
                settled = min(settled, sign * bound)
    lowest = min([settled, sign * best] + [h[0] for h in heap])
    return Bound(sign * lowest, best, at, count)


def _monotone(lifted: Lifted, q: Query) -> Bound | None:
    """`q`'s exact bound where its value is proven monotone in every parameter over the
    whole box (afsmc.verify.lifting.monotone): the value at the corner its signs name."""
    signs = monotone.slopes(lifted, q, lifted.box).signs()
    if signs is None:
        return None
    at = monotone.extreme_corner(lifted.names, lifted.box, signs, q.end)
    value = float(attained(lifted, [q], lifted.values_at([at]))[0])
    return Bound(value, value, at, 1)


def extremes(lifted: Lifted, qs: Sequence[Query], precision: float
             ) -> tuple[list[Extreme], dict[str, float]]:
    """Each property's Extreme (outer bounds, attained values and where), and its gap
    (the larger of its two ends'). First, all queries of a kind together: one
    lifted pass over the whole box (outer bounds), one at the corner each query's initial
    state picks there (attained values); then each end whose gap exceeds `precision` is
    refined alone."""
    corners = corners_of(lifted.names, lifted.box)
    ends: dict[str, dict[str, Bound]] = {}
    for kind in ("P", "R"):
        group = [q for q in qs if q.kind == kind]
        if not group:
            continue
        outer, picks, mixed = lifted_bounds(lifted, group, lifted.values_at(corners))
        at = [corners[int(i)] for i in picks]
        vals = attained(lifted, group, lifted.values_at(at))
        for j, q in enumerate(group):
            disagree = [n for n, m in zip(lifted.names, mixed[:, j], strict=True) if m]
            ends.setdefault(q.prop, {})[q.end] = refine(
                lifted, q, precision, (float(outer[j]), disagree), (float(vals[j]), at[j]))
    out, gaps = [], {}
    for q in qs:
        if q.end != "min":
            continue
        lo, hi = ends[q.prop]["min"], ends[q.prop]["max"]
        outer_lo, outer_hi = lo.outer, hi.outer
        if q.kind == "P":
            outer_lo, outer_hi = max(0.0, outer_lo), min(1.0, outer_hi)
        out.append(Extreme(q.prop, outer_lo, outer_hi, lo.attained, hi.attained, lo.at, hi.at,
                           "lifting"))
        gaps[q.prop] = max(lo.gap, hi.gap)
    return out, gaps


def decide(lifted: Lifted, q: Query, boxes: Sequence[Mapping[str, tuple[float, float]]],
           op: str, threshold: float, margin: float) -> list[str]:
    """Each region's verdict by lifted passes for all of them (or as many as VALUE_BYTES
    allows): "holds" if every valuation in the box meets `value op threshold` with the
    margin against it, "fails" if none meets it with the margin the other way, else
    "unknown". `q.end`: the side the requirement reads ("min" for >= and >, "max" for <=
    and <), computed first for every box; its mirror, the other side, only for the boxes
    the first does not show to hold."""
    if not boxes:
        return []
    lower = op in (">=", ">")
    worst = _lifted_values(lifted, q, boxes)
    holds = [(w >= threshold + margin) if lower else (w <= threshold - margin) for w in worst]
    open_ = [b for b, h in zip(boxes, holds, strict=True) if not h]
    other = dataclasses.replace(q, end="max" if q.end == "min" else "min")
    best = iter(_lifted_values(lifted, other, open_))
    out = []
    for h in holds:
        if h:
            out.append("holds")
            continue
        b = next(best)
        fails = (b <= threshold - margin) if lower else (b >= threshold + margin)
        out.append("fails" if fails else "unknown")
    return out


def _lifted_values(lifted: Lifted, q: Query, boxes: Sequence[Mapping[str, tuple[float, float]]]
                   ) -> list[float]:
    """`q`'s lifted bound over each box, by one pass for as many boxes as VALUE_BYTES
    allows (the pass keeps a value per state and box)."""
    per = max(1, VALUE_BYTES // (8 * max(lifted.states, 1)))
    out: list[float] = []
    for i in range(0, len(boxes), per):
        part = boxes[i:i + per]
        corners = [c for b in part for c in corners_of(lifted.names, b)]
        values, _, _ = lifted_bounds(lifted, [q], lifted.values_at(corners))
        out += values.reshape(len(part)).tolist()
    return out
