"""Negative cases, one per directory under tests/cases/err_* and warn_*: `afsmc check`
gives the pinned diagnostics (code, file:line:col, caret, hint) and exit code. A case with a
`command.txt` (one argument per line, `{input}` for the input's path) runs that command
instead of `check`."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

from tests.conftest import CASES, ROOT, run_cli

CASE_DIRS = sorted(p for p in CASES.iterdir() if p.name.startswith(("err_", "warn_")))


@pytest.mark.parametrize("case", CASE_DIRS, ids=[p.name for p in CASE_DIRS])
def test_case(case: Path, update_golden: bool, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.chdir(ROOT)
    rel = (case / "input.afsm").relative_to(ROOT).as_posix()
    command = case / "command.txt"
    argv = [a.replace("{input}", rel) for a in command.read_text().splitlines() if a] \
        if command.exists() else ["check", rel]
    result = run_cli(*argv)
    is_error = case.name.startswith("err_")
    assert result.code == (1 if is_error else 0), result.err
    kind = "error" if is_error else "warning"
    # every diagnostic names the file (or --formula), line and column, its code, and
    # quotes the line
    where = f"(?:{re.escape(rel)}|--formula)"
    assert re.search(rf"^{where}:\d+:\d+: {kind}\[[EW]\d{{3}}\]: ", result.err, re.M)
    assert re.search(r"^ +\d+ \| .+\n +\| +\^+", result.err, re.M)
    assert "Traceback" not in result.err
    golden = case / "expected.txt"
    if update_golden or not golden.exists():
        golden.write_text(result.err)
    assert result.err == golden.read_text()


def test_the_issue_s_five_errors_each_exit_1_with_line_and_column(monkeypatch: pytest.MonkeyPatch) -> None:
    """A weight tie, a probability sum other than 1, an out-of-range update, an undefined
    name and a syntax error: exit 1 and a diagnostic at the right line:col."""
    monkeypatch.chdir(ROOT)
    expect = {
        "err_weight_tie": ("E301", 6, 43),
        "err_prob_sum": ("E305", 6, 5),
        "err_out_of_range": ("E303", 5, 31),
        "err_undefined": ("E203", 4, 28),
        "err_syntax_semicolon": ("E102", 2, 16),
    }
    for name, (code, line, col) in expect.items():
        rel = f"tests/cases/{name}/input.afsm"
        result = run_cli("check", rel)
        assert result.code == 1
        assert f"{rel}:{line}:{col}: error[{code}]" in result.err, result.err


def test_all_errors_of_a_file_are_reported_together(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.chdir(ROOT)
    result = run_cli("check", "tests/cases/err_undefined/input.afsm")
    codes = re.findall(r"error\[(E\d+)\]", result.err)
    assert len(codes) >= 4  # levl, Finished, Activ, "nope"


def test_missing_file_is_a_diagnostic_not_a_traceback(tmp_path: Path) -> None:
    result = run_cli("check", str(tmp_path / "nope.afsm"))
    assert result.code == 1
    assert "error[E001]: cannot read" in result.err


def test_usage_errors_exit_2() -> None:
    assert run_cli("check").code == 2
    assert run_cli("frobnicate").code == 2
    assert run_cli("check", "examples/patrol.afsm", "--const", "NOEQUALS").code == 2


def test_unknown_and_fixed_constants_on_the_command_line(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.chdir(ROOT)
    r = run_cli("check", "examples/patrol.afsm", "--const", "CELS=3")
    assert r.code == 1 and "error[E209]" in r.err and "did you mean 'CELLS'" in r.err
    r = run_cli("check", "examples/patrol.afsm", "--const", "LOW=3")
    assert r.code == 1 and "is a fixed constant" in r.err
    r = run_cli("check", "examples/patrol.afsm", "--const", "CELLS=x")
    assert r.code == 1 and "not an int" in r.err


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


def test_formula_syntax_errors_speak_only_of_the_formula(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.chdir(ROOT)
    r = run_cli("verify", "examples/patrol.afsm", "--formula", 'P=? [ F "done" ] ]')
    assert r.code == 1
    assert "--formula:1:18: error[E101]: unexpected ']'" in r.err
    assert "expected end of the formula" in r.err and "';'" not in r.err
    r = run_cli("verify", "examples/patrol.afsm", "--formula", "P=? [ F cell > 1 cell ]")
    assert r.code == 1 and "E102" not in r.err and "';'" not in r.err


def test_a_file_syntax_error_with_formula_is_the_file_s_own(tmp_path: Path) -> None:
    bad = tmp_path / "bad.afsm"
    bad.write_text("machine m;\nmode A initial")
    r = run_cli("verify", str(bad), "--formula", "P=? [ F true ]")
    assert r.code == 1
    assert f"{bad}:2:15: error[E102]" in r.err and "the file ends after" in r.err
    assert "property" not in r.err
