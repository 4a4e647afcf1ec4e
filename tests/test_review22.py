"""What a new user's first hour found (review 22): command-line edges of compile, diagram,
sweep, check --werror and standard input."""

from __future__ import annotations

from pathlib import Path

from tests.conftest import EXAMPLES, run_cli

PATROL = str(EXAMPLES / "patrol.afsm")

BOOL_PARAM = """machine windy;
param bool WINDY = false;
var x : [0..3] init 0;
mode A initial;
mode B final;
action Go in A when x < 3 { 0.5: x := x + 1; 0.5: skip; }
action Fin in A when x == 3 weight 0.5 { goto B; }
hazard Gust from {A} with probability (WINDY ? 0.1 : 0) { goto B; }
label done = mode == B && x == 3;
property p = P=? [ F "done" ];
"""


def test_an_output_under_a_regular_file_says_that_it_is_not_a_directory(tmp_path: Path) -> None:
    blocker = tmp_path / "afile"
    blocker.write_text("mine\n")
    for sub in ("x.svg", "deeper/x.svg"):
        r = run_cli("diagram", PATROL, "-o", str(blocker / sub))
        assert r.code == 1, r.err
        assert f"E003]: cannot write {blocker / sub}: {blocker} is not a directory" in r.err, r.err
    assert blocker.read_text() == "mine\n"


def test_compile_dot_to_a_picture_name_is_a_usage_error(tmp_path: Path) -> None:
    out = tmp_path / "x.svg"
    r = run_cli("compile", PATROL, "-t", "dot", "-o", str(out))
    assert r.code == 2 and "afsmc diagram" in r.err and "DOT text" in r.err, r.err
    assert not out.exists()
    # a .dot or .gv name is what -t dot writes
    r = run_cli("compile", PATROL, "-t", "dot", "-o", str(tmp_path / "x.gv"))
    assert r.code == 0 and (tmp_path / "x.gv").read_text().count("\ndigraph ") == 1, r.err


def test_sweeping_a_bool_over_numbers_fails_once_before_any_point(tmp_path: Path) -> None:
    path = tmp_path / "windy.afsm"
    path.write_text(BOOL_PARAM)
    r = run_cli("sweep", str(path), "--const", "WINDY=0:1")
    assert r.code == 1
    assert r.err.count("error[E208]") == 1 and "0, 1 are not bools" in r.err, r.err
    assert "sweep it as 'false,true'" in r.err and "points in" not in r.err, r.err
    ok = run_cli("sweep", str(path), "--const", "WINDY=false,true", "--json")
    assert ok.code == 0, ok.err
    # and an int swept over true/false
    path.write_text(BOOL_PARAM.replace("param bool WINDY = false", "param int WINDY = 0")
                    .replace("(WINDY ? 0.1 : 0)", "(WINDY > 0 ? 0.1 : 0)"))
    r = run_cli("sweep", str(path), "--const", "WINDY=false,true")
    assert r.code == 1 and r.err.count("error[E208]") == 1, r.err
    assert "true and false are not numbers" in r.err, r.err


def test_werror_says_why_warnings_exit_1(tmp_path: Path) -> None:
    path = tmp_path / "warned.afsm"
    path.write_text(BOOL_PARAM.replace("var x : [0..3] init 0;",
                                       "var x : [0..3] init 0;\nvar unused : [0..1] init 0;"))
    plain = run_cli("check", str(path))
    assert plain.code == 0 and "W303" in plain.err, plain.err
    strict = run_cli("check", "--werror", str(path))
    assert strict.code == 1
    assert "afsmc: --werror: 1 warning(s) treated as errors" in strict.err, strict.err
    clean = run_cli("check", "--werror", PATROL)
    assert clean.code == 0 and "--werror" not in clean.err, clean.err


def test_standard_input_where_a_command_needs_a_file() -> None:
    r = run_cli("verify", "-")
    assert r.code == 1
    assert "E001]: cannot read -: this command reads a file, not standard input" in r.err, r.err
    assert "'afsmc check -'" in r.err, r.err
