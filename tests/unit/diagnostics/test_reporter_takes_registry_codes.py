"""Reporter takes the registry's codes (a Code, or its string for now) at their declared
severity, and refuses any other: a wrong code is a bug in afsmc, found by the first test
that reports it."""

from __future__ import annotations

import pytest

from afsmc.diagnostics import Reporter, Severity, Source, Span, codes


def test_a_code_from_the_registry_is_reported_as_its_plain_string() -> None:
    rep = Reporter()
    span = Span.at_offset(Source("m.afsm", "machine m;\n"), 0, 7)
    rep.error(codes.E301, "tie", span)
    rep.warning("W303", "unused", span)
    rep.note(codes.N412, "kept", None)
    assert [(d.code, d.severity) for d in rep.diagnostics] == [
        ("E301", Severity.ERROR), ("W303", Severity.WARNING), ("N412", Severity.NOTE)]
    assert all(type(d.code) is str for d in rep.diagnostics)  # JSON and repr as before


def test_a_code_the_registry_lacks_is_refused() -> None:
    with pytest.raises(ValueError, match="E300 is not declared"):
        Reporter().error("E300", "nothing", None)


@pytest.mark.parametrize(("method", "code", "why"), [
    ("warning", codes.E301, "E301 is declared as an error, reported as a warning"),
    ("error", "W303", "W303 is declared as a warning, reported as an error"),
    ("note", codes.E301, "E301 is declared as an error, reported as a note"),
])
def test_a_code_at_another_severity_is_refused(method: str, code: str, why: str) -> None:
    with pytest.raises(ValueError, match=why):
        getattr(Reporter(), method)(code, "message", None)
