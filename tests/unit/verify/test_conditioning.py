"""Sound for the model as written: the rounding of the model Storm builds in doubles,
multiplied by a mission's expected number of steps, never turns a verdict wrong
(afsmc.verify.core.conditioning). The oracles are closed forms: a run of a million
expected steps, a probability of exactly 2/3 reached slowly, and the same million over an
interval probability."""

from __future__ import annotations

from fractions import Fraction
from pathlib import Path

import pytest

from afsmc import verify
from afsmc.verify.core import conditioning
from afsmc.verify.outcome.results import PropertyResult

pytestmark = pytest.mark.storm

# Each step halts with probability 1e-6: the expected number of steps is exactly 10^6.
LONG = """machine longrun;
const prob P_FAULT = {fault};
mode Run = 0 initial;
mode Halted = 1 final;
action Step in Run {{
    1 - P_FAULT: skip;
    P_FAULT: goto Halted;
}}
label halted = mode == Halted;
rewards steps {{
    true : 1;
}}
"""

# Done with 2e-6, failed with 1e-6 per step: Done is reached with probability exactly 2/3,
# after 333,333 steps on average; the interval constant makes it an MDP.
SLOW = """machine slow;
const prob P_DONE = 0.000002;
const prob P_FAIL = 0.000001;
const int D = [1, 2];
var t : [0..2] init 0;
mode Run = 0 initial;
mode Done = 1 final;
mode Fail = 2 final;
action Step in Run {
    P_DONE: goto Done;
    P_FAIL: goto Fail;
    1 - P_DONE - P_FAIL: t := min(2, D);
}
"""

OFFSETS = ("0", "1e-6", "-1e-6", "1e-9", "-1e-9", "1e-12", "-1e-12")


def _right_or_undecided(r: PropertyResult, truth: Fraction, op: str, t: str) -> None:
    holds = truth <= Fraction(t) if op == "<=" else truth >= Fraction(t)
    assert r.verdict is not None
    assert r.verdict.kind in (("holds" if holds else "fails"), "undecided"), \
        (r.formula, r.verdict, r.min, r.max, r.value, r.error)
    if r.min is not None and r.max is not None:
        assert r.min <= r.max


def _meets(v: Fraction, op: str, t: Fraction) -> bool:
    return v <= t if op == "<=" else v >= t


def _thresholds(value: Fraction) -> list[str]:
    return [repr(float(value + Fraction(d))) for d in OFFSETS]


@pytest.mark.parametrize("precision", [None, 1e-12])
def test_a_million_expected_steps_never_gets_a_wrong_verdict(tmp_path: Path,
                                                             precision: float | None) -> None:
    path = tmp_path / "long.afsm"
    path.write_text(LONG.format(fault="0.000001"))
    truth = Fraction(10**6)
    formulas = [f'R{{"steps"}}{op}{t} [ F "halted" ]'
                for t in _thresholds(truth) for op in ("<=", ">=")]
    res = verify.run(str(path), formulas=formulas, precision=precision)
    for r in res.properties:
        op, t = r.formula[10:12], r.formula[12:].split(" ")[0]
        _right_or_undecided(r, truth, op, t)
    # the value at the threshold itself is decided, exactly
    at = res.properties[0]
    assert at.verdict is not None and at.verdict.kind == "holds" and at.error == 0
    assert at.exact["value"] == "1000000" and "decided exactly" in at.verdict.reason


@pytest.mark.parametrize("precision", [None, 1e-12])
def test_two_thirds_reached_slowly_never_gets_a_wrong_verdict(tmp_path: Path,
                                                              precision: float | None) -> None:
    path = tmp_path / "slow.afsm"
    path.write_text(SLOW)
    truth = Fraction(2, 3)
    formulas = [f"P{op}{t} [ F mode == Done ]" for t in _thresholds(truth) for op in ("<=", ">=")]
    res = verify.run(str(path), formulas=formulas, precision=precision, uniform=False)
    for r in res.properties:
        op, t = r.formula[1:3], r.formula[3:].split(" ")[0]
        _right_or_undecided(r, truth, op, t)


@pytest.mark.parametrize("precision", [None, 1e-9])
def test_a_million_steps_over_an_interval_probability_never_gets_a_wrong_verdict(
        tmp_path: Path, precision: float | None) -> None:
    # the expected steps 1/P_FAULT over P_FAULT in [1e-6, 2e-6]: min 500,000, max 1,000,000
    path = tmp_path / "longiv.afsm"
    path.write_text(LONG.format(fault="[0.000001, 0.000002]"))
    lo, hi = Fraction(500_000), Fraction(10**6)
    formulas = [f'R{{"steps"}}{op}{t} [ F "halted" ]'
                for t in _thresholds(hi) for op in ("<=", ">=")]
    res = verify.run(str(path), formulas=formulas, precision=precision)
    for r in res.properties:
        op, t = r.formula[10:12], Fraction(r.formula[12:].split(" ")[0])
        worst, best = (hi, lo) if op == "<=" else (lo, hi)
        truth = "holds" if _meets(worst, op, t) else "fails" if not _meets(best, op, t) \
            else "depends"
        assert r.verdict is not None and r.verdict.kind in (truth, "undecided"), \
            (r.formula, r.verdict, r.min, r.max, r.error)
        assert r.min is not None and r.max is not None and r.min <= r.max


def test_the_bound_of_a_query_says_how_far_the_rounding_can_take_it(tmp_path: Path) -> None:
    path = tmp_path / "long.afsm"
    path.write_text(LONG.format(fault="0.000001"))
    (r,) = verify.run(str(path), formulas=['R{"steps"}=? [ F "halted" ]'],
                      precision=1e-9).properties
    assert r.value is not None and r.error is not None
    # the double-precision model is about 8e-5 off; the stated error covers it
    assert abs(Fraction(r.value) - 10**6) <= Fraction(r.error) and r.error > 1e-5


def test_over_interval_probabilities_the_steps_are_bounded_over_the_box(tmp_path: Path) -> None:
    path = tmp_path / "longiv.afsm"
    path.write_text(LONG.format(fault="[0.000001, 0.000002]"))
    # the max over the box is 10^6 (at P_FAULT = 1e-6): the requirement cannot hold there
    (r,) = verify.run(str(path), formulas=['R{"steps"}<=999999.9 [ F "halted" ]']).properties
    assert r.verdict is not None and r.verdict.kind in ("depends", "undecided")
    assert r.max is not None and r.error is not None
    assert abs(Fraction(r.max) - 10**6) <= Fraction(r.error)
    res = verify.run(str(path), formulas=['R{"steps"}=? [ F "halted" ]'], precision=1e-6)
    assert res.probability is not None
    assert [e.name for e in res.probability.extremes] == ["adhoc"]  # not kappa's


def test_a_well_conditioned_mission_keeps_its_verdicts_and_nearly_its_error() -> None:
    root = Path(__file__).resolve().parents[3]
    res = verify.run(str(root / "examples" / "patrol.afsm"),
                     formulas=['P>=0.8 [ F "done" ]', 'P>=0.82 [ F "done" ]'], uniform=False)
    kinds = [r.verdict.kind for r in res.properties if r.verdict is not None]
    assert kinds == ["holds", "depends"]
    assert all(r.error is not None and 1e-6 <= r.error < 1.000001e-6 for r in res.properties)


def test_the_widening_scales_with_the_expected_steps_and_the_value() -> None:
    r = PropertyResult("p", "", "R", value=1e6, error=1e-6)
    assert conditioning.widening(None, r) is None
    assert conditioning.widening(float("inf"), r) is None
    small = conditioning.widening(10.0, PropertyResult("q", "", "P", value=0.5))
    big = conditioning.widening(1e6, r)
    assert small is not None and big is not None
    assert small == 2 * 10 * conditioning.DELTA
    assert big == 2 * 1e6 * conditioning.DELTA * 1e6


def test_a_min_above_the_max_becomes_their_middle_with_the_gap_in_the_error() -> None:
    r = PropertyResult("p", "", "P", min=0.5 + 1e-12, max=0.5, error=1e-12)
    (o,) = conditioning.ordered([r])
    assert o.min == o.max and o.min is not None and o.error is not None
    assert abs(o.min - 0.5) <= o.error and abs(o.min - (0.5 + 1e-12)) <= o.error


def test_a_failure_of_the_bounds_keeps_the_midpoint_values_as_reference(tmp_path: Path) -> None:
    from afsmc.diagnostics import CompileError
    from afsmc.verify.outcome.results import Partial

    root = Path(__file__).resolve().parents[3]
    text = (root / "examples" / "patrol.afsm").read_text(encoding="utf-8")
    box = tmp_path / "p0.afsm"  # an end at 0: the parametric engine refuses the box (E440)
    box.write_text(text.replace("const prob P_FAULT  = 0.01;",
                                "const prob P_FAULT = [0, 0.03];"), encoding="utf-8")
    mid = tmp_path / "mid.afsm"  # the oracle: the same mission at the midpoint
    mid.write_text(text.replace("const prob P_FAULT  = 0.01;",
                                "const prob P_FAULT = 0.015;"), encoding="utf-8")
    with pytest.raises(CompileError) as err:
        verify.run(str(box), properties=["finish"])
    assert [d.code for d in err.value.diagnostics] == ["E440", "N412"]
    partial = err.value.partial
    assert isinstance(partial, Partial)
    (r,) = partial.properties
    assert r.min is None and r.max is None and r.reference is not None  # never as bounds
    (want,) = verify.run(str(mid), properties=["finish"]).properties
    assert (r.reference.min, r.reference.max) == pytest.approx((want.min, want.max), abs=1e-9)
