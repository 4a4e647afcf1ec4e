"""What a mission leaves uncertain, and a property's bounds over all of it together.

A property's `min` and `max` range over everything uncertain at once (docs/verification.md,
"What a result means"):

- the interval constants (`const T = [a..b]`): floor or ceil, chosen anew at every step;
- the order in which agents move (an interleaving, or `timed ties nondet`);
- the interval probabilities (`const prob P = [lo, hi]`): one fixed value per run,
  anywhere in the box.

Storm's sparse and symbolic engines and afsmc's explorer bound the first two (an MDP's
min and max) with every interval probability at its midpoint. Where the mission has
interval probabilities, :func:`over_probabilities` asks Storm's parametric engine for the
extremes over the whole box, jointly with the scheduler's choices (afsmc.verify.engines.parametric),
and makes them the property's `min` and `max`; the midpoint's answer stays as a reference
point (`PropertyResult.reference`), never judged.
"""

from __future__ import annotations

import dataclasses
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field

from afsmc.compiler import lowered
from afsmc.diagnostics import Diagnostic, Severity, Span, codes
from afsmc.lower.lowering import Lowered
from afsmc.lower.reduce import Reductions
from afsmc.model import expr as E
from afsmc.model import ir
from afsmc.text import num
from afsmc.verify.engines import parametric
from afsmc.verify.lifting import route
from afsmc.verify.lifting.model import NotLiftable
from afsmc.verify.outcome.results import Checks, Partial, PropertyResult
from afsmc.verify.plan.precision import PARAMETER_PRECISION, PARAMETER_SOLVER_ERROR

INTERVAL_CONSTANTS = "interval constants"
AGENT_ORDER = "agent order"
INTERVAL_PROBABILITIES = "interval probabilities"


def sources(model: ir.Model) -> tuple[str, ...]:
    """What the mission's `min` and `max` range over, in the order of the docs; empty for
    a mission with nothing uncertain (a DTMC: one value per property)."""
    out = []
    if model.interval_constants:
        out.append(INTERVAL_CONSTANTS)
    comp = model.composition
    if comp is not None and comp.text in ("interleaving", "interleaving, fair",
                                          "timed, ties nondet"):
        out.append(AGENT_ORDER)
    if model.prob_intervals:
        out.append(INTERVAL_PROBABILITIES)
    return tuple(out)


@dataclass(frozen=True)
class Reference:
    """A property's values at a reference point, reported and never judged. `point`:
    "midpoint" (every interval probability at the middle of its interval); `min`/`max`
    over the other uncertainty there (an MDP), `value` (a DTMC), `uniform` (the interval
    constants' floor or ceil at random), `exact` (--exact: the values as `num/den`)."""

    point: str
    min: float | None = None
    max: float | None = None
    value: float | None = None
    uniform: float | None = None
    exact: dict[str, str] = field(default_factory=dict)

    def to_json(self) -> dict[str, object]:
        from afsmc.verify.engines.storm import finite

        out: dict[str, object] = {"point": self.point}
        for key in ("min", "max", "value", "uniform"):
            out[key] = finite(getattr(self, key))
        if self.exact:
            out["exact"] = dict(sorted(self.exact.items()))
        return out


@dataclass(frozen=True)
class ProbabilityBox:
    """The interval probabilities' box and, per property, where the extremes were found
    (Storm's parametric engine): what `afsmc verify --json` prints as
    `probability_intervals`."""

    box: dict[str, tuple[float, float]]
    extremes: tuple[parametric.Extreme, ...]
    precision: float
    seconds: float = 0.0  # the bounds' time, build and refinement
    engine: str = "Storm's parametric engine"  # what computed them

    def to_json(self) -> dict[str, object]:
        return parametric.to_json(self.box, self.extremes, self.precision)


def bound_error(precision: float | None) -> float:
    """The error of a bound over interval probabilities: the parametric engine's refinement
    precision and its solver's, plus that of the check at the midpoint when it is larger."""
    base = PARAMETER_PRECISION + PARAMETER_SOLVER_ERROR
    return base if precision is None else max(base, precision)


def over_probabilities(checks: Checks, model: ir.Model, props: Sequence[ir.Property], *,
                       via: str, reductions: Reductions | None, precision: float | None,
                       preserve: Sequence[ir.Property] = (),
                       progress: Callable[[str], None] | None = None,
                       beside: Sequence[ir.Property] = ()
                       ) -> tuple[Checks, ProbabilityBox | None, dict[str, float]]:
    """`checks` with each property's `min`/`max` its bounds over every fixed value of the
    interval probabilities (the midpoint's answer kept as its `reference`); the box, and
    each property's error (none of either for a mission without interval probabilities).
    `preserve`: the further properties the check's reductions kept exact (a sweep's other
    points), so that the model bounded is the model checked. `beside`: further queries
    bounded with them that are not the mission's (the conditioning's expected steps).

    The bounds are attained values (`Extreme.min_attained`: by afsmc's parameter lifting
    where it takes the mission, else Storm's parametric engine): the true extreme lies
    within `error` of each, beyond it (below a min, above a max)."""
    box = parametric.interval_box(model)
    if not box:
        return checks, None, {}
    t0 = time.perf_counter()
    asked = [*props, *beside]
    kept = dataclasses.replace(model, properties=tuple(asked) + tuple(preserve))
    low = lowered(kept, "nondet", reductions)
    found, gaps, engine = _bounded(low, asked, box, via, progress)
    seconds = time.perf_counter() - t0
    by_name = {e.name: e for e in found}
    error = bound_error(precision)
    errors = {r.name: max(error, gaps.get(r.name, 0.0)) for r in checks.properties
              if r.name in by_name}
    widened = [_widened(r, by_name[r.name]) if r.name in by_name else r
               for r in checks.properties]
    return (dataclasses.replace(checks, properties=widened),
            ProbabilityBox(box, tuple(found), PARAMETER_PRECISION, seconds, engine), errors)


LIFTING = "afsmc's explorer, parameter lifting"
PARAMETRIC = "Storm's parametric engine"


def _bounded(low: Lowered, props: Sequence[ir.Property], box: dict[str, tuple[float, float]],
             via: str, progress: Callable[[str], None] | None
             ) -> tuple[list[parametric.Extreme], dict[str, float], str]:
    """Each property's bounds over `box`: by parameter lifting on afsmc's explorer where it
    takes them (`_lifted`), the others by Storm's parametric engine; the lifted ones' gaps,
    and the engine in words."""
    found, gaps, engine = _lifted(low, props, box, progress)
    left = [p for p in props if p.name not in {e.name for e in found}]
    if left:
        if progress is not None:
            progress(f"bounding {len(left)} propert{'y' if len(left) == 1 else 'ies'} over "
                     + ", ".join(f"{n} in [{lo:g}, {hi:g}]" for n, (lo, hi) in box.items())
                     + " with Storm's parametric engine")
        found += parametric.extremes(low, left, via=via, precision=PARAMETER_PRECISION)
        engine = PARAMETRIC if not gaps else f"{LIFTING} and {PARAMETRIC}"
    return found, gaps, engine


def _lifted(low: Lowered, props: Sequence[ir.Property], box: dict[str, tuple[float, float]],
            progress: Callable[[str], None] | None
            ) -> tuple[list[parametric.Extreme], dict[str, float], str]:
    """The bounds afsmc's explorer and parameter lifting give (afsmc.verify.lifting), each
    one's gap; none where it does not take the mission (Storm's parametric engine then
    bounds every property)."""
    if progress is not None:
        progress(f"bounding {len(props)} propert{'y' if len(props) == 1 else 'ies'} over "
                 + ", ".join(f"{n} in [{lo:g}, {hi:g}]" for n, (lo, hi) in box.items())
                 + " by parameter lifting on afsmc's explorer")
    try:
        found, gaps, _ = route.extremes(low, props, box, PARAMETER_PRECISION)
    except NotLiftable as why:
        if progress is not None:
            progress(f"parameter lifting does not take it ({why}): Storm's parametric "
                     "engine bounds it")
        return [], {}, PARAMETRIC
    return found, gaps, LIFTING


def reach_bounds(model: ir.Model, targets: Sequence[tuple[str, E.Expr]], *,
                 via: str = "prism") -> tuple[dict[str, tuple[float, float]], str]:
    """The min and max probability of ever reaching each target (name, state predicate)
    over everything uncertain, interval probabilities included (the diagram's --reach on
    a mission with interval probabilities): the same bounds as `verify -f 'P=? [ F ... ]'`
    gives, by the same engines (parameter lifting on afsmc's explorer where it takes the
    mission, else Storm's parametric engine), and which in words."""
    span = Span.at_offset(model.source, 0, 0)
    props = [ir.Property(name, "P", "", ir.Path("F", target), None, span)
             for name, target in targets]
    kept = dataclasses.replace(model, properties=tuple(props))
    found, _, engine = _bounded(lowered(kept, "nondet"), props, parametric.interval_box(model),
                                via, None)
    return {e.name: (e.min_attained, e.max_attained) for e in found}, engine


def _midpoint(r: PropertyResult) -> Reference:
    """`r`'s answer, made with the interval probabilities at their midpoint, as a reference."""
    return Reference("midpoint", r.min, r.max, r.value, r.uniform, dict(r.exact))


def _widened(r: PropertyResult, e: parametric.Extreme) -> PropertyResult:
    """`r` with its midpoint answer as its reference and the bounds of `e` as its min and
    max."""
    return dataclasses.replace(
        r, reference=_midpoint(r),
        min=e.min_attained, max=e.max_attained, value=None, uniform=None, exact={},
        attained_at={"min": dict(e.min_at), "max": dict(e.max_at)})


def kept_at_midpoint(checks: Checks) -> tuple[list[Diagnostic], Partial]:
    """What a failure of the bounds over the interval probabilities keeps of the check
    already made at their midpoint: each answer as its reference (never as the bounds,
    which are what failed), and a note that says them."""
    props = [dataclasses.replace(
        r, reference=_midpoint(r),
        min=None, max=None, value=None, uniform=None, exact={}) for r in checks.properties]
    said = "; ".join(
        f"{r.name} " + ", ".join(f"{k} {num(v)}" for k in ("min", "max", "value", "uniform")
                                  if (v := getattr(r, k)) is not None)
        for r in checks.properties)
    note = Diagnostic(codes.N412, Severity.NOTE, "answered at the interval probabilities' "
                      f"midpoint before the failure (a reference point, not the bounds over "
                      f"their box): {said}", None)
    return [note], Partial(checks.model, checks.uniform_model, props)


def described(over: Sequence[str], box: ProbabilityBox | None,
              composition: str | None = None) -> str:
    """What min and max range over, in words for the front-ends' headers (empty: nothing,
    a DTMC's one value). `composition` (VerifyResult.composition): a fair interleaving
    says that only fair schedulers count."""
    order = "the order in which the agents move"
    if composition == "interleaving, fair":
        order += (" (fair schedulers only: every agent that stays able to move eventually "
                  "moves)")
    words = {INTERVAL_CONSTANTS: "the interval constants' floor/ceil choices",
             AGENT_ORDER: order}
    parts = [words[s] for s in over if s in words]
    if INTERVAL_PROBABILITIES in over and box is not None:
        parts.append("every fixed " + ", ".join(f"{n} in [{lo:g}, {hi:g}]"
                                                 for n, (lo, hi) in box.box.items()))
    if len(parts) > 1:
        return ", ".join(parts[:-1]) + " and " + parts[-1]
    return parts[0] if parts else ""
