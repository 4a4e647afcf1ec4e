"""afsmc.check.int_pow: an integer pow with a negative exponent assigned to an int variable
is E308 (Storm's engines disagree on it); rounded, or with a non-negative exponent, it is
fine."""

from __future__ import annotations

from afsmc.check.int_pow import check_int_pow
from tests.unit.check.rules import codes, line_of, run_rule

POW = """machine intpow;
var x : [0..3] init 0;
var y : [0..8] init 0 clamp;
mode S = 0 initial;
mode D = 1 final;
action Go in S when x < 3 { x := x + 1, y := pow(2, x - 1) + 1; }
action Stop in S when x == 3 { goto D; }
"""


def test_a_fractional_pow_assigned_to_an_int_is_e308() -> None:
    (d,) = run_rule(check_int_pow, POW)
    assert d.code == "E308"
    assert d.message == ("pow(2, x - 1) is a fraction where x - 1 < 0, as in the state "
                         "mode = S, x = 0, but an update of action Go assigns it to the "
                         "integer variable y")
    assert line_of(d, POW) == 6


def test_rounding_or_a_non_negative_exponent_is_fine() -> None:
    assert codes(check_int_pow, POW.replace("pow(2, x - 1) + 1", "floor(pow(2, x - 1))")) == []
    assert codes(check_int_pow, POW.replace("pow(2, x - 1)", "pow(2, x)")) == []
