"""afsmc.check.mode_numbers: mode numbers that span more than WIDE values (slow for Storm's
symbolic engines) are W305."""

from __future__ import annotations

from afsmc.check.mode_numbers import WIDE, check_mode_numbers
from tests.unit.check.rules import codes, line_of, run_rule

TEXT = """machine m;
mode A = 1000000 initial;
mode B final;
action a in A { goto B; }
"""


def test_a_sparse_numbering_is_w305_at_the_widest_mode() -> None:
    (d,) = run_rule(check_mode_numbers, TEXT)
    assert d.code == "W305" and not d.is_error
    assert d.message.startswith("the mode numbers span 1,000,001 values for 2 modes")
    assert line_of(d, TEXT) == 2


def test_a_dense_numbering_is_fine() -> None:
    assert codes(check_mode_numbers, TEXT.replace("1000000", "0")) == []
    assert codes(check_mode_numbers, TEXT.replace("1000000", str(WIDE - 2))) == []
