"""The value grammar of `afsmc sweep --const NAME=VALUES` and `--bound`: `parse_values`."""

from __future__ import annotations

import pytest

from afsmc.verify.reports.sweep_values import MAX_POINTS, parse_values


def test_a_range_includes_its_stop_when_the_steps_reach_it() -> None:
    assert parse_values("0:900:300") == [0, 300, 600, 900]
    assert parse_values("0:10:4") == [0, 4, 8]
    assert parse_values("2:5") == [2, 3, 4, 5]  # the step defaults to 1
    assert parse_values(" 7:7 ") == [7]


def test_decimal_steps_are_exact() -> None:
    got = parse_values("0:1:0.1")
    assert len(got) == 11
    assert got == [0.0, 0.1, 0.2, 0.3, 0.4, 0.5, 0.6, 0.7, 0.8, 0.9, 1.0]
    assert parse_values("0:1:0.25") == [0.0, 0.25, 0.5, 0.75, 1.0]


def test_a_list_is_sorted() -> None:
    assert parse_values("30,10,20") == [10, 20, 30]
    assert parse_values("1, 2,5") == [1, 2, 5]
    assert parse_values("-1.5,2") == [-1.5, 2]


def test_an_int_stays_an_int_only_as_written_so() -> None:
    ints = parse_values("0:4:2")
    assert ints == [0, 2, 4] and all(type(x) is int for x in ints)
    doubles = parse_values("0:2.0")  # a decimal anywhere in the range: every value a double
    assert doubles == [0.0, 1.0, 2.0] and all(type(x) is float for x in doubles)
    mixed = parse_values("1,2.0,1e1")
    assert [type(x) for x in mixed] == [int, float, float]
    assert [type(x) for x in parse_values("1e0")] == [float]


def test_bools_sweep_a_bool_constant() -> None:
    assert parse_values("true,false") == [False, True]
    assert parse_values("true") == [True]


@pytest.mark.parametrize(("text", "message"), [
    ("", "no values"),
    ("   ", "no values"),
    ("0:10:0", "the step of '0:10:0' must be positive"),
    ("0:10:-1", "must be positive"),
    ("5:1", "'5:1' is empty: stop is below start"),
    ("a:b", "expected numbers in start:stop:step, got 'a:b'"),
    ("1:2:3:4", "expected start:stop:step, got '1:2:3:4'"),
    ("0:inf", "expected finite numbers"),
    ("1,x", "not a number: 'x'"),
    ("1,nan", "not a finite number: 'nan'"),
    ("3,3", "3 is given twice in '3,3'"),
    ("1,2.0,2.0", "2.0 is given twice"),
    ("true,1", "mixes true/false with numbers"),
    ("true,true", "a value is given twice"),
])
def test_malformed_values_are_refused_with_a_reason(text: str, message: str) -> None:
    with pytest.raises(ValueError) as info:
        parse_values(text)
    assert message in str(info.value), str(info.value)


def test_a_range_has_at_most_max_points() -> None:
    assert len(parse_values(f"1:{MAX_POINTS}")) == MAX_POINTS
    with pytest.raises(ValueError) as info:
        parse_values(f"0:{MAX_POINTS}")
    assert str(info.value) == f"'0:{MAX_POINTS}' has 10,001 points; at most 10,000"


def test_a_value_of_thousands_of_digits_is_refused_not_a_crash() -> None:
    """Python's int-string limit (4,300 digits) is never reached: a whole number beyond 64
    bits is refused before it is converted or printed."""
    import pytest as _pytest

    from afsmc.verify.reports import sweep_values

    with _pytest.raises(ValueError, match="does not fit in a 64-bit integer"):
        sweep_values._list("1" * 5000)
    with _pytest.raises(ValueError, match="more than 10\\^18 points"):
        sweep_values._range("0:" + "1" * 5000)
