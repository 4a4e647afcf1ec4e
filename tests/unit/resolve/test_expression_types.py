"""Expressions and types: each expression is typed where it stands (E222, E224-E226,
E232-E234), and a part that needs no state is folded to check PRISM and Storm can hold
its value (E245)."""

from __future__ import annotations

from afsmc.model import expr as E
from afsmc.model.expr import Type
from tests.unit.resolve.util import FRAME, codes, errors, resolved


def _weight(expr: str, decls: str = "") -> E.Expr:
    model = resolved(FRAME + decls + f"action Go in A weight {expr} {{ skip; }}\n").model
    return model.action("Go").weight


def test_division_is_a_double_and_min_of_ints_an_int() -> None:
    assert _weight("x / 2").type is Type.DOUBLE
    assert _weight("min(1, x)").type is Type.INT
    assert _weight("max(1, 0.5)").type is Type.DOUBLE
    assert _weight("floor(x / 2)").type is Type.INT
    assert _weight("x > 0 ? 1 : 0.5").type is Type.DOUBLE


def test_names_resolve_to_typed_references() -> None:
    w = _weight("K * x", "const double K = 0.5;\n")
    assert isinstance(w, E.Binary) and w.type is Type.DOUBLE
    assert isinstance(w.left, E.ConstRef) and w.left.name == "K"
    assert isinstance(w.right, E.VarRef) and w.right.name == "x" and w.right.type is Type.INT


def test_guards_and_weights_must_have_their_type() -> None:
    ds = errors(FRAME + "var flag : bool init false;\n"
                "action Go in A when x + 1 weight flag { skip; }\n")
    assert [(d.code, d.message) for d in ds] == [
        ("E222", "a guard must be true or false, not an int"),
        ("E222", "a weight must be a number, not a bool")]


def test_comparisons_need_comparable_types() -> None:
    (d,) = errors(FRAME + "label l = mode == 1;\n")
    assert d.code == "E226" and d.message == "cannot compare a mode with an int"
    assert codes(FRAME + "var flag : bool init false;\n"
                 "action Go in A when flag < 1 { skip; }\n") == ["E226"]


def test_assignments_keep_the_variable_type() -> None:
    ds = errors(FRAME + "var flag : bool init false;\naction Go in A { flag := 2, x := 0.5; }\n")
    assert [(d.code, d.message) for d in ds] == [
        ("E239", "'flag' is a bool; cannot assign an int"),
        ("E239", "'x' is an int; cannot assign a double")]


def test_the_mode_and_labels_only_where_they_may_stand() -> None:
    assert codes(FRAME + "const int K = mode == A ? 1 : 0;\n") == ["E224"]
    assert codes(FRAME + "label l = x > 0;\naction Go in A when \"l\" { skip; }\n") == ["E225"]


def test_functions_are_known_and_take_their_arguments() -> None:
    assert codes(FRAME + "action Go in A weight sqrt(x) { skip; }\n") == ["E233"]
    assert codes(FRAME + "action Go in A weight floor(x, 2) { skip; }\n") == ["E234"]
    assert codes(FRAME + "action Go in A weight mod(x, 0.5) { skip; }\n") == ["E234"]


def test_w_names_an_action_and_stands_only_in_a_weight() -> None:
    w = _weight("2 * w(Other)", "action Other in A { skip; }\n")
    assert any(isinstance(n, E.WeightRef) and n.action == "Other" for n in E.walk(w))
    assert codes(FRAME + "action Go in A when w(Go) > 0 { skip; }\n") == ["E232"]
    assert codes(FRAME + "action Go in A weight w(Nobody) { skip; }\n") == ["E203"]


def test_weights_referring_to_each_other_in_a_cycle_are_e240() -> None:
    (d,) = errors(FRAME + "action Up in A weight w(Down) { skip; }\n"
                  "action Down in A weight w(Up) { skip; }\n")
    assert d.code == "E240" and d.message.endswith("w(Up) -> w(Down) -> w(Up)")


def test_a_constant_part_beyond_int64_is_e245() -> None:
    (d,) = errors(FRAME + "action Go in A weight x + 9223372036854775807 * 2 { skip; }\n")
    assert d.code == "E245" and "does not fit in a 64-bit integer" in d.message
    assert codes(FRAME + "action Go in A weight 9223372036854775808 { skip; }\n") == ["E245"]


def test_a_range_beyond_what_storm_stores_is_e249() -> None:
    (d,) = errors(FRAME + "var big : [0..281474976710656] init 0;\n"
                  "action Go in A when big > 0 { skip; }\n")
    assert d.code == "E249" and "±2^48" in d.message
