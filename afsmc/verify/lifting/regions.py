"""A region's verdict on afsmc's explored model (afsmc.verify.lifting), for `afsmc regions`
(afsmc.verify.reports.regions.refine_lifted).

A box inside one whose value is proven monotone in every parameter
(afsmc.verify.lifting.monotone) is decided by the exact values at its two extreme
corners: point passes, their values kept for the boxes that share a corner. Any other
box gets one slope pass: its lifted bounds decide it where they can; else, if the pass
proves the value monotone over it, it is decided by its corners as above (and so is
every box inside it, in later rounds, without another slope pass); else it is unknown.

A verdict keeps the margin against the threshold: "holds" if every value of the box
meets `value op threshold` with `margin` against it, "fails" if none meets it with the
margin the other way, else "unknown".
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence

from afsmc.verify.arrays.acyclic import F64
from afsmc.verify.lifting import monotone, order
from afsmc.verify.lifting.bounds import VALUE_BYTES
from afsmc.verify.lifting.model import Box, Lifted, Query

Signs = tuple[int, ...]


class Decider:
    """Decides boxes round after round, keeping the boxes proven monotone and the exact
    values at the corners evaluated so far. `q.end`: the side the requirement reads
    ("min" for >= and >, "max" for <= and <)."""

    def __init__(self, lifted: Lifted, q: Query, op: str, threshold: float, margin: float
                 ) -> None:
        # each layer's states that depend on the parameters first: a corner's point
        # pass computes only those (afsmc.verify.lifting.order); the caller may have
        # renumbered them already, and then keeps no second copy
        self.lifted = lifted if lifted.leading is not None else order.dependent_first(lifted)
        self.q = q
        self.base: F64 | None = None
        self.lower = op in (">=", ">")
        self.threshold, self.margin = threshold, margin
        self.proven: list[tuple[Box, Signs]] = []
        self.values: dict[tuple[float, ...], float] = {}
        self.slope_passes = 0
        self.point_passes = 0

    def summary(self) -> str:
        """The work so far, for the progress lines."""
        def count(n: int, one: str, many: str) -> str:
            return f"{n} {one if n == 1 else many}"
        return (f"{count(self.slope_passes, 'slope pass', 'slope passes')}, "
                f"{count(len(self.values), 'corner value', 'corner values')}, "
                f"{count(len(self.proven), 'box', 'boxes')} proven monotone")

    def verdict(self, worst: float, best: float | None) -> str:
        """The verdict from the value on the side the requirement reads (`worst`) and on
        the other (`best`; None: not known yet)."""
        t, m = self.threshold, self.margin
        if (worst >= t + m) if self.lower else (worst <= t - m):
            return "holds"
        if best is not None and ((best <= t - m) if self.lower else (best >= t + m)):
            return "fails"
        return "unknown"

    def decide(self, boxes: Sequence[Mapping[str, tuple[float, float]]]) -> list[str]:
        verdicts: list[str | None] = [None] * len(boxes)
        signs = [self._inside_proven(b) for b in boxes]
        for i, b in enumerate(boxes):
            if signs[i] is not None:
                continue
            s = monotone.slopes(self.lifted, self.q, b)
            self.slope_passes += 1
            worst, best = (s.low, s.high) if self.lower else (s.high, s.low)
            found, proven = self.verdict(worst, best), s.signs()
            signs[i] = proven
            if found != "unknown" or proven is None:
                verdicts[i] = found
            else:
                self.proven.append((b, proven))
        open_ = [i for i, v in enumerate(verdicts) if v is None]
        worst_end = self.q.end
        best_end = "max" if worst_end == "min" else "min"
        worst_at = self._exact([self._corner(boxes[i], signs[i], worst_end) for i in open_])
        worst_of = dict(zip(open_, worst_at, strict=True))
        rest = [i for i in open_ if self.verdict(worst_of[i], None) != "holds"]
        best_at = self._exact([self._corner(boxes[i], signs[i], best_end) for i in rest])
        best_of = dict(zip(rest, best_at, strict=True))
        for i in open_:
            verdicts[i] = self.verdict(worst_of[i], best_of.get(i))
        return [v if v is not None else "unknown" for v in verdicts]

    def _inside_proven(self, box: Box) -> Signs | None:
        for outer, signs in self.proven:
            if all(outer[n][0] <= box[n][0] and box[n][1] <= outer[n][1] for n in box):
                return signs
        return None

    def _corner(self, box: Box, signs: Signs | None, end: str) -> tuple[float, ...]:
        assert signs is not None
        at = monotone.extreme_corner(self.lifted.names, box, signs, end)
        return tuple(at[n] for n in self.lifted.names)

    def _exact(self, corners: Sequence[tuple[float, ...]]) -> list[float]:
        """The query's exact value at each corner: those not known yet by point passes."""
        new = sorted({c for c in corners if c not in self.values})
        if new:
            points = [dict(zip(self.lifted.names, c, strict=True)) for c in new]
            if self.base is None:
                self.base = monotone.base_values(self.lifted, self.q)
            found = monotone.exact_values(self.lifted, self.q, points, VALUE_BYTES, self.base)
            self.point_passes += 1
            self.values.update(zip(new, found, strict=True))
        return [self.values[c] for c in corners]
