"""afsmc.syntax.drive gives the AST (spans and diagnostics included) that lark's tree and
Builder.build give, or gives up."""

from __future__ import annotations

import dataclasses
import random
from pathlib import Path
from typing import Any

import pytest
from lark import Token

from afsmc.diagnostics import Reporter, Source, Span
from afsmc.syntax import drive
from afsmc.syntax.build import Builder
from afsmc.syntax.grammar import _LEXING, EXPR_RULES, lalr
from tests.fuzz import generate

ROOT = Path(__file__).resolve().parents[3]
FILES = sorted([*ROOT.glob("examples/*.afsm"), *ROOT.glob("tests/golden/cases/*/input.afsm")])


def _key(x: Any) -> Any:
    """Everything of an AST a later stage could read: node types, fields, spans."""
    if isinstance(x, Span):
        return ("span", x.line, x.column, x.end_line, x.end_column, x.start, x.end)
    if dataclasses.is_dataclass(x) and not isinstance(x, type):
        return (type(x).__name__, *((f.name, _key(getattr(x, f.name)))
                                    for f in dataclasses.fields(x) if f.name != "source"))
    if isinstance(x, Token):
        return ("token", x.type, str(x), x.start_pos, x.end_pos)
    if isinstance(x, (tuple, list)):
        return tuple(_key(y) for y in x)
    return ("other", type(x).__name__, repr(x))


def _answer(node: Any, reporter: Reporter) -> Any:
    return (_key(node), tuple((d.code, d.message, _key(d.span)) for d in reporter.diagnostics))


def _both(text: str, start: str = "start") -> tuple[Any, Any]:
    """(lark's tree built by Builder.build, drive's answer): the AST's key and the
    diagnostics, or the exception's type."""
    source = Source("t.afsm", text)
    reset = _LEXING.set(text)
    try:
        try:
            builder = Builder(source, Reporter())
            lark_answer = _answer(builder.build(lalr().parse(text, start=start)),
                                  builder.reporter)
        except Exception as exc:
            lark_answer = type(exc).__name__
        try:
            builder = Builder(source, Reporter())
            drive_answer = _answer(drive.parse(lalr(), text, start, builder, EXPR_RULES),
                                   builder.reporter)
        except drive.GiveUp:
            drive_answer = "GiveUp"
        except Exception as exc:
            drive_answer = type(exc).__name__
    finally:
        _LEXING.reset(reset)
    return lark_answer, drive_answer


@pytest.mark.parametrize("path", FILES, ids=lambda p: p.parent.name if p.name == "input.afsm"
                         else p.name)
def test_the_repository_files_parse_to_larks_tree_or_give_up(path: Path) -> None:
    lark_answer, drive_answer = _both(path.read_text(encoding="utf-8", errors="replace"))
    if isinstance(lark_answer, tuple):
        assert drive_answer == lark_answer
    else:  # lark raised: drive may not pretend the text parsed
        assert not isinstance(drive_answer, tuple)


def test_generated_and_mutated_specs_parse_to_larks_tree_or_give_up() -> None:
    rng = random.Random(36)
    seeds = generate.seeds()
    parsed = 0
    for i in range(60):
        text = (generate.spec(rng) if i % 3 == 0 else generate.from_grammar(rng) if i % 3 == 1
                else generate.mutate(rng, rng.choice(seeds)).decode("utf-8", "replace"))
        lark_answer, drive_answer = _both(text)
        if isinstance(lark_answer, tuple):
            assert drive_answer == lark_answer, text
            parsed += 1
        else:
            assert not isinstance(drive_answer, tuple), text
    assert parsed >= 10


@pytest.mark.parametrize("prop", ['P=? [ F mode == A ]', 'Pmax>=0.5 [ G<=(N+1) x < 3 ]',
                                  'R{"t"}min=? [ F done ]', 'P=? [ x U<=4 "a" ]'])
def test_a_property_parses_to_larks_tree(prop: str) -> None:
    lark_answer, drive_answer = _both(prop, "prop")
    assert isinstance(lark_answer, tuple) and drive_answer == lark_answer


@pytest.mark.parametrize("text", ["machine m; const int N = ;", "machine m; modeA initial;",
                                  "machine m; const int N = 1 $ 2;", ""])
def test_a_text_out_of_the_ordinary_is_left_to_lark(text: str) -> None:
    lark_answer, drive_answer = _both(text)
    if isinstance(lark_answer, tuple):
        assert drive_answer == lark_answer
    else:  # GiveUp, or the exception of a callback (a keyword run into a name)
        assert not isinstance(drive_answer, tuple)


@pytest.mark.parametrize("text", [
    "const int N = " + "1" * 1200 + ";\nmode A = " + "2" * 1100 + " initial;\n",
    "formula f = ((x + 1)) * (2 - -3) + max(1, (2), 3) + g((x));\nmode M = 0 initial final;\n",
    "const double P = [0.1, 0.2] from data \"a.csv\" column \"c\" with coverage = -0.9;\n",
    "action A in * except {1..3, B} { 0.5: goto B, x := (1, 2); 0.5: skip; }\n",
    "",
    "// only a comment\n",
])
def test_odd_corners_build_the_same_ast(text: str) -> None:
    lark_answer, drive_answer = _both(text)
    assert isinstance(lark_answer, tuple) and drive_answer == lark_answer


@pytest.mark.parametrize("levels", [4996, 4997, 4998, 4999, 5000])
def test_nesting_is_counted_as_lark_counts_it(levels: int) -> None:
    for text in ["formula f = " + "-" * levels + "x;\n",
                 "formula f = " + "(" * levels + "1" + ")" * levels + ";\n",
                 "formula f = " + "!(" * levels + "x" + ")" * levels + ";\n"]:
        lark_answer, drive_answer = _both(text)
        assert (isinstance(lark_answer, tuple)) == (isinstance(drive_answer, tuple))
        if isinstance(lark_answer, tuple):
            assert drive_answer == lark_answer


def test_spans_made_without_init_are_spans() -> None:
    from afsmc.syntax.build import _span

    source = Source("s.afsm", "abc\ndef\n")
    fast, plain = _span(source, 1, 2, 2, 3, 1, 6), Span(source, 1, 2, 2, 3, 1, 6)
    assert fast == plain and hash(fast) == hash(plain)
    assert vars(fast) == vars(plain)
