"""A syntax error raises CompileError with one diagnostic explaining the mistake (cases
taken from tests/golden/cases/err_syntax_*/expected.txt, called on the parser directly)."""

from __future__ import annotations

import pytest

from afsmc.diagnostics import CompileError, Diagnostic
from afsmc.syntax.errors.messages import NOT_OPERATOR, OPERATORS
from afsmc.syntax.parser import parse, parse_property

MODES = "mode A initial;\nmode B final;\n"


def _error(text: str) -> Diagnostic:
    with pytest.raises(CompileError) as err:
        parse(text, "t.afsm")
    (diag,) = err.value.diagnostics
    return diag


def _at(diag: Diagnostic) -> tuple[int, int, int]:
    """Line, column and length of the diagnostic's span (the carets under it)."""
    assert diag.span is not None
    return diag.span.line, diag.span.column, diag.span.end - diag.span.start


@pytest.mark.parametrize(("text", "code", "message", "hint", "at"), [
    pytest.param(
        "machine semi;\nconst int A = 1\nconst int B = 2;\n",
        "E102", "missing ';' at the end of the declaration",
        "add ';' here; the next line starts with 'const'", (2, 16, 1), id="semicolon"),
    pytest.param(
        "var x : [0..3] init 0;\nlabel l = x = 1;\n",
        "E103", "'=' is not a comparison; write '==' to compare", "found '='",
        (2, 13, 1), id="compare"),
    pytest.param(
        "machine m;\nmode A = 0 initial;\nmode B = 1 final;\n"
        "action Go in A {\n    0.5: goto B;\n    0.5: skip\n}\n",
        "E116", "missing ';' at the end of the outcome",
        "add ';' here; the next line starts with '}'", (6, 14, 1), id="outcome-semicolon"),
    pytest.param(
        MODES + "var x : [0..9] init 0;\naction a in A weight 0.5 when x > 5 { goto B; }\n",
        "E120", "the guard comes before the weight: 'action NAME in MODES when GUARD "
        "weight W { ... }'", "found 'when'", (4, 26, 4), id="weight-before-guard"),
    pytest.param(
        "machine m;\nmode A = 0 initial final; /* the only mode\nlabel s = mode == A;\n",
        "E117", "this comment is not closed",
        "close it with '*/'; everything after '/*' is part of it until then",
        (2, 27, 2), id="unclosed-comment"),
    pytest.param(
        "var x : [0..1] init 0;\nmodeA initial;\n",
        "E122", "'modeA' is not a keyword, and no name may stand here",
        "if the keyword 'mode' is meant, put a space after it: 'mode A'; else check the "
        "spelling", (2, 1, 5), id="keyword-run-into-name"),
    pytest.param(
        'const int K = 3;\nproperty p = P=? [ F<=K-1 "l" ];\n',
        "E121", "a step bound that is an expression is written in brackets",
        "write 'F<=(K - 1)'", (2, 20, 7), id="step-bound-expression"),
    pytest.param(
        MODES + "var x : [0..3] init 0;\nvar y : [0..3] init 0;\n"
        "action Go in A { x := 1 & y := 2; }\n",
        "E107", "updates of one outcome are separated by ','",
        "write ',' instead of '&' (PRISM joins updates with '&')", (5, 25, 1),
        id="update-ampersand"),
    pytest.param(
        MODES + "var x : [0..3] init 0;\n"
        "hazard H from {A} when x > 0 with probability 0.1 { goto B; }\n",
        "E124", "a hazard is either preemptive ('when GUARD') or probabilistic "
        "('with probability P'), not both",
        "for a probability that depends on the state, write 'with probability "
        "(x > 0 ? 0.1 : 0)'", (4, 30, 4), id="hazard-two-triggers"),
    pytest.param(
        "var x : [0..3] init 0;\nformula even = x mod 2 == 0;\n",
        "E123", "afsm has no infix 'mod': write 'mod(a, b)'", "write 'mod(x, 2)'",
        (2, 18, 3), id="infix-mod"),
    pytest.param(
        "label l = not x;\n", "E123", NOT_OPERATOR, OPERATORS, (1, 11, 3),
        id="python-not"),
    pytest.param(
        "formula f = x 2;\n", "E101", "missing operator between 'x' and '2'",
        "join them with an operator ('+', '==', '&&', ...) or end the declaration with ';'",
        (1, 15, 1), id="missing-operator"),
])
def test_a_mistake_gets_its_code_message_hint_and_span(
        text: str, code: str, message: str, hint: str, at: tuple[int, int, int]) -> None:
    diag = _error(text)
    assert (diag.code, diag.message, diag.hint) == (code, message, hint)
    assert _at(diag) == at


def test_an_unclosed_brace_points_at_the_end_and_at_the_brace() -> None:
    text = MODES + "action Go in A {\n    0.5: goto B;\n    0.5: skip;\n"
    diag = _error(text)
    assert (diag.code, diag.message) == ("E112", "missing '}'")
    assert diag.hint == "add '}' here; the file ends before it"
    assert _at(diag)[:2] == (5, 15)
    (note,) = diag.related
    assert note.message == "the '{' that is not closed"
    assert (note.span.line, note.span.column) == (3, 16)


def test_a_body_running_into_the_next_declaration_misses_its_brace() -> None:
    diag = _error(MODES + "action Go in A { goto B;\naction Back in B { goto A; }\n")
    assert (diag.code, diag.message) == ("E112", "missing '}' before the next declaration")
    assert _at(diag)[:2] == (3, 25)


def test_a_nested_temporal_operator_is_explained() -> None:
    diag = _error('label l = true;\nproperty p = P=? [ F F "l" ];\n')
    assert diag.code == "E115"
    assert diag.message.startswith("temporal operators (F, G, X, U) do not nest")


def test_a_formula_speaks_of_its_own_end() -> None:
    with pytest.raises(CompileError) as err:
        parse_property('P=? [ F "done"', "--formula")
    (diag,) = err.value.diagnostics
    assert (diag.code, diag.message) == ("E112", "missing ']'")
    assert diag.hint == "add ']' here; the formula ends before it"
    assert diag.span is not None and diag.span.source.path == "--formula"


def test_an_unknown_character_lists_what_was_expected() -> None:
    diag = _error("machine m;\nmode A initial; @\n")
    assert (diag.code, diag.message) == ("E101", "unexpected character '@'")
    assert diag.hint is not None and diag.hint.startswith("expected ")
    assert _at(diag)[:2] == (2, 17)
