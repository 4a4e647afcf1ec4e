"""How far the model Storm solves can be from the model as written, and what a verdict
does about it (docs/verification.md, "When floating point can mislead").

Storm builds the model in double precision: each transition probability is the written
expression evaluated in doubles, so each row of the built matrix differs from the
written one by at most `DELTA` in the sum of its absolute differences, and each reward by
a relative rounding. Storm's sound methods are sound for the built matrix. For the
runs' transient part Q, the values of the written and the built model differ by
v' - v = (I - Q')^-1 (dQ v + dr), so by at most

    kappa * DELTA * max(1, |v|)

where kappa = |(I - Q')^-1 1| is the expected number of steps until the run ends in the
built model (for an MDP the largest over the schedulers: the optimum of each model is
attained by some scheduler, and the difference under any one scheduler is bounded so).
A mission of a million expected steps multiplies the rounding of its probabilities by a
million: that, not the solver, is what made `R{"steps"}<=1000000` fail on a model whose
value is exactly 1,000,000.

So with requirements, afsmc asks Storm one more query of the same model, kappa itself
(`R{"steps"}=? [ F <a final mode> ]`, min and max for an MDP), widens each requirement's
error by the bound above, and judges with the widened error. A verdict that the widened
error turns `undecided` is decided again exactly, by Storm's exact engine on the model as
written (rational arithmetic), where the model has at most `EXACT_STATES` states and no
interval probabilities; otherwise it stays `undecided`, with the widened bound.

Where kappa is unknown (a machine without final modes, a scheduler that can run forever)
the same is done for margins thinner than `THIN` relative to the
value: they are decided exactly or left `undecided`.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass

from afsmc.diagnostics import Span
from afsmc.model import expr as E
from afsmc.model import ir
from afsmc.verify.core.uncertainty import ProbabilityBox
from afsmc.verify.outcome.results import Checks, PropertyResult
from afsmc.verify.outcome.verdicts import Verdict, judge

# A row's rounding: each probability of a row is its written expression evaluated in
# doubles, each operation within a relative 2^-53; 2^-46 (128 roundings of a value at most
# 1) covers rows whose probabilities take up to about a hundred operations together.
DELTA = 2.0 ** -46
# Decided again by Storm's exact engine up to this many states (its rational arithmetic
# takes seconds there, and grows faster than the states).
EXACT_STATES = 20_000
# Without kappa: a margin below this, relative to max(1, |bound|), is not trusted.
THIN = 1e-6
STEPS = "afsmc_steps"  # the reward structure and the query of kappa


@dataclass(frozen=True)
class Asked:
    """The model with kappa's reward structure, and the query (None: kappa cannot be
    asked of this mission)."""

    model: ir.Model
    query: ir.Property | None

    def properties(self, props: Sequence[ir.Property]) -> list[ir.Property]:
        """`props` and kappa's query, if asked."""
        return [*props, *([self.query] if self.query is not None else [])]


def ask(model: ir.Model, props: Sequence[ir.Property]) -> Asked:
    """kappa's query beside `props` (asked in sound mode: requirements or --precision): a
    state reward of 1 and its expected total until the run ends (`_end`). A mission with a
    machine without a final mode has none."""
    # its query's names (afsmc_steps, and _min, _max for an MDP) must be no one else's
    taken = {p.name for p in props} | {r.name for r in model.rewards}
    end = _end(model)
    if end is None or any(n.startswith(STEPS) for n in taken):
        return Asked(model, None)
    span = Span.at_offset(model.source, 0, 0)
    reward = ir.RewardStruct(STEPS, (ir.RewardItem(None, E.TRUE, E.lit(1), span),), span)
    query = ir.Property(STEPS, "R", "", ir.RewardPath("F", end), STEPS, span)
    return Asked(dataclasses.replace(model, rewards=(*model.rewards, reward)), query)


def _end(model: ir.Model) -> E.Expr | None:
    """Where a run ends: in a final mode; in a composed mission, every agent in one of its
    final modes. None if some machine has no final mode."""
    machines = [("mode", model)] if model.composition is None else [
        (a.mode_var, a.model) for a in model.composition.agents]
    end: E.Expr = E.TRUE
    for var, m in machines:
        finals = [mode.number for mode in m.modes if mode.final]
        if not finals:
            return None
        here: E.Expr = E.FALSE
        for n in finals:
            here = E.Binary("||", here, E.Binary("==", E.VarRef(var, E.Type.INT), E.lit(n),
                                                 E.Type.BOOL), E.Type.BOOL)
        end = E.Binary("&&", end, here, E.Type.BOOL)
    return end


def steps(checks: Checks, asked: Asked) -> tuple[Checks, float | None]:
    """`checks` without kappa's result, and kappa: the largest expected number of steps
    (over the interval probabilities' box too, when the mission has some: their bound;
    None: not asked or not answered; inf: some run may never end)."""
    if asked.query is None:
        return checks, None
    mine = [r for r in checks.properties if r.name == STEPS]
    rest = [r for r in checks.properties if r.name != STEPS]
    found = [v for r in mine for v in (r.value, r.min, r.max) if v is not None]
    kappa = max(found) if found else None
    return dataclasses.replace(checks, properties=rest), kappa


def without_steps(box: ProbabilityBox | None) -> ProbabilityBox | None:
    """The interval probabilities' box without kappa's bounds (not a property of the
    mission's)."""
    if box is None:
        return None
    return dataclasses.replace(box, extremes=tuple(e for e in box.extremes if e.name != STEPS))


def widening(kappa: float | None, r: PropertyResult) -> float | None:
    """The bound on how far `r`'s values can be from the written model's because of the
    built model's rounding (None: unknown)."""
    if kappa is None or not math.isfinite(kappa):
        return None
    values = [abs(v) for v in (r.value, r.min, r.max) if v is not None and math.isfinite(v)]
    # kappa itself was computed to within Storm's relative precision: a factor 2 over it
    return 2 * kappa * DELTA * max(1.0, *values)


@dataclass(frozen=True)
class Accounted:
    """The results with the rounding accounted for: each requirement's error widened and
    its verdict judged with it; `redecide`, the requirements whose verdict the rounding
    could change (to be decided exactly where the model allows)."""

    results: list[PropertyResult]
    redecide: list[str]


def account(results: Sequence[PropertyResult], kappa: float | None) -> Accounted:
    """Each result's error widened by the rounding's bound, and each requirement judged
    with it; a verdict that this changes is to be decided again. With kappa unknown, the
    same for a margin thinner than THIN (the error is not widened: there is no bound to
    widen it by). Exact results, and those without a guaranteed error, are as they were."""
    out, again = [], []
    for r in results:
        if r.error is None or r.error == 0:
            out.append(r)
            continue
        if r.threshold is None or r.verdict is None or r.verdict.kind == "undecided":
            extra = widening(kappa, r)
            out.append(r if extra is None else dataclasses.replace(r, error=r.error + extra))
            continue
        lo, hi = (r.value, r.value) if r.value is not None else (r.min, r.max)
        assert lo is not None and hi is not None
        extra = widening(kappa, r)
        if extra is None:
            thin = THIN * max(1.0, abs(lo), abs(hi))
            if judge(r.threshold, lo, hi, r.error + thin).kind != r.verdict.kind:
                again.append(r.name)
            out.append(r)
            continue
        v = judge(r.threshold, lo, hi, r.error + extra)
        if v.kind != r.verdict.kind:
            again.append(r.name)
        out.append(dataclasses.replace(r, error=r.error + extra, verdict=v))
    return Accounted(out, again)


def ordered(results: Sequence[PropertyResult]) -> list[PropertyResult]:
    """Never a min above the max: where rounding put them so, both become their middle,
    with the error widened by half their gap and the verdict judged again (each true extreme lies within `error` of its
    value, and the true min is at most the true max, so both lie within the new error of
    the middle)."""
    out = []
    for r in results:
        lo, hi = r.min, r.max
        if lo is not None and hi is not None and math.isfinite(lo) and math.isfinite(hi) \
                and lo > hi and r.error is not None:
            mid, gap = (lo + hi) / 2, (lo - hi) / 2
            e = r.error + gap
            verdict = None if r.threshold is None else judge(r.threshold, mid, mid, e)
            r = dataclasses.replace(r, min=mid, max=mid, error=e, verdict=verdict)
        out.append(r)
    return out


def redecided(results: Sequence[PropertyResult], names: Sequence[str],
              exact: Callable[[list[str]], list[PropertyResult]] | None) -> list[PropertyResult]:
    """The results with `names` decided again: by `exact` (the exact engine's results of
    those properties), or, without it, `undecided` with their widened error."""
    if not names:
        return list(results)
    got = {r.name: r for r in exact(list(names))} if exact is not None else {}
    out = []
    for r in results:
        if r.name not in names:
            out.append(r)
        elif r.name in got:
            e = got[r.name]
            assert e.verdict is not None
            reason = (e.verdict.reason + "; decided exactly: the rounding of the model "
                      "Storm built could have changed the floating-point verdict")
            out.append(dataclasses.replace(
                r, min=e.min, max=e.max, value=e.value, exact=e.exact, error=0.0,
                verdict=dataclasses.replace(e.verdict, reason=reason)))
        else:
            out.append(dataclasses.replace(r, verdict=_undecided(r)))
    return out


def _undecided(r: PropertyResult) -> Verdict:
    assert r.verdict is not None and r.threshold is not None
    return Verdict("undecided", f"{r.threshold.exact} lies within the error of the model "
                   "as written: the rounding of the model Storm built, over its expected "
                   "number of steps, could change the verdict; ask with --exact",
                   decided_by=r.verdict.decided_by)
