"""afsmc.check.undefined: a part of an expression that is undefined (division by zero) in a
state where it is evaluated is E306; one made of constants only is E245."""

from __future__ import annotations

from afsmc.check.undefined import check_undefined
from tests.unit.check.rules import codes, line_of, run_rule

DIV = """machine div_update;
var x : [0..3] init 0;
var y : [0..3] init 0 clamp;
mode A = 0 initial;
mode B = 1 final;
action Go in A { y := floor(3 / x); goto B; }
"""


def test_a_division_by_zero_where_an_update_is_evaluated_is_e306() -> None:
    (d,) = run_rule(check_undefined, DIV)
    assert d.code == "E306"
    assert d.message == ("3 / x is undefined (division by zero) in the state mode = A, x = 0, "
                         "where an update of action Go is evaluated")
    assert line_of(d, DIV) == 6
    assert d.hint is not None and "'x != 0 && ...'" in d.hint


def test_a_guard_that_excludes_the_zero_makes_it_defined() -> None:
    assert codes(check_undefined, DIV.replace("action Go in A {", "action Go in A when x > 0 {")
                 .replace("mode B = 1 final;", "mode B = 1 final;\naction Wait in A when x == 0 "
                          "{ x := 1; }")) == []


def test_a_constant_part_that_cannot_be_computed_is_e245() -> None:
    text = """machine c;
const int Z = 0;
var y : [0..3] init 0 clamp;
mode A = 0 initial;
mode B = 1 final;
action Go in A { y := floor(3 / Z); goto B; }
"""
    (d,) = run_rule(check_undefined, text)
    assert d.code == "E245"
    assert d.message.startswith("this expression cannot be compiled: 3 / Z is undefined")
