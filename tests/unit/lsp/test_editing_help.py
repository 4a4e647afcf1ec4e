"""The language server's editing help without a client: quick fixes worked out from hints,
semantic token kinds, and the call that signature help finds."""

from __future__ import annotations

import pytest

from afsmc.diagnostics import CompileError
from afsmc.lsp import index as I
from afsmc.lsp import tokens
from afsmc.lsp.actions import fixes
from afsmc.lsp.analysis import analyse_fast, analyse_full
from afsmc.lsp.features import call_at
from afsmc.syntax.parser import parse

BASE = "machine m;\nvar x : [0..2] init 0;\nmode A initial final;\n"


def _apply(text: str, edits: tuple[tuple[int, int, str], ...]) -> str:
    for a, b, s in sorted(edits, reverse=True):
        text = text[:a] + s + text[b:]
    return text


def _fixed(text: str, code: str) -> str:
    """The text after the first quick fix of the first `code` diagnostic."""
    fast = analyse_fast(text, "t.afsm")
    idx = I.build(fast.module, text) if fast.module is not None else None
    (d,) = [d for d in analyse_full(text, "t.afsm") if d.code == code][:1]
    (fix, *_) = fixes(d, text, idx)
    return _apply(text, fix.edits)


def test_missing_semicolon_is_inserted() -> None:
    text = "machine m;\nconst int N = 2\nvar x : [0..N] init 0;\nmode A initial final;\n"
    out = _fixed(text, "E102")
    assert "const int N = 2;" in out
    parse(out, "t.afsm")  # parses now


def test_did_you_mean_replaces_the_name() -> None:
    text = BASE + "label high = xx > 1;\n"
    out = _fixed(text, "E203")
    assert "label high = x > 1;" in out


def test_reserved_name_is_renamed_everywhere() -> None:
    text = "machine m;\nvar __y : [0..2] init 0;\nmode A initial final;\nlabel l = __y > 1;\n"
    out = _fixed(text, "E202")
    assert "__y" not in out and out.count("y") == 2
    assert not [d for d in analyse_full(out, "t.afsm") if d.code == "E202"]


def test_probability_sum_gets_the_complement() -> None:
    text = BASE.replace("mode A initial final;", "mode A initial;\nmode B final;") + \
        "action a in A { 0.3: x := 1, goto B; 0.6: goto B; }\n"
    out = _fixed(text, "E305")
    assert "1 - 0.3: goto B;" in out
    assert not [d for d in analyse_full(out, "t.afsm") if d.code == "E305"]


def test_no_fix_without_an_edit_in_the_hint() -> None:
    text = BASE + "const int N = 1 / 0;\n"
    diags = [d for d in analyse_full(text, "t.afsm") if d.hint]
    assert diags
    fast = analyse_fast(text, "t.afsm")
    idx = I.build(fast.module, text) if fast.module is not None else None
    assert all(fixes(d, text, idx) == [] for d in diags if d.code == "E245")


def test_token_kinds_tell_constants_apart() -> None:
    text = ("machine m;\nparam int P = 1;\nconst int C = 2;\nconst int T = [1, 3];\n"
            "var x : [0..C] init 0;\nmode A initial final;\nlabel l = x > P + T;\n")
    idx = I.build(parse(text, "t.afsm"), text)
    kinds = {text[a:b]: k for a, b, k, _ in tokens.spans(idx)}
    assert kinds["P"] == "parameter" and kinds["C"] == "constant" and kinds["T"] == "interval"
    assert kinds["m"] == "namespace" and kinds["A"] == "enumMember" and kinds["l"] == "label"


@pytest.mark.parametrize("text, expected", [
    ("max(a, ", ("max", 1)),
    ("max(a, floor(", ("floor", 0)),
    ("max(a, floor(b), ", ("max", 2)),
    ("weight w(", ("w", 0)),
    ("(a, ", None),
    ("foo(a, ", None),
    ("max(a); x := ", None),
])
def test_call_at(text: str, expected: tuple[str, int] | None) -> None:
    assert call_at(text, len(text)) == expected


def test_fix_of_a_text_that_does_not_parse_needs_no_index() -> None:
    text = "machine m;\nconst int N = 2\n"
    with pytest.raises(CompileError) as exc:
        parse(text, "t.afsm")
    (d,) = exc.value.diagnostics
    assert fixes(d, text, None)
