"""A requirement's threshold is part of the language server's index: the constants it names
are uses (rename and references find them), in P and in R requirements alike."""

from __future__ import annotations

from tests.conftest import EXAMPLES


def test_constants_in_thresholds_are_indexed() -> None:
    from afsmc.lsp import index as I
    from afsmc.syntax.parser import parse

    text = (EXAMPLES / "patrol.afsm").read_text() + (
        'property need = P>=(LOW / 10) [ F "done" ];\n'
        'property few  = R{"steps"}<=(LOW * 6) [ F "done" || "halted" ];\n')
    idx = I.build(parse(text, "patrol.afsm"), text)
    uses = [text[o.start:o.end] for o in idx.occurrences if o.name == "LOW"]
    at = [o.start for o in idx.occurrences if o.name == "LOW"]
    assert uses == ["LOW"] * len(uses)
    assert text.index("(LOW / 10)") + 1 in at and text.index("(LOW * 6)") + 1 in at
