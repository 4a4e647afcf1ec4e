"""afsmc.check.overflow: an integer expression that the variables' ranges take beyond 64
bits, where it is evaluated, is E307; computing in doubles is fine."""

from __future__ import annotations

from afsmc.check.overflow import check_overflow
from tests.unit.check.rules import codes, line_of, run_rule

BIG = """machine overflow;
const int BIG = 4000000000000000000;
var x : [0..3] init 0;
mode A = 0 initial;
mode B = 1 final;
formula scaled = x * BIG;
action Go in A when scaled > 0 { goto B; }
action Grow in A when x < 3 weight 0.5 { x += 1; }
"""


def test_a_product_beyond_64_bits_is_e307_at_the_formula() -> None:
    (d,) = run_rule(check_overflow, BIG)
    assert d.code == "E307"
    assert d.message == ("x * BIG can reach 1.2e+19 (x in [0..3]), beyond a 64-bit integer, "
                         "where the guard of action Go is evaluated")
    assert line_of(d, BIG) == 6


def test_the_same_product_in_doubles_does_not_overflow() -> None:
    assert codes(check_overflow, BIG.replace("x * BIG", "1.0 * x * BIG")) == []
