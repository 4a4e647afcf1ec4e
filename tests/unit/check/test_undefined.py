"""Expressions undefined where they are evaluated (a division by zero): E306 with the state,
E245 for a constant-only part; the same answer from enumeration and from Z3; no traceback."""

from __future__ import annotations

from pathlib import Path

import pytest

from afsmc import check
from afsmc.compiler import load
from afsmc.diagnostics import Reporter
from afsmc.lower.lowering import lower
from afsmc.model import ir, search
from afsmc.model.evaluate import EvalError
from tests.conftest import ROOT, run_cli
from tests.storm_util import storm_prism

GUARDED = """machine guarded;
const double D = 4.0;
var x : [0..3] init 0;
var y : [0..3] init 0 clamp;
mode A = 0 initial;
mode B = 1 final;
action Go in A when x > 0 && 2 / x > 0.5 weight 0.5 / D { y := floor(3 / x); goto B; }
action St in A when x == 0 || 1 / x <= 0.5 weight (x == 0 ? 0.5 : 1 / (x + 1)) { x := min(3, x + 1); }
action Dn in A when x == 3 weight 0.9 { goto B; }
label l = x != 0 && 1 / x > 0;
rewards r { x > 0 : 1 / x; }
property p = P=? [ F "l" ];
property q = R{"r"}=? [ F mode == B ];
"""


def _codes(path: str) -> list[tuple[str, str]]:
    loaded = load(path, run_checks=False)
    return [(d.code, d.message) for d in check.run(loaded.model, used_names=loaded.used_names)]


@pytest.mark.parametrize("case", ["err_div_guard", "err_div_update", "err_div_constant",
                                  "err_weight_nan"])
def test_the_smt_solver_finds_the_division_by_zero_enumeration_finds(
        case: str, monkeypatch: pytest.MonkeyPatch) -> None:
    """Z3 has no division by zero (x / 0 is some number) and ToReal took only integers: the
    constant 0.5 / D crashed the check with a Z3Exception."""
    path = str(ROOT / "tests" / "golden" / "cases" / case / "input.afsm")
    enumerated = _codes(path)
    assert any(code in ("E306", "E245") for code, _ in enumerated)
    monkeypatch.setattr(search, "ENUMERATION_LIMIT", 0)
    monkeypatch.setattr(search, "SAMPLE_LIMIT", 0)
    assert _codes(path) == enumerated


def test_a_division_where_it_counts_only_is_accepted(tmp_path: Path,
                                                     monkeypatch: pytest.MonkeyPatch) -> None:
    """Behind &&, ||, ?: and a guard, a division by zero in one state hides nothing."""
    path = tmp_path / "guarded.afsm"
    path.write_text(GUARDED)
    r = run_cli("check", str(path))
    assert r.code == 0 and "E306" not in r.err and "Traceback" not in r.err, r.err
    monkeypatch.setattr(search, "ENUMERATION_LIMIT", 0)
    monkeypatch.setattr(search, "SAMPLE_LIMIT", 0)
    r = run_cli("check", str(path))
    assert r.code == 0 and "E306" not in r.err and "Traceback" not in r.err, r.err


@pytest.mark.storm
def test_verify_and_simulate_refuse_what_check_refuses() -> None:
    """verify and simulate both stop at E306 on a file check refuses (not p = 0, not E506)."""
    rel = str(ROOT / "tests" / "golden" / "cases" / "err_div_guard" / "input.afsm")
    for argv in (["verify", rel], ["simulate", rel, "--runs", "10"]):
        r = run_cli(*argv)
        assert r.code == 1 and "error[E306]" in r.err and "E506" not in r.err, r.err


def test_an_evaluation_error_in_a_rule_is_a_warning_not_a_traceback(
        monkeypatch: pytest.MonkeyPatch) -> None:
    def broken(model: ir.Model, rep: Reporter) -> None:
        raise EvalError("division by zero")

    monkeypatch.setattr(check, "RULES", (broken,))
    model = load(str(ROOT / "tests" / "golden" / "cases" / "err_div_guard" / "input.afsm"),
                 run_checks=False).model
    (d,) = check.run(model)
    assert d.code == "W309" and "division by zero" in d.message


def _model(tmp: Path, text: str) -> object:
    path = tmp / "spec.afsm"
    path.write_text(text)
    return load(str(path)).model


@pytest.mark.storm
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
