"""`afsm` formatting (afsmc.syntax.fmt): canonical, idempotent, keeps every comment, never
changes meaning.

Meaning is checked against the compiler: the PRISM text compiled from the formatted file
equals the one compiled from the original, once the `// file:line` comments (which cite
source lines, and lines move) are stripped.
"""

from __future__ import annotations

import re
from pathlib import Path

import pytest

from afsmc.syntax.fmt import format_text
from tests.conftest import CASES, EXAMPLES, run_cli
from tests.specs import BOM, SMALL

CASE_DIRS = sorted(p for p in CASES.glob("fmt_*") if (p / "input.afsm").exists())


SPECS = sorted(EXAMPLES.glob("*.afsm")) + [p / "input.afsm" for p in CASE_DIRS]


def comments(text: str) -> list[str]:
    """The comments of a text, found with a regular expression (not the formatter's lexer)."""
    found = re.findall(r'"(?:\\.|[^"\\])*"|(//[^\n]*|/\*[\s\S]*?\*/)', text)
    return [c.rstrip() for c in found if c]


def prism(path: Path) -> str:
    res = run_cli("compile", str(path), "-o", "-")
    assert res.code == 0, res.err
    return "\n".join(line.split("//")[0].rstrip() for line in res.out.splitlines())


@pytest.mark.parametrize("spec", SPECS, ids=lambda p: f"{p.parent.name}/{p.name}")
def test_idempotent_and_keeps_comments(spec: Path) -> None:
    text = spec.read_text()
    once = format_text(text)
    assert format_text(once) == once
    assert comments(once) == comments(text)
    assert all(len(line) <= 100 or "//" in line or "when" in line or "=" in line
               for line in once.splitlines())


@pytest.mark.parametrize("spec", SPECS, ids=lambda p: f"{p.parent.name}/{p.name}")
def test_meaning_preserved(spec: Path, tmp_path: Path) -> None:
    formatted = tmp_path / spec.name
    formatted.write_text(format_text(spec.read_text()))
    assert prism(formatted) == prism(spec)


def test_layout_does_not_depend_on_spacing() -> None:
    text = (EXAMPLES / "patrol.afsm").read_text()

    def spread(line: str) -> str:  # more spaces in the code part of a line
        code, sep, comment = line.partition("//")
        code = re.sub(r"([;,(){}\[\]])", r" \1 ", code)
        return code.replace(" ", "   ") + sep + comment

    spread_text = "\n".join(spread(line) for line in text.splitlines())
    assert spread_text != text
    assert format_text(spread_text) == format_text(text)


@pytest.mark.parametrize(("written", "printed"), [
    ("-(-1.5)", "-(-1.5)"),          # was `--1.5`
    ("-(-(1.5))", "-(-(1.5))"),      # was `--1.5`
    ("-(2)", "-(2)"),                # was `-2`
    ("- -3", "- -3"),                # was `--3`
    ("--3", "- -3"),
    ("-  - -1", "- - -1"),
    ("2--(1)", "2 - -(1)"),
    ("-(-a)", "-(-a)"),
    ("- -a", "- -a"),                # was `--a`
    ("((a))", "((a))"),              # was `(a)`
    ("(((a)+1))*2", "(((a) + 1)) * 2"),
    ("max((a),(((2))))", "max((a), (((2))))"),
    ("(-(-(a)))", "(-(-(a)))"),
])
def test_parentheses_are_kept_and_minus_signs_stay_apart(written: str, printed: str) -> None:
    """docs/editors.md: parentheses the author wrote are kept, none added or dropped; two
    minus signs are never printed as `--`. The safety net checks the AST is the same."""
    text = f"machine m;\nconst int a = 1;\nconst double D = {written};\nmode A = 0 initial final;\n"
    out = format_text(text)
    assert f"const double D = {printed};\n" in out
    assert format_text(out) == out


def test_parentheses_of_step_bounds_are_kept() -> None:
    text = ("machine m;\nconst int a = 2;\nmode A = 0 initial final;\n"
            "property p = P=? [ F<=((3)) mode == A ];\nproperty q = P=? [ F<=(a) mode == A ];\n"
            "property r = P=? [ F<=a mode == A ];\nproperty s = P=? [ F<=(a+1) mode == A ];\n")
    out = format_text(text)
    for bound in ("F<=((3))", "F<=(a)", "F<=a", "F<=(a + 1)"):
        assert f"[ {bound} mode == A ]" in out


def test_rmin_written_together_still_parses() -> None:
    """fmt writes `Rmin=?` as PRISM does; the check for keywords run into names (E122) first
    refused it (found by the grammar fuzzer)."""
    text = " machine  a  ;  property  a  =  R  min  =?  [  C  ]  ; "
    out = format_text(text)
    assert "property a = Rmin=? [ C ];" in out and format_text(out) == out


def test_fmt_keeps_a_byte_order_mark() -> None:
    out = format_text(BOM + "machine  small ;\n" + SMALL.split("\n", 1)[1])
    assert out.startswith(BOM + "machine small;\n") and out.count(BOM) == 1
    assert format_text(out) == out
