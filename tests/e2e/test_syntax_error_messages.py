"""How syntax errors read on the command line: in files and in `--formula`, where the caret
stands, and which mistake the message names."""

from __future__ import annotations

from pathlib import Path

import pytest

from tests.conftest import ROOT, run_cli


@pytest.mark.storm
def test_formula_syntax_errors_speak_only_of_the_formula(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.chdir(ROOT)
    r = run_cli("verify", "examples/patrol.afsm", "--formula", 'P=? [ F "done" ] ]')
    assert r.code == 1
    assert "--formula:1:18: error[E101]: unexpected ']'" in r.err
    assert "expected end of the formula" in r.err and "';'" not in r.err
    r = run_cli("verify", "examples/patrol.afsm", "--formula", "P=? [ F cell > 1 cell ]")
    assert r.code == 1 and "E102" not in r.err and "';'" not in r.err


@pytest.mark.storm
def test_a_file_syntax_error_with_formula_is_the_file_s_own(tmp_path: Path) -> None:
    bad = tmp_path / "bad.afsm"
    bad.write_text("machine m;\nmode A initial")
    r = run_cli("verify", str(bad), "--formula", "P=? [ F true ]")
    assert r.code == 1
    assert f"{bad}:2:15: error[E102]" in r.err and "the file ends after" in r.err
    assert "property" not in r.err


def test_two_operands_in_a_row_outside_a_property_are_not_called_nested_temporal(
        tmp_path: Path) -> None:
    # The parser state after `x` is the same in a label and after `F` in a property: E115
    # only where a temporal operator stands before the failing token, never E103.
    from tests.conftest import run_cli

    path = tmp_path / "m.afsm"
    path.write_text('machine m;\nmode A = 0 initial;\nvar x : [0..1];\nlabel a = x "l";\n',
                    encoding="utf-8")
    r = run_cli("check", str(path))
    assert r.code == 1 and "error[E101]: missing operator between 'x' and '\"l\"'" in r.err, r.err
    assert "E115" not in r.err and "E103" not in r.err


@pytest.mark.storm
@pytest.mark.parametrize(("formula", "column"), [
    ("P=? [ F F mode == Dock ]", 11), ("P=? [ F F true ]", 11), ('P=? [ F F !"done" ]', 11),
    ("P=? [ F F (cell == 1) ]", 9), ("P=? [ cell == 1 U F mode == Dock ]", 21),
    ("P=? [ F<=3 G<=2 true ]", 17)])
def test_a_nested_operator_before_a_keyword_or_bracket_is_e115(formula: str,
                                                               column: int) -> None:
    """The inner operator lexes as a name when no label follows it; the error is E115, not
    E116 ("missing ';' at the end of the outcome") nor E233 ("unknown function 'F'")."""
    from tests.conftest import EXAMPLES, run_cli

    r = run_cli("verify", str(EXAMPLES / "patrol.afsm"), "--formula", formula)
    assert r.code == 1 and f"--formula:1:{column}: error[E115]: temporal operators" in r.err, \
        r.err


def test_mode_equals_is_taken_for_a_comparison(tmp_path: Path) -> None:
    """`when mode = A` (PRISM's spelling) is E103, as `x = 1` is, not a bare "unexpected '='"."""
    from tests.conftest import run_cli

    for line in ("action Go in A when mode = A { goto B; }", "label l = mode = B;"):
        path = tmp_path / "m.afsm"
        path.write_text("machine m;\nvar x : [0..2] init 0;\nmode A = 0 initial;\n"
                        f"mode B = 1 final;\n{line}\n", encoding="utf-8")
        r = run_cli("check", str(path))
        assert r.code == 1 and "error[E103]: '=' is not a comparison" in r.err, r.err


@pytest.mark.parametrize("before", ["\t", "\t  ", "漢字 ", "é"])
def test_the_caret_sits_under_the_mistake_after_tabs_and_wide_characters(
        tmp_path: Path, before: str) -> None:
    path = tmp_path / "t.afsm"
    path.write_text("machine t;\nmode A = 0 initial;\n"
                    f"action Go in A when /*{before}*/\tx > 0 {{ goto A; }}\n", encoding="utf-8")
    r = run_cli("check", str(path))
    assert r.code == 1 and "error[E203]" in r.err, r.err
    lines = r.err.splitlines()
    i = next(k for k, line in enumerate(lines) if line.startswith(" 3 | "))
    shown, caret = lines[i][len(" 3 | "):], lines[i + 1][len(" 3 | "):]
    assert "\t" not in shown and caret.strip() == "^"
    # the caret's terminal column is that of the x (wide characters take two columns)
    col = sum(2 if "\u4e00" <= c <= "\u9fff" else 1 for c in shown[:shown.index("x > 0")])
    assert len(caret) - 1 == col
