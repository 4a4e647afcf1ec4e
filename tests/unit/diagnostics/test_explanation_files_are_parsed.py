"""The explanation files' format: `# CODE: title`, prose, `## Wrong` and `## Right`, each
with fenced blocks; and the text `afsmc explain` makes of one. Read from sample files
in fixtures/."""

from __future__ import annotations

from pathlib import Path

import pytest

from afsmc.diagnostics import explain
from afsmc.diagnostics.codes import REGISTRY
from afsmc.diagnostics.explain import as_text, parse

FIXTURES = Path(__file__).parent / "fixtures"


def test_a_file_gives_the_title_the_prose_and_both_examples() -> None:
    ex = parse((FIXTURES / "E301.md").read_text(encoding="utf-8"))
    assert (ex.code, ex.title) == ("E301", "weights of enabled actions tie")
    assert ex.prose.startswith("The enabled action with the largest weight fires.")
    assert ex.prose.endswith("make their guards exclusive.")
    assert ex.wrong.checkable and ex.right.checkable
    (wrong,) = ex.wrong.of("afsm")
    assert wrong.startswith("machine tie;\n") and wrong.endswith("F mode == B ];\n")
    assert "weight 0.6" in ex.right.of("afsm")[0]


def test_a_section_may_hold_a_shell_block_and_words_between_blocks() -> None:
    ex = parse((FIXTURES / "E101.md").read_text(encoding="utf-8"))
    assert [b.lang for b in ex.right.blocks] == ["afsm", "sh"]
    assert not ex.right.checkable and ex.wrong.checkable
    assert ex.right.of("sh") == ["afsmc check m.afsm\n"]
    assert "The same check from the command line:" in ex.right.markdown


@pytest.mark.parametrize(("text", "why"), [
    ("E301: tie\n\nProse.\n\n## Wrong\n\n```afsm\nx\n```\n\n## Right\n\n```afsm\ny\n```\n",
     "the first line is not '# CODE: title'"),
    ("# E301: tie\n\nProse.\n\n## Right\n\n```afsm\ny\n```\n\n## Wrong\n\n```afsm\nx\n```\n",
     "'## Wrong' then '## Right'"),
    ("# E301: tie\n\nProse.\n\n## Wrong\n\n```afsm\nx\n```\n", "'## Wrong' then '## Right'"),
    ("# E301: tie\n\nProse.\n\n## Wrong\n\nno block\n\n## Right\n\n```afsm\ny\n```\n",
     "'## Wrong' has no fenced code block"),
    ("# E301: tie\n\n## Wrong\n\n```afsm\nx\n```\n\n## Right\n\n```afsm\ny\n```\n",
     "no prose"),
])
def test_a_file_out_of_the_format_is_refused_saying_why(text: str, why: str) -> None:
    with pytest.raises(ValueError, match=why.replace("(", r"\(")):
        parse(text)


def test_windows_line_ends_read_the_same() -> None:
    text = (FIXTURES / "W301.md").read_text(encoding="utf-8")
    assert parse(text.replace("\n", "\r\n")) == parse(text)


def test_the_text_of_explain_has_the_heading_the_prose_and_indented_examples() -> None:
    ex = parse((FIXTURES / "E101.md").read_text(encoding="utf-8"))
    text = as_text("E101", "error", "unexpected token", ex)
    assert text.splitlines()[:3] == ["E101 (error): unexpected token", "",
                                     "The parser met a token that no declaration can "
                                     "continue with."]
    assert "\nWrong:\n\n    machine m;\n\n    mode A = 0 initial final;\n    )\n\nRight:\n" in text
    assert text.endswith("The same check from the command line:\n\n    afsmc check m.afsm")


def test_the_registry_reads_the_explanations_from_their_directory(
        monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(explain, "EXPLANATIONS", FIXTURES)
    explain.load.cache_clear()
    try:
        ex = REGISTRY["W301"].explanation
        assert ex is not None and ex.title == "a non-final mode has no actions"
        assert REGISTRY["E002"].explanation is None
    finally:
        explain.load.cache_clear()
