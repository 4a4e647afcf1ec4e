"""Constants given on the command line (`--const NAME=VALUE`): unknown, fixed, repeated,
incomplete, non-finite, beyond 64 bits, or written otherwise than in the language."""

from __future__ import annotations

from pathlib import Path

import pytest

from tests.conftest import EXAMPLES, ROOT, run_cli


def test_unknown_and_fixed_constants_on_the_command_line(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.chdir(ROOT)
    r = run_cli("check", "examples/patrol.afsm", "--const", "CELS=3")
    assert r.code == 1 and "error[E209]" in r.err and "did you mean 'CELLS'" in r.err
    r = run_cli("check", "examples/patrol.afsm", "--const", "LOW=3")
    assert r.code == 1 and "is a fixed constant" in r.err
    r = run_cli("check", "examples/patrol.afsm", "--const", "CELLS=x")
    assert r.code == 1 and "not an int" in r.err


def test_a_constant_given_twice_is_a_usage_error() -> None:
    for argv in (["--const", "CELLS=3,CELLS=4"], ["--const", "CELLS=3", "-c", "CELLS=5"]):
        r = run_cli("check", str(EXAMPLES / "patrol.afsm"), *argv)
        assert r.code == 2 and "--const CELLS is given twice" in r.err, r.err


def test_a_constant_without_a_name_is_a_usage_error() -> None:
    for value in ("=3", "CELLS=3,=4", " =3"):
        r = run_cli("check", str(EXAMPLES / "patrol.afsm"), "--const", value)
        assert r.code == 2 and "expected NAME=VALUE" in r.err and "(no name)" in r.err, r.err


@pytest.mark.storm
def test_a_constant_without_a_value_is_a_usage_error() -> None:
    # as `--const CELLS` is (no '='): both are the option's own syntax, not the model's
    for command in ("check", "verify", "sweep"):
        for value in ("CELLS=", "CELLS= ", "ROUNDS=1:2,CELLS="):
            r = run_cli(command, str(EXAMPLES / "patrol.afsm"), "--const", value)
            assert r.code == 2 and "expected NAME=VALUE" in r.err and "(no value)" in r.err, \
                r.err


WEIGHTED = """machine weighted;
param double D = 0.5;
param int N = 3;
var x : [0..3] init 0;
mode A = 0 initial;
mode B = 1 final;
action Up in A when x < 3 && x < N weight D { x += 1; }
action Done in A when x >= 3 || x >= N { goto B; }
label done = mode == B;
property reach = P=? [ F "done" ];
"""


@pytest.mark.parametrize("value", ["inf", "-inf", "1e400", "nan", "NaN", "infinity"])
def test_a_non_finite_double_on_the_command_line_is_e208(tmp_path: Path, value: str) -> None:
    path = tmp_path / "weighted.afsm"
    path.write_text(WEIGHTED)
    for argv in (["check"], ["compile", "-o", "-"]):
        r = run_cli(*argv, str(path), "--const", f"D={value}")
        assert r.code == 1, r.err
        assert f"{path}:2:14: error[E208]: --const D={value}: not a finite double" in r.err
        assert "Traceback" not in r.err and "E302" not in r.err


def test_an_integer_beyond_64_bits_on_the_command_line_is_e208(tmp_path: Path) -> None:
    path = tmp_path / "weighted.afsm"
    path.write_text(WEIGHTED)
    r = run_cli("check", str(path), "--const", "N=10000000000000000000")
    assert r.code == 1 and "error[E208]: --const N=10000000000000000000: does not fit in a " \
        "64-bit integer (-9223372036854775808 to 9223372036854775807)" in r.err
    assert run_cli("check", str(path), "--const", "N=9223372036854775807").code == 0


@pytest.mark.parametrize(("name", "value"), [("N", "1_0"), ("N", "١٢"), ("D", "0_5"),
                                             ("D", "٠.٥"), ("N", "0x10")])
def test_numbers_on_the_command_line_are_written_as_in_the_language(
        tmp_path: Path, name: str, value: str) -> None:
    # Python's int() and float() read digit separators and non-ASCII digits; afsm does not.
    path = tmp_path / "weighted.afsm"
    path.write_text(WEIGHTED)
    r = run_cli("check", str(path), "--const", f"{name}={value}")
    assert r.code == 1 and f"error[E208]: --const {name}={value}: not a" in r.err, r.err
    for ok in ("N=+3", "D=.5", "D=5e-1", "D=0."):
        assert run_cli("check", str(path), "--const", ok).code == 0, ok
