"""Every code of the registry has an explanation file in the agreed format, whose title is
the registry's; a Wrong example that is an .afsm file makes `afsmc check` report the code
and the Right one does not; and some test triggers every code."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

from afsmc.compiler import load
from afsmc.diagnostics import CompileError, Diagnostic, Severity
from afsmc.diagnostics.codes import REGISTRY
from afsmc.diagnostics.explain import EXPLANATIONS, Explanation, parse
from tests.conftest import ROOT

DIRECTORY = Path(str(EXPLANATIONS))
FILES = sorted(DIRECTORY.glob("*.md")) if DIRECTORY.is_dir() else []


def _parsed() -> dict[str, Explanation]:
    """The files that parse (the others fail their own test below)."""
    out = {}
    for path in FILES:
        try:
            out[path.stem] = parse(path.read_text(encoding="utf-8"))
        except ValueError:
            continue
    return out


def test_every_code_has_an_explanation_file() -> None:
    missing = [c for c in REGISTRY if not (DIRECTORY / f"{c}.md").is_file()]
    assert not missing, (f"{len(missing)} codes have no afsmc/diagnostics/explanations/"
                         f"<CODE>.md: {', '.join(missing)}")


def test_every_explanation_file_is_of_a_code() -> None:
    strays = [p.name for p in FILES if p.stem not in REGISTRY]
    assert not strays, f"explanations of codes the registry lacks: {strays}"


@pytest.mark.parametrize("path", FILES, ids=[p.stem for p in FILES])
def test_an_explanation_has_the_registry_s_title_and_both_examples(path: Path) -> None:
    ex = parse(path.read_text(encoding="utf-8"))  # raises on a missing section or block
    assert ex.code == path.stem
    if ex.code in REGISTRY:
        assert ex.title == REGISTRY[ex.code].title, (
            f"{path.name}: the title differs from afsmc/diagnostics/codes.py")
    for section in (ex.wrong, ex.right):
        assert {b.lang for b in section.blocks} <= {"afsm", "sh"}, section.blocks


def _check(text: str) -> list[Diagnostic]:
    try:
        return load("example.afsm", {}, text=text).diagnostics
    except CompileError as exc:
        return exc.diagnostics


CHECKABLE = [(code, ex) for code, ex in _parsed().items()
             if ex.wrong.checkable and ex.right.checkable]
# W309's Wrong example waits for the SMT solver's time limit (about 20 s).
SLOW_EXAMPLES = {"W309"}


@pytest.mark.parametrize(("code", "ex"), [
    pytest.param(code, ex, id=code, marks=[pytest.mark.slow] if code in SLOW_EXAMPLES else [])
    for code, ex in CHECKABLE])
def test_check_reports_the_code_on_wrong_and_not_on_right(code: str, ex: Explanation) -> None:
    wrong = _check(ex.wrong.of("afsm")[0])
    assert code in {d.code for d in wrong}, [(d.code, d.message) for d in wrong]
    right = _check(ex.right.of("afsm")[0])
    assert code not in {d.code for d in right}, [(d.code, d.message) for d in right]
    errors = [(d.code, d.message) for d in right if d.severity is Severity.ERROR]
    assert not errors, errors


# Files that name codes without triggering them: the registry's own tests.
NOT_TRIGGERS = {Path(__file__).parent, ROOT / "tests" / "e2e" / "test_explain_command.py"}


def triggered() -> set[str]:
    """Codes that appear in a test (a .py file, or a golden file of tests/golden/cases), or whose
    explanation `test_check_reports_the_code_on_wrong_and_not_on_right` runs."""
    found = {code for code, _ in CHECKABLE}
    tests = ROOT / "tests"
    paths = [p for p in tests.rglob("*.py")
             if not any(p == n or n in p.parents for n in NOT_TRIGGERS)]
    paths += sorted((tests / "golden" / "cases").glob("*/expected.txt"))
    for path in paths:
        found |= set(re.findall(r"\b[EWN]\d{3}\b", path.read_text(encoding="utf-8")))
    return found


def test_every_code_is_triggered_by_some_test() -> None:
    found = triggered()
    untested = [c for c in REGISTRY if c not in found]
    assert not untested, f"{len(untested)} codes no test triggers: {', '.join(untested)}"
