"""A requirement's verdict from a min, a max and their error bound (afsmc.verify.outcome.verdicts):
every case is checked against the definition, judged by brute force over values the
true min and max may take within the error."""

from __future__ import annotations

import itertools
import operator
from fractions import Fraction

import pytest

from afsmc.model.ir import Threshold
from afsmc.verify.outcome.results import PropertyResult
from afsmc.verify.outcome.verdicts import failing, judge, judge_all

OPS = {">=": operator.ge, ">": operator.gt, "<=": operator.le, "<": operator.lt}


def _truth(op: str, t: Fraction, lo: Fraction, hi: Fraction) -> str:
    """The verdict of exact values: holds / fails / depends by the definition."""
    meets = [OPS[op](v, t) for v in (lo, hi)]
    if all(meets):
        return "holds"
    if not any(meets):
        return "fails"
    return "depends"


def _th(op: str, text: str) -> Threshold:
    return Threshold(op, float(text), text)  # type: ignore[arg-type]


@pytest.mark.parametrize("op", list(OPS))
def test_every_sure_verdict_agrees_with_every_true_value_within_the_error(op: str) -> None:
    grid = [Fraction(k, 20) for k in range(21)]
    e = Fraction(1, 40)
    for t, lo, hi in itertools.product([Fraction(1, 2), Fraction(3, 10)], grid, grid):
        if lo > hi:
            continue
        v = judge(_th(op, str(float(t))), float(lo), float(hi), float(e))
        # every pair of true values within the error (and still min <= max)
        truths = {_truth(op, t, lo + a, hi + b) for a in (-e, 0, e) for b in (-e, 0, e)
                  if lo + a <= hi + b}
        if v.kind == "undecided":
            assert len(truths) > 1, (op, t, lo, hi, truths)
        else:
            assert truths == {v.kind}, (op, t, lo, hi, v)


def test_the_bound_that_counts_and_the_one_that_breaks_it() -> None:
    # patrol's finish: min 0.8102, max 0.8316
    assert judge(_th(">=", "0.8"), 0.8102, 0.8316, 1e-6).kind == "holds"
    d = judge(_th(">=", "0.82"), 0.8102, 0.8316, 1e-6)
    assert (d.kind, d.broken_by) == ("depends", "min") and "0.8102" in d.reason
    assert judge(_th(">=", "0.9"), 0.8102, 0.8316, 1e-6).kind == "fails"
    # an upper bound is judged by the max
    d = judge(_th("<", "0.82"), 0.8102, 0.8316, 1e-6)
    assert (d.kind, d.broken_by) == ("depends", "max")
    assert judge(_th("<=", "0.9"), 0.8102, 0.8316, 1e-6).kind == "holds"


def test_a_threshold_within_the_error_is_undecided_and_exact_values_decide_it() -> None:
    assert judge(_th(">=", "0.81"), 0.8100004, 0.9, 1e-6).kind == "undecided"
    assert judge(_th(">=", "0.81"), 0.8100004, 0.9, 1e-9).kind == "holds"
    # exact: equal to the threshold meets >= and misses >
    assert judge(_th(">=", "0.65"), 0.65, 0.65, 0.0, "13/20", "13/20").kind == "holds"
    assert judge(_th(">", "0.65"), 0.65, 0.65, 0.0, "13/20", "13/20").kind == "fails"
    # the double nearest 0.65 is not 13/20: the exact text decides, not the float
    assert judge(_th(">=", "0.65"), 0.65, 0.65, 0.0, "1301/2000", "1301/2000").kind == "holds"
    assert judge(_th(">=", "0.65"), 0.65, 0.65, 0.0, "1299/2000", "1299/2000").kind == "fails"


def test_a_dtmc_holds_or_fails_and_judge_all_sets_the_error() -> None:
    dtmc = PropertyResult("r", "P>=0.5 [ F \"done\" ]", "P", value=0.7,
                          threshold=_th(">=", "0.5"))
    plain = PropertyResult("v", "P=? [ F \"done\" ]", "P", value=0.7)
    rew = PropertyResult("s", "R{\"steps\"}<=10 [ F \"done\" ]", "R", min=4.0,
                         max=float("inf"), threshold=_th("<=", "10"))
    dtmc, plain, rew = judge_all([dtmc, plain, rew], 1e-6)
    assert dtmc.verdict is not None and dtmc.verdict.kind == "holds"
    assert plain.verdict is None and plain.error == 1e-6
    # an infinite expected reward in some resolution: the requirement depends on it
    assert rew.verdict is not None and (rew.verdict.kind, rew.verdict.broken_by) == (
        "depends", "max")
    assert failing([dtmc, plain, rew]) == [rew]
    j = rew.to_json()
    assert j["threshold"] == {"op": "<=", "bound": 10.0} and j["verdict"] == "depends"
    assert j["broken_by"] == "max" and j["error"] == 1e-6
    assert plain.to_json()["threshold"] is None and plain.to_json()["verdict"] is None
