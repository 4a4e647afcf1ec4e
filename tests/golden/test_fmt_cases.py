"""`afsmc fmt` on the golden cases: each tests/golden/cases/fmt_*/input.afsm formats to the
`expected.afsm` beside it."""

from __future__ import annotations

from pathlib import Path

import pytest

from afsmc.syntax.fmt import format_text
from tests.unit.syntax.test_fmt import CASE_DIRS


@pytest.mark.parametrize("case", CASE_DIRS, ids=lambda p: p.name)
def test_golden(case: Path, update_golden: bool) -> None:
    out = format_text((case / "input.afsm").read_text(), "input.afsm")
    expected = case / "expected.afsm"
    if update_golden:
        expected.write_text(out)
    assert out == expected.read_text()
