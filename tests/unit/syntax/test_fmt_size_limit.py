"""A layout longer than afsmc reads (MAX_SOURCE_CHARS) is refused with E004, the file left
as it was: formatting adds a few per cent to a dense file (bodies on lines of their own),
and a 2 MB file's layout went past the limit, where re-parsing it reported the
formatter's own fault (E190). The limit is lowered here so that the texts stay small."""

from __future__ import annotations

import pytest

from afsmc.diagnostics import CompileError
from afsmc.syntax import fmt

DENSE = "machine m;\nvar x:[0..3] init 0;\nmode A=0 initial final;\naction Go in A{x:=1;}\n"


def test_a_layout_past_the_limit_is_e004_not_e190(monkeypatch: pytest.MonkeyPatch) -> None:
    out = fmt.format_text(DENSE, "m.afsm")
    assert len(out) > len(DENSE)  # the layout is longer than the dense text
    monkeypatch.setattr(fmt, "MAX_SOURCE_CHARS", len(DENSE))
    with pytest.raises(CompileError) as exc:
        fmt.format_text(DENSE, "m.afsm")
    (d,) = exc.value.diagnostics
    assert d.code == "E004"
    assert f"would have {len(out):,} characters" in d.message and "left unchanged" in d.message
    monkeypatch.setattr(fmt, "MAX_SOURCE_CHARS", len(out))
    assert fmt.format_text(DENSE, "m.afsm") == out  # up to the limit it is formatted
