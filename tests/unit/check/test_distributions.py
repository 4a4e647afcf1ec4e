"""afsmc.check.distributions: a hazard's probability outside [0, 1] is E304; outcome
probabilities that do not sum to 1 are E305."""

from __future__ import annotations

from afsmc.check.distributions import check_distributions
from tests.unit.check.rules import codes, line_of, run_rule

HAZARD = """machine hz;
var x : [0..3] init 0;
mode A = 0 initial;
mode Broken = 1 final;
action Go in A { x := 3 - x; }
hazard Fault from * with probability 1.5 { goto Broken; }
"""

SUM = """machine sum;
const prob P_UP = 0.3;
var x : [0..3] init 0;
mode A = 0 initial;
action Step in A when x < 3 {
    P_UP: x += 1;
    0.6:  skip;
}
action Stop in A when x == 3 { skip; }
"""


def test_a_hazard_probability_outside_zero_one_is_e304() -> None:
    (d,) = run_rule(check_distributions, HAZARD)
    assert d.code == "E304"
    assert d.message == ("the probability of hazard Fault is 1.5, outside [0, 1], in the "
                         "state mode = A")
    assert line_of(d, HAZARD) == 6
    assert codes(check_distributions, HAZARD.replace("1.5", "0.5")) == []


def test_outcomes_that_do_not_sum_to_one_are_e305() -> None:
    (d,) = run_rule(check_distributions, SUM)
    assert d.code == "E305"
    assert d.message == "the outcome probabilities of action Step sum to 0.9, not 1"
    assert line_of(d, SUM) == 6
    assert codes(check_distributions, SUM.replace("0.6:", "1 - P_UP:")) == []


def test_a_state_dependent_sum_names_the_state() -> None:
    text = """machine sums;
var b : [0..10] init 4;
mode A initial;
mode B final;
action Go in A when b > 0 & b < 5 { b / 10 : b -= 1; 1 - b / 5 : b -= 1; }
action Stop in A when b == 0 | b >= 5 { goto B; }
"""
    (d,) = run_rule(check_distributions, text)
    assert d.code == "E305"
    assert d.message.endswith("sum to 0.9, not 1, in the state mode = A, b = 1")
