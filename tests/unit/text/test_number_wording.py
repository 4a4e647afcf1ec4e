"""How numbers are printed: non-finite doubles, and huge state counts as powers of ten."""

from __future__ import annotations

import math

from afsmc.model.pretty import number
from afsmc.text import count


def test_printing_never_fails_on_a_non_finite_double() -> None:
    assert [number(v) for v in (math.inf, -math.inf, math.nan, 1e300, 2.0)] == \
        ["inf", "-inf", "nan", "1e+300", "2.0"]


def test_huge_state_counts_read_as_powers_of_ten() -> None:
    assert [count(n) for n in (12_345_678, 2.5e9, 2e19, 2 * 10**400, math.inf)] == \
        ["12.3 M", "2.5 G", "2.0e19", "2.0e400", "inf"]
