"""afsmc.check.weights: Definition 2 (weights in [0, 1], distinct among the enabled actions),
modes that stop the machine (W301, W302) and w() of an action in other modes (W306)."""

from __future__ import annotations

from afsmc.check.weights import (
    check_deadlock,
    check_weight_range,
    check_weight_refs,
    check_weight_uniqueness,
)
from tests.unit.check.rules import codes, line_of, run_rule

TIE = """machine tie;
var b : [0..10] init 10;
mode Search = 0 initial;
mode Home = 1 final;
action Search in Search when b > 0 weight b / 10 { b -= 1; }
action Back in Search weight 0.5 { goto Home; }
"""


def test_weights_that_tie_in_a_reachable_state_are_e301() -> None:
    (d,) = run_rule(check_weight_uniqueness, TIE)
    assert d.code == "E301" and d.is_error
    assert d.message == "weights of Search and Back tie (both 0.5) in the state mode = Search, b = 5"
    assert line_of(d, TIE) == 5
    assert [r.message for r in d.related] == ["the weight of Back"]


def test_weights_whose_ranges_never_meet_do_not_tie() -> None:
    assert codes(check_weight_uniqueness, TIE.replace("weight 0.5", "weight 0.05")) == []


def test_a_weight_outside_zero_one_is_e302() -> None:
    text = """machine wr;
var x : [0..3] init 0;
mode A = 0 initial;
action Go in A weight x / 2 { x := 0; }
"""
    (d,) = run_rule(check_weight_range, text)
    assert d.code == "E302"
    assert d.message == "the weight of Go is 1.5, outside [0, 1], in the state mode = A, x = 3"
    assert codes(check_weight_range, text.replace("x / 2", "x / 3")) == []


def test_a_non_final_mode_without_actions_is_w301() -> None:
    text = """machine w;
mode A = 0 initial;
mode B = 1;
action Go in A { goto B; }
"""
    (d,) = run_rule(check_deadlock, text)
    assert d.code == "W301" and not d.is_error
    assert d.message == "mode B has no actions: the machine stops there"
    assert codes(check_deadlock, text.replace("mode B = 1;", "mode B = 1 final;")) == []


def test_a_state_where_no_action_is_enabled_is_w302() -> None:
    text = """machine stuck;
var x : [0..3] init 0;
mode A = 0 initial;
mode Done = 1 final;
action Up in A when x < 2 { x += 1; }
action Finish in A when x == 3 { goto Done; }
"""
    (d,) = run_rule(check_deadlock, text)
    assert d.code == "W302"
    assert d.message.startswith("no action is enabled in the state mode = A, x = 2")
    assert codes(check_deadlock, text.replace("x == 3", "x >= 2")) == []


def test_w_of_an_action_of_other_modes_is_w306() -> None:
    text = """machine c;
var x : [0..3] init 0;
mode A initial;
mode C;
mode B final;
action Move in C when x < 3 weight 0.5 { x += 1; }
action Go in A weight (1 - w(Move)) / 2 { goto C; }
action Back in C when x == 3 weight 0.2 { goto B; }
"""
    (d,) = run_rule(check_weight_refs, text)
    assert d.code == "W306"
    assert d.message == "w(Move) in the weight of Go is always 0: Move acts in none of Go's modes (A)"
    assert line_of(d, text) == 7


def test_w302_says_the_state_may_be_unreachable_and_how_to_silence_it() -> None:
    # The newcomer's case: `items_left = 0` in ToPack cannot be reached (Last leaves the
    # mode), but the check searches every value of the variables.
    text = """machine pack;
var items_left : [0..3] init 3;
mode ToPack = 0 initial;
mode Done = 1 final;
action Pack in ToPack when items_left > 1 { items_left -= 1; }
action Last in ToPack when items_left == 1 { items_left := 0; goto Done; }
"""
    (d,) = run_rule(check_deadlock, text)
    assert d.code == "W302"
    assert "mode = ToPack, items_left = 0: the machine stops there if it can reach it" in d.message
    assert d.hint is not None and "may be unreachable" in d.hint and "warning goes" in d.hint
    # following the hint: a guard widened over the unreachable state silences it
    assert codes(check_deadlock, text.replace("items_left == 1", "items_left <= 1")) == []
