"""The bounds over the interval probabilities by afsmc's explorer and parameter lifting:
what afsmc.verify.core.uncertainty asks first, before Storm's parametric engine."""

from __future__ import annotations

from collections.abc import Sequence

from afsmc.lower.lowering import Lowered
from afsmc.model import ir
from afsmc.verify.engines.parametric import Extreme
from afsmc.verify.lifting import bounds, model
from afsmc.verify.lifting.model import Box, NotLiftable


def extremes(low: Lowered, props: Sequence[ir.Property], box: Box, precision: float
             ) -> tuple[list[Extreme], dict[str, float], list[ir.Property]]:
    """The bounds of the properties the passes answer (P [F T], R [F T]) over `box`,
    jointly with `low`'s nondeterminism (the nondet lowering at the midpoint); each one's
    gap between its outer and attained ends (at most `precision` unless the refinement
    stopped first); and the properties left to Storm's parametric engine. Raises
    NotLiftable where the explorer or the lifting does not take the mission."""
    qs, targets, rewards, left = model.queries(low, props)
    if not qs:
        raise NotLiftable("no property of the form P [F T] or R [F T]")
    lifted = model.build(low, box, targets, rewards)
    found, gaps = bounds.extremes(lifted, qs, precision)
    return found, gaps, [p for p in props if p.name in left]
