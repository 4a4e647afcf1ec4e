"""Fuzzing: whatever the input, `afsmc check` answers with its own diagnostics and
never with a Python exception. Inputs come from the grammar itself (hypothesis
`from_lark`) and from mutating the examples. `afsmc fmt` is fuzzed too: whatever parses,
it formats (its safety net never fires), idempotently, keeping the author's parentheses."""

from __future__ import annotations

from pathlib import Path

import lark
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from hypothesis.extra.lark import from_lark

from afsmc.compiler import load
from afsmc.diagnostics import CompileError, render_all
from afsmc.syntax.fmt import format_text
from afsmc.syntax.grammar import grammar_text
from afsmc.syntax.parser import parse
from tests.conftest import EXAMPLES

SETTINGS = settings(max_examples=100, deadline=None,
                    suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large])


def _check(text: str) -> None:
    try:
        checked = load("fuzz.afsm", text=text)
    except CompileError as exc:
        assert exc.diagnostics, "a CompileError carries at least one diagnostic"
        rendered = render_all(exc.diagnostics)
        assert "error[" in rendered
        for d in exc.diagnostics:
            if d.span is not None:
                assert 1 <= d.span.line <= text.count("\n") + 2
    else:
        render_all(checked.diagnostics)


# Names drawn from a small pool so that generated files often refer to real declarations.
NAMES = st.sampled_from(["a", "b", "x", "Idle", "Run", "Go", "p", "w", "succ", "mode_x", "T"])
GRAMMAR = lark.Lark(grammar_text(), start="start")


# from_lark joins tokens without the ignored whitespace: pad every token with spaces.
EXPLICIT = {t.name: st.just(f" {t.pattern.value} ") for t in GRAMMAR.terminals
            if isinstance(t.pattern, lark.lexer.PatternStr)}
EXPLICIT |= {"NAME": NAMES.map(lambda n: f" {n} "), "WS": st.just(" "),
             "NUMBER": st.sampled_from([" 0 ", " 1 ", " 2 ", " 0.5 ", " 10 ", " 3 "]),
             "ESCAPED_STRING": st.sampled_from([' "succ" ', ' "a" ']),
             "COMMENT": st.just("// c\n")}


@pytest.mark.slow
def test_generated_files_are_mostly_parseable() -> None:
    """The generator really exercises the checker, not just the syntax-error path (a fixed
    seed: a random search of 500 examples sometimes found no such file)."""
    from hypothesis import find

    text = find(from_lark(GRAMMAR, explicit=EXPLICIT), lambda t: "action" in t and "mode" in t,
                settings=settings(max_examples=2000, database=None, derandomize=True))
    lark.Lark(grammar_text(), parser="lalr").parse(text)


@pytest.mark.slow
@SETTINGS
@given(from_lark(GRAMMAR, explicit=EXPLICIT))
def test_grammar_generated_files_never_crash(text: str) -> None:
    _check(text)


EXAMPLE_TEXTS = [p.read_text() for p in sorted(EXAMPLES.glob("*.afsm"))] + [
    p.read_text() for p in sorted((Path(__file__).resolve().parents[2] / "golden" / "cases").glob("*/input.afsm"))]


@st.composite
def mutated(draw: st.DrawFn) -> str:
    text = draw(st.sampled_from(EXAMPLE_TEXTS))
    for _ in range(draw(st.integers(1, 4))):
        if not text:
            break
        i = draw(st.integers(0, len(text) - 1))
        j = draw(st.integers(i, min(len(text), i + 40)))
        op = draw(st.sampled_from(["delete", "duplicate", "replace", "insert"]))
        if op == "delete":
            text = text[:i] + text[j:]
        elif op == "duplicate":
            text = text[:j] + text[i:j] + text[j:]
        elif op == "replace":
            text = text[:i] + draw(st.sampled_from(list("{}();:=,.[]!&|?+-*/<>\"0 x"))) + text[i + 1:]
        else:
            token = draw(st.sampled_from(["mode", "goto", "weight", "when", " w(Search) ",
                                          "[0..2]", "1e309", "0.0", "/ 0", "init", "T",
                                          "\u00e9", "\t", "\n"]))
            text = text[:i] + token + text[i:]
    return text


@pytest.mark.slow
@SETTINGS
@given(mutated())
def test_mutated_examples_never_crash(text: str) -> None:
    _check(text)


@settings(max_examples=60, deadline=None)
@given(st.text(max_size=200))
def test_arbitrary_text_never_crashes(text: str) -> None:
    _check(text)


def _formats(text: str) -> str | None:
    """The formatted text, or None if `text` does not parse; the formatter's own refusal
    (E190: its output would not parse or would mean something else) fails the test."""
    try:
        parse(text, "fuzz.afsm")
    except CompileError:
        return None
    out = format_text(text, "fuzz.afsm")
    assert format_text(out, "fuzz.afsm") == out, "formatting is idempotent"
    return out


@pytest.mark.slow
@SETTINGS
@given(from_lark(GRAMMAR, explicit=EXPLICIT))
def test_grammar_generated_files_format(text: str) -> None:
    _formats(text)


@st.composite
def arithmetic(draw: st.DrawFn, depth: int = 0) -> str:
    """Expression text with parentheses, minus signs and spacing as an author might write."""
    space = draw(st.sampled_from(["", " ", "  "]))
    kind = draw(st.sampled_from(["atom", "atom", "neg", "paren", "binary"] if depth < 4
                                else ["atom"]))
    if kind == "atom":
        return draw(st.sampled_from(["1", "1.5", "0", "2e3", "a", "b", "max(a, 2)"]))
    inner = draw(arithmetic(depth + 1))
    if kind == "neg":
        return "-" + space + inner
    if kind == "paren":
        return "(" + space + inner + space + ")"
    op = draw(st.sampled_from(["+", "-", "*", "/"]))
    return inner + space + op + space + draw(arithmetic(depth + 1))


@pytest.mark.slow
@settings(max_examples=200, deadline=None)
@given(arithmetic())
def test_fmt_keeps_parentheses_and_never_joins_minus_signs(e: str) -> None:
    """`-(-1.5)` once came out as `--1.5` and `((a))` as `(a)` (docs/editors.md: the
    parentheses the author wrote are kept, none added or dropped)."""
    text = f"machine m;\nconst double a = 1;\nconst double b = 2;\nconst double D = {e};\n"
    out = _formats(text)
    assert out is not None, "every generated expression is afsm"
    printed = out.split("const double D = ", 1)[1].split(";", 1)[0].lstrip()
    assert "--" not in printed
    assert printed.count("(") == e.count("(")
    assert printed.replace(" ", "") == e.replace(" ", "")
