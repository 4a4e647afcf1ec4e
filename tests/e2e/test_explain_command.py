"""`afsmc explain`: a code's explanation, the list of every code, the docs page; an
unknown code is a usage error (exit 2) that suggests the closest codes."""

from __future__ import annotations

import pytest

from afsmc.diagnostics.codes import REGISTRY
from afsmc.diagnostics.docs import page
from afsmc.diagnostics.explain import as_text
from tests.conftest import run_cli


def test_explain_prints_the_code_s_heading_then_its_explanation() -> None:
    r = run_cli("explain", "E301")
    assert r.code == 0 and r.err == ""
    code = REGISTRY["E301"]
    assert r.out.startswith("E301 (error): weights of enabled actions tie\n\n")
    assert r.out == as_text("E301", "error", code.title, code.explanation) + "\n"


def test_a_code_is_found_in_any_case() -> None:
    assert run_cli("explain", "w303").out == run_cli("explain", "W303").out


def test_explain_alone_lists_every_code_with_its_severity_and_title() -> None:
    r = run_cli("explain")
    assert r.code == 0
    for code in REGISTRY.values():
        assert f"  {code}  {code.severity.value:<7}  {code.title}\n" in r.out + "\n"
    assert r.out.startswith("E0xx: ")
    assert r.out.index("E301  error") < r.out.index("W301  warning") < r.out.index("N412  note")


@pytest.mark.parametrize(("given", "suggested"), [
    ("E3O1", " (did you mean E301?)"),
    ("301", " (did you mean E301 or W301?)"),
    ("E3011", " (did you mean E301 or E311?)"),
    ("frobnicate", ""),
])
def test_an_unknown_code_exits_2_with_a_suggestion(given: str, suggested: str) -> None:
    r = run_cli("explain", given)
    assert r.code == 2 and r.out == ""
    assert r.err == (f"afsmc: error: no diagnostic code {given!r}{suggested}; "
                     "'afsmc explain' lists every code\n")


def test_markdown_prints_the_docs_page() -> None:
    r = run_cli("explain", "--markdown")
    assert r.code == 0 and r.out == page()
    assert run_cli("explain", "E301", "--markdown").code == 2
