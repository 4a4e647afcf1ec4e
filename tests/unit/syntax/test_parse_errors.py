"""Syntax errors from the parser itself: where the diagnostic points and what it says."""

from __future__ import annotations

import pytest


@pytest.mark.parametrize(("text", "where", "hint"), [
    ("machine x", (1, 10), "the file ends after this declaration"),
    ("machine x\n", (1, 10), "the file ends after this declaration"),
    ("machine m;\nmode A initial  // first\n/* end */\n", (2, 15),
     "the file ends after this declaration"),
    ("machine m;\nmode A initial // first\nmode B;\n", (2, 15),
     "the next line starts with 'mode'"),
])
def test_a_missing_semicolon_is_placed_after_the_last_token(
        text: str, where: tuple[int, int], hint: str) -> None:
    from afsmc.diagnostics import CompileError
    from afsmc.syntax.parser import parse

    with pytest.raises(CompileError) as info:
        parse(text, "in.afsm")
    (d,) = info.value.diagnostics
    assert d.code == "E102" and d.span is not None
    assert (d.span.line, d.span.column) == where
    assert d.hint is not None and hint in d.hint


@pytest.mark.parametrize("decl", ["mode C;", "var y : [0..1];", "label l = true;",
                                  "property p = P=? [ F true ];", "rewards r { true : 1; }"])
def test_an_unclosed_body_is_named_whatever_declaration_follows(decl: str) -> None:
    from afsmc.diagnostics import CompileError
    from afsmc.syntax.parser import parse

    text = f"machine m;\nmode A initial;\naction Go in A {{\n    skip;\n// c\n{decl}\n"
    with pytest.raises(CompileError) as info:
        parse(text, "in.afsm")
    (d,) = info.value.diagnostics
    assert (d.code, d.message) == ("E112", "missing '}' before the next declaration")
    assert d.span is not None and (d.span.line, d.span.column) == (4, 10)
    assert [(r.span.line, r.span.column) for r in d.related] == [(3, 16)]


def test_a_comment_between_a_policy_minus_and_its_number_keeps_the_number() -> None:
    # The number is read from its token, not from the source text with the comment in it.
    from afsmc.syntax import ast
    from afsmc.syntax.parser import parse

    def policy(text: str) -> list[float]:
        module = parse("machine m;\nconst int a = 3 from sim uav.move.duration with "
                       f"confidence = {text};\n", "m.afsm")
        decl = module.decls[0]
        assert isinstance(decl, ast.ConstDecl) and decl.source is not None
        return [value for _, value in decl.source.policy]

    assert policy("- // c\n 0.5") == policy("- /* c */ 0.5") == policy("-0.5") == [-0.5]
