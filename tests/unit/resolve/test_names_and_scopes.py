"""Names and scopes: every name declared once (E201), reserved and internal names refused
(E202), and names looked up where they are used (E203, E215, E223, E227, E230, E231)."""

from __future__ import annotations

from tests.unit.resolve.util import FRAME, codes, errors, resolved


def test_a_constant_named_like_a_variable_is_e201_pointing_at_the_first() -> None:
    (d,) = errors(FRAME + "const int x = 2;\n")
    assert d.code == "E201" and d.message == "'x' is already declared as a variable"
    assert [r.message for r in d.related] == ["first declared here"]
    assert d.related[0].span.line == 2


def test_an_action_declared_twice_is_e201() -> None:
    (d,) = errors(FRAME + "action Go in A { skip; }\naction Go in A { skip; }\n")
    assert d.code == "E201" and d.message == "action 'Go' is declared twice"


def test_an_action_named_like_a_variable_is_e201() -> None:
    (d,) = errors(FRAME + "action x in A { skip; }\n")
    assert d.code == "E201" and "names both an action and the variable x" in d.message


def test_a_tuple_field_whose_flat_name_is_taken_is_e201_once() -> None:
    # `pos.x` is `pos_x` in PRISM; its uses are not also E223
    text = FRAME + "var pos_x : [0..1] init 0;\nvar pos : (x : [0..1], y : [0..1]);\n" \
        "action Go in A when pos.x == 0 && pos_x == 0 && pos.y == 0 { skip; }\n"
    assert codes(text) == ["E201"]


def test_reserved_and_internal_names_are_e202() -> None:
    (d,) = errors(FRAME + "const int max = 1;\n")
    assert d.code == "E202" and "reserved in PRISM or Storm" in d.message
    (d,) = errors(FRAME + "const int __k = 1;\n")
    assert d.code == "E202" and "names that start with __ are reserved" in d.message
    assert d.hint == "choose another name, e.g. 'k'"


def test_an_undeclared_name_is_e203_with_a_suggestion() -> None:
    (d,) = errors(FRAME.replace("var x", "var level") + "action Go in A when levl < 3 { skip; }\n")
    assert d.code == "E203" and d.message == "'levl' is not declared"
    assert d.hint == "did you mean 'level'?"


def test_an_undeclared_name_in_a_comparison_is_not_also_a_type_error() -> None:
    assert codes(FRAME + "action Go in A when mode == Alpa { skip; }\n") == ["E203"]


def test_an_unknown_mode_is_e215() -> None:
    assert codes(FRAME + "action Go in Z { goto Q; }\n") == ["E215", "E215"]


def test_an_unknown_label_reward_or_action_reference_is_e203() -> None:
    text = FRAME + "rewards r { [Stop] true : 1; }\naction Go in A { skip; }\n" \
        "property p = P=? [ F \"nope\" ];\nproperty q = R{\"s\"}=? [ F mode == B ];\n"
    assert codes(text) == ["E203", "E203", "E203"]


def test_an_action_used_as_a_value_is_e227() -> None:
    (d,) = errors(FRAME + "action Go in A weight Other { skip; }\naction Other in A { skip; }\n")
    assert d.code == "E227" and d.hint == "its weight is written w(Other)"


def test_a_tuple_needs_a_field_and_has_only_its_own() -> None:
    text = FRAME + "var pos : (x : [0..1], y : [0..1]);\n" \
        "action Go in A when pos == 0 || pos.z == 0 { skip; }\n"
    assert codes(text) == ["E230", "E223"]


def test_a_constant_cannot_use_a_formula() -> None:
    assert codes(FRAME + "formula f = 1;\nconst int K = f;\n"
                 "action Go in A when x < K { skip; }\n") == ["E231"]


def test_a_formula_may_use_a_formula_declared_after_it_but_not_itself() -> None:
    ok = FRAME + "formula f = g + 1;\nformula g = x;\naction Go in A when f < 3 { skip; }\n"
    assert [f.name for f in resolved(ok).model.formulas] == ["f", "g"]
    assert codes(FRAME + "formula f = f + 1;\naction Go in A when f < 3 { skip; }\n") == ["E221"]
