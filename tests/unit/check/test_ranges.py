"""afsmc.check.ranges: an update that can leave its variable's range is E303, with the
witness state; a clamped variable or a guarded update is fine."""

from __future__ import annotations

from afsmc.check.ranges import check_update_ranges
from tests.unit.check.rules import codes, line_of, run_rule

RANGE = """machine range;
const int D = [1, 2];
var x : [0..3] init 0;
mode A = 0 initial;
action Step in A when x < 3 { x += D; }
action Stop in A when x >= 3 { skip; }
"""


def test_an_update_out_of_range_is_e303_with_the_state() -> None:
    (d,) = run_rule(check_update_ranges, RANGE)
    assert d.code == "E303"
    assert d.message == ("this update can take x out of its range [0..3]: x + D = 4 in the "
                         "state mode = A, x = 2, D = 2")
    assert line_of(d, RANGE) == 5


def test_clamping_or_a_tighter_guard_keeps_the_update_in_range() -> None:
    assert codes(check_update_ranges, RANGE.replace("init 0;", "init 0 clamp;")) == []
    assert codes(check_update_ranges, RANGE.replace("when x < 3 {", "when x < 2 {")) == []
