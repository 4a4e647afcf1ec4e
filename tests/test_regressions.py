"""Regressions found by review: each spec once gave a wrong answer or a crash."""

from __future__ import annotations

from pathlib import Path

import pytest

from afsmc.compiler import load
from afsmc.lower.lowering import lower
from afsmc.lower.reduce import Reductions, reduce
from tests.storm_util import storm_prism


def _model(tmp: Path, text: str) -> object:
    path = tmp / "spec.afsm"
    path.write_text(text)
    return load(str(path)).model


def test_saturation_keeps_an_authors_own_cap(tmp_path: Path) -> None:
    """`t := min(t + 1, 3)` is not a plain counter: t never passes 3."""
    model = _model(tmp_path, """
machine sat1;
var t : [0..10] init 0;
mode A = 0 initial;
mode B = 1 final;
action Tick in A when t < 8 { t := min(t + 1, 3); }
action Stop in A when t >= 8 { goto B; }
label late = t >= 5;
property p = P=? [ F<=20 "late" ];
""")
    _, plain = storm_prism(lower(model), tmp_path, "plain")  # type: ignore[arg-type]
    _, reduced = storm_prism(reduce(lower(model), Reductions()), tmp_path, "red")  # type: ignore[arg-type]
    assert plain["p"] == 0.0 and reduced["p"] == 0.0


def test_nested_implication_means_the_same_to_storm(tmp_path: Path) -> None:
    """afsm reads `a => b => c` as `a => (b => c)`; Storm's PRISM parser groups to the
    left, so the output must carry parentheses. With a, b, c false it is true."""
    model = _model(tmp_path, """
machine imp;
var a : bool init false;
var b : bool init false;
var c : bool init false;
mode A = 0 initial;
mode B = 1 final;
action Go in A { goto B; }
label L = a => b => c;
property p = P=? [ F<=0 "L" ];
""")
    _, values = storm_prism(lower(model), tmp_path)  # type: ignore[arg-type]
    assert values["p"] == 1.0


def test_a_negative_power_in_an_excluded_state_does_not_crash_the_checks(tmp_path: Path) -> None:
    model = _model(tmp_path, """
machine pw;
var x : [0..3] init 2;
var y : [0..8] init 0;
mode M = 0 initial;
mode D = 1 final;
action Go in M when x > 0 { goto D, y := pow(2, x - 1); }
action St in M when x == 0 { x := 1; }
label L = y == 2;
property p = P=? [ F "L" ];
""")
    _, values = storm_prism(lower(model), tmp_path)  # type: ignore[arg-type]
    assert values["p"] == pytest.approx(1.0)


def test_hazards_woven_into_a_preemptive_hazard_make_their_target_reachable(tmp_path: Path) -> None:
    """Only the preemptive Stop fires in A, but Crash is woven into it: D is reachable."""
    path = tmp_path / "mg.afsm"
    path.write_text("""
machine mg;
var x : [0..3] init 0;
mode A = 0 initial;
mode C = 2 final;
mode D = 3 final;
action Wait in A when x > 0 && x < 1 { x := 0; }
hazard Stop from {A} when x >= 0 { goto C; }
hazard Crash from {A} with probability 0.5 { goto D; }
label L = mode == D;
property p = P=? [ F "L" ];
""")
    checked = load(str(path))
    assert not any(d.code == "W601" for d in checked.diagnostics)
    _, values = storm_prism(lower(checked.model), tmp_path)
    assert values["p"] == pytest.approx(0.5)


def test_weight_of_an_action_disabled_by_a_preemptive_hazard_is_zero(tmp_path: Path) -> None:
    """Definition 2: w(s, a) > 0 only where a is enabled, and a preemptive hazard disables
    the ordinary actions of its modes. Halt's weight 1 - w(Run) must see w(Run) = 0."""
    model = _model(tmp_path, """
machine pre;
var x : [0..2] init 0;
mode A = 0 initial;
mode Low = 1 final;
mode High = 2 final;
action Run in A when x < 2 weight 0.9 { x := x + 1; }
hazard Halt from {A} when x >= 1 weight 1 - w(Run) { goto Low; }
hazard Stop from {A} when x >= 1 weight 0.3 { goto High; }
label low = mode == Low;
property p = P=? [ F "low" ];
""")
    # At x = 1 the hazards preempt Run, so w(Run) = 0 and Halt (1) beats Stop (0.3).
    _, values = storm_prism(lower(model), tmp_path)  # type: ignore[arg-type]
    assert values["p"] == 1.0


def test_unnumbered_modes_take_the_lowest_free_number() -> None:
    """docs/language.md (Modes): unnumbered modes fill the gaps in declaration order, counting
    the numbers written further down too; not "one more than the mode before"."""
    text = """machine num;
mode Idle = 0 initial; mode Search; mode Carry = 5; mode Back; mode Done = 9 final;
mode Emerg final;
action Go in Idle { goto Search; }
action Pick in Search { goto Carry; }
action Drop in Carry { goto Back; }
action Home in Back { goto Done; }
"""
    model = load("num.afsm", text=text).model
    assert {m.name: m.number for m in model.modes} == {
        "Idle": 0, "Search": 1, "Back": 2, "Emerg": 3, "Carry": 5, "Done": 9}


def test_two_operands_in_a_row_outside_a_property_are_not_called_nested_temporal(
        tmp_path: Path) -> None:
    # The parser state after `x` is the same in a label and after `F` in a property: E115
    # only where a temporal operator stands before the failing token (it said E103 before).
    from tests.conftest import run_cli

    path = tmp_path / "m.afsm"
    path.write_text('machine m;\nmode A = 0 initial;\nvar x : [0..1];\nlabel a = x "l";\n',
                    encoding="utf-8")
    r = run_cli("check", str(path))
    assert r.code == 1 and "error[E101]: missing operator between 'x' and '\"l\"'" in r.err, r.err
    assert "E115" not in r.err and "E103" not in r.err


@pytest.mark.parametrize(("formula", "column"), [
    ("P=? [ F F mode == Dock ]", 11), ("P=? [ F F true ]", 11), ('P=? [ F F !"done" ]', 11),
    ("P=? [ F F (cell == 1) ]", 9), ("P=? [ cell == 1 U F mode == Dock ]", 21),
    ("P=? [ F<=3 G<=2 true ]", 17)])
def test_a_nested_operator_before_a_keyword_or_bracket_is_e115(formula: str,
                                                               column: int) -> None:
    """The inner operator lexes as a name when no label follows it: the error was E116
    ("missing ';' at the end of the outcome") or E233 ("unknown function 'F'"), review 18."""
    from tests.conftest import EXAMPLES, run_cli

    r = run_cli("verify", str(EXAMPLES / "patrol.afsm"), "--formula", formula)
    assert r.code == 1 and f"--formula:1:{column}: error[E115]: temporal operators" in r.err, \
        r.err


def test_mode_equals_is_taken_for_a_comparison(tmp_path: Path) -> None:
    """`when mode = A` (PRISM's spelling) gave a bare "unexpected '='", where `x = 1` got E103."""
    from tests.conftest import run_cli

    for line in ("action Go in A when mode = A { goto B; }", "label l = mode = B;"):
        path = tmp_path / "m.afsm"
        path.write_text("machine m;\nvar x : [0..2] init 0;\nmode A = 0 initial;\n"
                        f"mode B = 1 final;\n{line}\n", encoding="utf-8")
        r = run_cli("check", str(path))
        assert r.code == 1 and "error[E103]: '=' is not a comparison" in r.err, r.err


def test_check_takes_several_files_and_standard_input(tmp_path: Path) -> None:
    """`check a.afsm b.afsm` was a usage error and `check -` E001, though `fmt` takes both
    (review 18). One report for all of them; exit 1 if any has an error."""
    import subprocess
    import sys

    from tests.conftest import CASES, EXAMPLES, run_cli

    good = [str(EXAMPLES / "patrol.afsm"), str(EXAMPLES / "uav.afsm")]
    assert run_cli("check", *good).code == 0
    bad = CASES / "err_weight_tie" / "input.afsm"
    r = run_cli("check", *good, str(bad), str(tmp_path / "none.afsm"))
    assert r.code == 1 and "error[E301]" in r.err and "error[E001]" in r.err, r.err
    r = subprocess.run([sys.executable, "-m", "afsmc", "check", "-"], input=bad.read_text(),
                       capture_output=True, text=True, timeout=120)
    assert r.returncode == 1 and "<stdin>:6:43: error[E301]" in r.stderr, r.stderr
    # standard input is read as strictly as a file (review 19), and only once
    b = subprocess.run([sys.executable, "-m", "afsmc", "check", "-"],
                       input=b"machine m;\nmode A\xe9 = 0 initial;\n", capture_output=True,
                       timeout=120)
    assert b.returncode == 1 and b"<stdin>:2:7: error[E001]" in b.stderr, b.stderr
    assert run_cli("check", "-", "-").code == 2


def test_a_usage_error_shows_the_command_s_usage() -> None:
    """An unknown option of a command printed afsmc's top-level usage (review 18); a missing
    argument file printed a bare '[Errno 2] ...'."""
    from tests.conftest import EXAMPLES, run_cli

    r = run_cli("fmt", "--nope", str(EXAMPLES / "patrol.afsm"))
    assert r.code == 2 and "usage: afsmc fmt" in r.err and \
        "afsmc fmt: error: unrecognized arguments: --nope" in r.err, r.err
    r = run_cli("--nope", "fmt", str(EXAMPLES / "patrol.afsm"))  # before the command: afsmc's
    assert r.code == 2 and "afsmc: error: unrecognized arguments: --nope" in r.err, r.err
    r = run_cli("verify", str(EXAMPLES / "patrol.afsm"), "@no-such.args")
    assert r.code == 2 and "cannot read the argument file 'no-such.args': No such file" in \
        r.err and "Errno" not in r.err, r.err


def test_verify_of_an_empty_file_names_the_file(tmp_path: Path) -> None:
    # E213 had no file:1:1 in verify (check had it), with or without --formula.
    from tests.conftest import run_cli

    path = tmp_path / "empty.afsm"
    path.write_text("", encoding="utf-8")
    for extra in ((), ("-f", "P=? [ F true ]")):
        r = run_cli("verify", str(path), *extra)
        assert r.code == 1 and f"{path}:1:1: error[E213]" in r.err, r.err


def test_a_one_field_tuple_takes_a_plain_value(tmp_path: Path) -> None:
    """`var p : (x: [0..2]) init 1` and `p := (2)`: one field takes a plain value (`(2)` is
    the number 2); both used to be E217/E237. The answer equals a plain variable's."""
    import json

    from tests.conftest import run_cli

    def value(text: str) -> float:
        path = tmp_path / "t.afsm"
        path.write_text(text)
        r = run_cli("verify", str(path), "--json")
        assert r.code == 0, r.err
        return float(json.loads(r.out)["properties"][0]["value"])

    head = "mode A initial;\nmode B final;\n"
    tup = value(head + "var p : (x: [0..2]) init 1;\n"
                "action a in A { 0.5: goto B, p := (2); 0.5: goto B, p := p.x; }\n"
                "property q = P=? [ F p.x == 2 ];\n")
    plain = value(head + "var x : [0..2] init 1;\n"
                  "action a in A { 0.5: goto B, x := 2; 0.5: goto B, x := x; }\n"
                  "property q = P=? [ F x == 2 ];\n")
    assert tup == plain == 0.5
