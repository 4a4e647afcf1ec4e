"""Integer `mod` and `pow` mean what Storm computes, in the checks, the simulator and the
backends. The oracles are plain stormpy (on a hand-written PRISM model, and on afsmc's
PRISM and JANI output) and values computed by hand."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
import stormpy
import z3

from afsmc.backends import jani
from afsmc.compiler import load
from afsmc.lower.lowering import lower
from afsmc.model import expr as E
from afsmc.model.evaluate import Env, evaluate
from afsmc.model.search import _z3
from afsmc.sim.compile import compile_expr
from tests.conftest import run_cli
from tests.storm_util import storm_prism

INT = E.Type.INT
PAIRS = [(a, b) for a in range(-8, 9) for b in range(-4, 5) if b != 0]

# Worked by hand from Storm's rule: the C++ remainder (sign of a), plus b where a < 0.
HAND = {(7, 3): 1, (-7, 3): 2, (7, -3): 1, (-7, -3): -4, (-6, 3): 3, (6, -3): 0, (-6, -3): -3,
        (0, 3): 0, (0, -3): 0}


def _valuations(model: object) -> list[dict[str, object]]:
    vals = model.state_valuations  # type: ignore[attr-defined]
    return [json.loads(str(vals.to_json(s))) for s in range(model.nr_states)]  # type: ignore[attr-defined]


def _storm_mod_table(tmp: Path) -> dict[tuple[int, int], int]:
    """mod(a, b) for every pair, as Storm's sparse engine computes it from PRISM text."""
    n = len(PAIRS)
    branches = " + ".join(f"1/{n} : (s'=1) & (a'={a}) & (b'={b})" for a, b in PAIRS)
    path = tmp / "mod.prism"
    path.write_text(f"""dtmc
module m
  s : [0..2] init 0;
  a : [-8..8] init 0;
  b : [-4..4] init 0;
  y : [-20..20] init 0;
  [] s = 0 -> {branches};
  [] s = 1 -> (s'=2) & (y'=mod(a, b));
  [] s = 2 -> true;
endmodule
""")
    opts = stormpy.BuilderOptions()
    opts.set_build_state_valuations()
    model = stormpy.build_model(stormpy.parse_prism_program(str(path)), options=opts)
    return {(int(v["a"]), int(v["b"])): int(v["y"])  # type: ignore[call-overload]
            for v in _valuations(model) if v["s"] == 2}


@pytest.mark.storm
def test_mod_is_storms_in_the_evaluator_the_simulator_and_the_smt_search(tmp_path: Path) -> None:
    storm = _storm_mod_table(tmp_path)
    assert len(storm) == len(PAIRS)
    e = E.Call("mod", (E.VarRef("a", INT), E.VarRef("b", INT)), INT)
    for (x, y), want in HAND.items():
        if (x, y) in storm:
            assert storm[x, y] == want, (x, y)
        assert evaluate(e, Env(vars={"a": x, "b": y})) == want, (x, y)
    a = np.array([p[0] for p in PAIRS], dtype=np.int64)
    b = np.array([p[1] for p in PAIRS], dtype=np.int64)
    want = np.array([storm[p] for p in PAIRS])
    assert np.array_equal(evaluate(e, Env(vars={"a": a, "b": b})), want)  # checks' enumeration
    assert np.array_equal(compile_expr(e)({"a": a, "b": b}), want)  # simulator
    for (x, y), v in storm.items():  # checks' SMT search (beyond 4 M states)
        assert evaluate(e, Env(vars={"a": x, "b": y})) == v
        got = z3.simplify(_z3(e, {"a": z3.IntVal(x), "b": z3.IntVal(y)}, 0, {}))
        assert got.as_long() == v, (x, y)


MOD_NEGATIVE = """
machine md2;
var x : [0..6] init 5;
var y : [0..3] init 0{clamp};
mode S = 0 initial;
mode D = 1 final;
action Go in S {{ y := mod(x, 0 - 4), goto D; }}
property p = P=? [ F mode == D && y == 1 ];
"""


@pytest.mark.storm
def test_mod_by_a_negative_number_agrees_between_verify_simulate_and_check(tmp_path: Path) -> None:
    """Storm: mod(5, -4) = 1, so p = 1; numpy's mod gave -3 (simulate: p = 0, check: E303)."""
    path = tmp_path / "md2.afsm"
    path.write_text(MOD_NEGATIVE.format(clamp=" clamp"))
    for via in ("prism", "jani"):
        r = run_cli("verify", str(path), "--via", via, "--json")
        assert r.code == 0, r.err
        assert json.loads(r.out)["properties"][0]["value"] == 1.0
    r = run_cli("simulate", str(path), "--runs", "50", "--json")
    assert r.code == 0, r.err
    assert json.loads(r.out)["properties"][0]["estimate"] == 1.0
    plain = tmp_path / "md3.afsm"
    plain.write_text(MOD_NEGATIVE.format(clamp=""))
    r = run_cli("check", str(plain))
    assert r.code == 0 and "E303" not in r.err, r.err


POW_NEGATIVE_BASE = """
machine pn;
var x : [0..6] init 0;
var y : [-100..100] init 0;
var r : bool init false;
mode S = 0 initial;
mode E = 1;
mode D = 2 final;
action Pick in S {{
  1/7: x := 0, goto E;
  1/7: x := 1, goto E;
  1/7: x := 2, goto E;
  1/7: x := 3, goto E;
  1/7: x := 4, goto E;
  1/7: x := 5, goto E;
  1/7: x := 6, goto E;
}}
action Eval in E {{ goto D, r := pow({base}, x) > 0, y := pow({base}, x); }}
property p0 = P=? [ F mode == D && r && x == 0 ];
property p1 = P=? [ F mode == D && r && x == 1 ];
property p2 = P=? [ F mode == D && r && x == 2 ];
property q3 = P=? [ F mode == D && y == 0 - 8 && x == 3 ];
property q4 = P=? [ F mode == D && y == 16 && x == 4 ];
property q6 = P=? [ F mode == D && y == 64 && x == 6 ];
property pos = P=? [ F mode == D && r ];
"""

# By hand: pow(-2, x) > 0 exactly for even x (0, 2, 4, 6), each with probability 1/7;
# pow(-2, 3) = -8, pow(-2, 4) = 16, pow(-2, 6) = 64.
POW_HAND = {"p0": 1 / 7, "p1": 0.0, "p2": 1 / 7, "q3": 1 / 7, "q4": 1 / 7, "q6": 1 / 7,
            "pos": 4 / 7}


@pytest.mark.slow
@pytest.mark.storm
@pytest.mark.parametrize("base", ["0 - 2", "B", "-2", "k - 4"])
def test_pow_of_a_negative_base_is_right_in_storm_via_prism_and_jani(tmp_path: Path, base: str) -> None:
    """Storm's sparse engine computed pow(b, x) with b folded to a negative constant as
    -(|b| ^ x): every probability above was 0 but for q3."""
    text = POW_NEGATIVE_BASE.format(base=base).replace(
        "mode S", "const int B = 0 - 2;\nvar k : [2..2] init 2;\nmode S", 1)
    path = tmp_path / "pn.afsm"
    path.write_text(text)
    low = lower(load(str(path)).model)
    _, values = storm_prism(low, tmp_path)  # plain stormpy on afsmc's PRISM output
    assert values == pytest.approx(POW_HAND)
    jpath = tmp_path / "pn.jani"
    jpath.write_text(jani.dumps(jani.emit(low)), encoding="utf-8")
    jmodel, props = stormpy.parse_jani_model(str(jpath))
    built = stormpy.build_model(jmodel, props)
    init = built.initial_states[0]
    jvalues = {p.get_name(): float(stormpy.model_checking(built, p).get_value(init)) for p in props}
    assert jvalues == pytest.approx(POW_HAND)
    for via in ("prism", "jani"):
        for engine in ("sparse", "dd"):
            r = run_cli("verify", str(path), "--via", via, "--engine", engine, "--json")
            assert r.code == 0, r.err
            got = {p["name"]: p["value"] for p in json.loads(r.out)["properties"]}
            assert got == pytest.approx(POW_HAND), (via, engine)
    r = run_cli("simulate", str(path), "--runs", "2000", "--json")
    assert r.code == 0, r.err
    for p in json.loads(r.out)["properties"]:
        assert p["low"] <= POW_HAND[p["name"]] <= p["high"], p


def test_pow_rewrite_keeps_a_base_that_is_never_negative(tmp_path: Path) -> None:
    path = tmp_path / "pp.afsm"
    path.write_text(POW_NEGATIVE_BASE.format(base="2").replace(" && y == 0 - 8", " && y == 8")
                    .replace("y : [-100..100]", "y : [0..100]"))
    text = run_cli("compile", str(path), "-o", "-")
    assert text.code == 0, text.err
    assert "pow(2, x)" in text.out and "max(" not in text.out


NEGATIVE_EXPONENT = """
machine pw;
var x : [0..3] init 0;
mode S = 0 initial;
mode D = 1 final;
action Inc in S when x < 3 weight pow(2, -x) { x := x + 1; }
action Other in S weight 0.3 { goto D; }
property p = P=? [ F mode == D && x == 2 ];
property q = P=? [ F mode == D && x == 1 ];
"""


@pytest.mark.storm
def test_int_pow_with_a_negative_exponent_simulates_as_storm_verifies(tmp_path: Path) -> None:
    """pow(2, -x) is 1, 0.5, 0.25: Inc wins over 0.3 at x = 0 and 1, Other at x = 2, so
    p = 1 and q = 0 (by hand). The simulator crashed on numpy's integer power."""
    path = tmp_path / "pw.afsm"
    path.write_text(NEGATIVE_EXPONENT)
    r = run_cli("verify", str(path), "--json")
    assert r.code == 0, r.err
    assert {p["name"]: p["value"] for p in json.loads(r.out)["properties"]} == {"p": 1.0, "q": 0.0}
    r = run_cli("simulate", str(path), "--runs", "100", "--json")
    assert r.code == 0, r.err
    assert {p["name"]: p["estimate"] for p in json.loads(r.out)["properties"]} == {"p": 1.0, "q": 0.0}


DIVISION_BEHIND_A_GUARD = """
machine dg;
var x : [0..3] init 0;
mode S = 0 initial;
mode D = 1 final;
action Up in S weight 0.5 { x := min(x + 1, 3); }
action Go in S when x > 0 && 6 / x > 2.5 weight 0.7 { goto D; }
property p = P=? [ F mode == D ];
"""


@pytest.mark.storm
def test_a_division_by_zero_behind_a_guard_simulates_as_storm_verifies(tmp_path: Path) -> None:
    """6 / x is undefined at x = 0, where `x > 0` already decides the guard: check accepts
    the model and Storm gives p = 1 (Go fires at x = 1 or 2). The simulator stopped with
    "division by zero" (E506): it computed 6 / x in every run before the `&&`."""
    path = tmp_path / "dg.afsm"
    path.write_text(DIVISION_BEHIND_A_GUARD)
    r = run_cli("check", str(path))
    assert r.code == 0, r.err
    r = run_cli("verify", str(path), "--solver", "topological", "--json")  # Storm
    assert r.code == 0, r.err
    assert json.loads(r.out)["properties"][0]["value"] == 1.0
    r = run_cli("simulate", str(path), "--runs", "100", "--json")
    assert r.code == 0, r.err
    assert json.loads(r.out)["properties"][0]["estimate"] == 1.0
