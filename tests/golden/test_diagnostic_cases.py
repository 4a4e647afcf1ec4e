"""Negative cases, one per directory under tests/golden/cases/err_* and warn_*: `afsmc check`
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
        rel = f"tests/golden/cases/{name}/input.afsm"
        result = run_cli("check", rel)
        assert result.code == 1
        assert f"{rel}:{line}:{col}: error[{code}]" in result.err, result.err


def test_all_errors_of_a_file_are_reported_together(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.chdir(ROOT)
    result = run_cli("check", "tests/golden/cases/err_undefined/input.afsm")
    codes = re.findall(r"error\[(E\d+)\]", result.err)
    assert len(codes) >= 4  # levl, Finished, Activ, "nope"
