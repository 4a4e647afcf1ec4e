"""afsmc.syntax.drive gives lark's own tree, positions included, or gives up."""

from __future__ import annotations

import random
from pathlib import Path
from typing import Any

import pytest
from lark import Token, Tree

from afsmc.syntax import drive
from afsmc.syntax.grammar import _LEXING, lalr
from tests.fuzz import generate

ROOT = Path(__file__).resolve().parents[3]
FILES = sorted([*ROOT.glob("examples/*.afsm"), *ROOT.glob("tests/golden/cases/*/input.afsm")])
META = ("line", "column", "start_pos", "end_line", "end_column", "end_pos", "empty",
        "container_line", "container_column", "container_start_pos", "container_end_line",
        "container_end_column", "container_end_pos")


def _key(x: Any) -> Any:
    """Everything of a tree a later stage could read: rule names, tokens with their
    places, each node's positions and nesting depth."""
    if isinstance(x, Tree):
        meta = x._meta
        m = None if meta is None else tuple(getattr(meta, a, None) for a in META)
        return ("tree", x.data, m, getattr(x, "afsmc_depth", None),
                tuple(_key(c) for c in x.children))
    if isinstance(x, Token):
        return ("token", x.type, str(x), x.start_pos, x.line, x.column, x.end_line,
                x.end_column, x.end_pos)
    return ("other", repr(x))


def _both(text: str, start: str = "start") -> tuple[Any, Any]:
    """(lark's answer, drive's answer): a tree's key, or the exception's type."""
    reset = _LEXING.set(text)
    try:
        try:
            lark_answer = _key(lalr().parse(text, start=start))
        except Exception as exc:
            lark_answer = type(exc).__name__
        try:
            drive_answer = _key(drive.parse(lalr(), text, start))
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
