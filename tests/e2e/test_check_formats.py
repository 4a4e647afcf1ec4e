"""`afsmc check --format text|json|sarif`: text on standard error by default; JSON (also
`--json`, byte for byte) or SARIF 2.1.0 on standard output; the exit code is the same."""

from __future__ import annotations

import json
from pathlib import Path

import pytest
from sarif_kit import validation_errors

from afsmc.diagnostics import Diagnostic, Source
from tests.conftest import ROOT, run_cli

TIE = "tests/golden/cases/err_weight_tie/input.afsm"
FILES = [TIE, "tests/golden/cases/err_undefined/input.afsm", "tests/golden/cases/warn_deadlock/input.afsm"]


@pytest.fixture(autouse=True)
def _at_root(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.chdir(ROOT)


def test_json_is_the_same_as_the_json_flag_byte_for_byte() -> None:
    flag, option = run_cli("check", *FILES, "--json"), run_cli("check", *FILES, "--format", "json")
    assert (flag.code, flag.out, flag.err) == (option.code, option.out, option.err)
    assert flag.code == 1 and flag.err == ""
    assert [d["code"] for d in json.loads(flag.out)][:1] == ["E301"]


def test_the_json_output_reads_back_into_the_diagnostics() -> None:
    out = run_cli("check", TIE, "--format", "json").out
    sources = {TIE: Source(TIE, Path(TIE).read_text(encoding="utf-8"))}
    back = [Diagnostic.from_json(obj, sources) for obj in json.loads(out)]
    assert [d.to_json() for d in back] == json.loads(out)
    assert back[0].span is not None and back[0].span.source.line(back[0].span.line)


def test_text_is_the_default() -> None:
    default, text = run_cli("check", *FILES), run_cli("check", *FILES, "--format", "text")
    assert (default.code, default.out, default.err) == (text.code, text.out, text.err)
    assert default.out == "" and "error[E301]" in default.err


def test_sarif_goes_to_standard_output_and_validates() -> None:
    r = run_cli("check", *FILES, "--format", "sarif")
    assert r.code == 1 and r.err == ""
    log = json.loads(r.out)
    assert validation_errors(log) == []
    results = log["runs"][0]["results"]
    assert [res["ruleId"] for res in results] == [
        d["code"] for d in json.loads(run_cli("check", *FILES, "--json").out)]
    uris = {res["locations"][0]["physicalLocation"]["artifactLocation"]["uri"]
            for res in results}
    assert uris == set(FILES)


def test_sarif_of_a_clean_file_has_no_results_and_exits_0() -> None:
    r = run_cli("check", "examples/uav.afsm", "--format", "sarif")
    log = json.loads(r.out)
    assert r.code == 0 and log["runs"][0]["results"] == [] and validation_errors(log) == []


def test_werror_exits_1_in_every_format() -> None:
    warn = "tests/golden/cases/warn_deadlock/input.afsm"
    for fmt in ("text", "json", "sarif"):
        r = run_cli("check", warn, "--format", fmt, "--werror")
        assert r.code == 1, fmt
        assert ("--werror: " in r.err) == (fmt == "text"), fmt


def test_json_flag_with_another_format_is_a_usage_error() -> None:
    r = run_cli("check", TIE, "--json", "--format", "sarif")
    assert r.code == 2
    assert r.err == "afsmc: error: --json is --format json; it cannot go with --format sarif\n"
    assert run_cli("check", TIE, "--json", "--format", "json").code == 1
    assert run_cli("check", TIE, "--format", "xml").code == 2
