"""Constants and intervals: values computed in declaration order, interval constants,
params set with --const, and the errors of each (E204-E211, E229)."""

from __future__ import annotations

import pytest

from afsmc.model.expr import Type
from afsmc.resolve import parse_override
from tests.unit.resolve.util import FRAME, codes, errors, resolved


def test_an_interval_constant_keeps_both_ends_and_its_lower_end_as_value() -> None:
    model = resolved(FRAME + "const int D = [1, 3];\n"
                     "action Go in A { x := min(3, x + D); }\n").model
    d = model.constant("D")
    assert d.interval == (1, 3) and d.value == 1 and d.is_interval
    assert model.interval_constants == (d,) and model.is_nondeterministic


def test_an_interval_bound_may_be_a_constant_expression() -> None:
    model = resolved(FRAME + "const int N = 2;\nconst int D = [N - 1, 2 * N];\n"
                     "action Go in A { x := min(3, x + D); }\n").model
    assert model.constant("D").interval == (1, 4)


def test_an_interval_constant_outside_an_update_is_e229() -> None:
    (d,) = errors(FRAME + "const int D = [1, 2];\naction Go in A when x < D { skip; }\n")
    assert d.code == "E229"
    assert d.message == "interval constant 'D' can only be used in updates, not in a guard"


@pytest.mark.parametrize(("decl", "code"), [
    ("const double D = [1, 2];", "E204"),
    ("const int D = [3, 2];", "E205"),
])
def test_an_interval_must_be_an_int_and_not_empty(decl: str, code: str) -> None:
    assert codes(FRAME + decl + "\naction Go in A { skip; }\n") == [code]


def test_a_param_takes_its_default_or_the_command_line_value() -> None:
    text = FRAME + "param int N = 2;\nparam double p = 0.5;\naction Go in A when x < N { skip; }\n"
    model = resolved(text).model
    assert model.constant("N").value == 2 and model.constant("N").is_param
    model = resolved(text, {"N": "3", "p": "1"}).model
    assert model.constant("N").value == 3
    p = model.constant("p")
    assert p.value == 1.0 and isinstance(p.value, float) and p.type is Type.DOUBLE


def test_constants_computed_from_a_param_follow_the_override() -> None:
    text = FRAME + "param int N = 2;\nconst int M = N * N + 1;\naction Go in A when x < M { skip; }\n"
    assert resolved(text, {"N": "5"}).model.constant("M").value == 26


def test_an_override_of_an_undeclared_name_is_e209_with_a_suggestion() -> None:
    (d,) = errors(FRAME + "param int CELLS = 2;\naction Go in A when x < CELLS { skip; }\n",
                  {"CELLZ": "3"})
    assert d.code == "E209" and d.message == "--const CELLZ: no open constant named 'CELLZ'"
    assert d.hint == "did you mean 'CELLS'?"


def test_an_override_of_a_fixed_constant_is_e209() -> None:
    (d,) = errors(FRAME + "const int K = 2;\naction Go in A when x < K { skip; }\n", {"K": "3"})
    assert d.code == "E209" and d.message == "--const K: 'K' is a fixed constant"


@pytest.mark.parametrize(("value", "why"), [
    ("three", "not an int"),
    ("1_0", "not an int"),
    ("9223372036854775808", "does not fit in a 64-bit integer"),
])
def test_an_override_that_is_no_int64_is_e208(value: str, why: str) -> None:
    (d,) = errors(FRAME + "param int N = 2;\naction Go in A when x < N { skip; }\n", {"N": value})
    assert d.code == "E208" and d.message.startswith(f"--const N={value}: {why}")


def test_a_param_without_a_value_is_e206_once() -> None:
    # not also an empty range [0..-1] from its stand-in value
    text = FRAME + "param int N;\nvar cell : [0..N-1] init 0;\naction Go in A when cell < N { skip; }\n"
    (d,) = errors(text)
    assert d.code == "E206" and d.message == "open constant 'N' has no value"


def test_a_probability_outside_0_1_is_e207() -> None:
    assert codes(FRAME + "const prob p = 1.5;\naction Go in A weight p { skip; }\n") == ["E207"]


def test_a_constant_cannot_read_a_variable_or_be_used_before_its_declaration() -> None:
    assert codes(FRAME + "const int K = x + 1;\nconst int L = M;\nconst int M = 1;\n"
                 "action Go in A when x < K + L { skip; }\n") == ["E224", "E228"]


def test_a_constant_that_cannot_be_evaluated_is_e211() -> None:
    assert codes(FRAME + "const int K = 0;\nconst double L = 1 / K;\n"
                 "action Go in A weight L { skip; }\n") == ["E211"]


def test_parse_override_splits_at_the_first_equals_sign_and_strips() -> None:
    assert parse_override(" N = 3 ") == ("N", "3")
    assert parse_override("s=a=b") == ("s", "a=b")
    for bad in ("N", "=3", "N="):
        with pytest.raises(ValueError, match="expected NAME=VALUE"):
            parse_override(bad)
