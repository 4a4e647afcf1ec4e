"""`afsmc verify` and `afsmc.verify.run`: real Storm, values checked against closed forms
derived by hand, the PRISM route against the JANI route, and the engines against each other."""

from __future__ import annotations

import json
import time
from collections.abc import Callable
from pathlib import Path

import pytest

from afsmc.diagnostics import CompileError
from afsmc.verify import run, upper_bound
from tests.conftest import EXAMPLES, run_cli

pytestmark = pytest.mark.storm

PATROL = str(EXAMPLES / "patrol.afsm")

# A DTMC: each attempt succeeds with probability P_OK. So P(F<=k done) = 1 - (1-P_OK)^k
# and the expected number of attempts is 1 / P_OK (geometric distribution).
GEO = """
machine geo;
param prob P_OK = 0.3;
mode Try = 0 initial;
mode Done = 1 final;
action Attempt in Try {
    P_OK: goto Done;
    1 - P_OK: skip;
}
label done = mode == Done;
rewards tries { [Attempt] true : 1; }
property soon = P=? [ F<=5 "done" ];
property tries = R{"tries"}=? [ F "done" ];
"""

# An MDP: two jobs of duration [2, 3] each (P_FAIL = 0: no retries). The total time is
# 4, 5 or 6; min/max pick the ends, uniform picks each end with probability 1/2, so the
# total is 4, 5, 6 with probabilities 1/4, 1/2, 1/4.
DEADLINE = """
machine deadline;
param int D = 5;
param prob P_FAIL = 0.2;
const int DUR = [2, 3];
var t : [0..20] init 0 clamp;
var left : [0..2] init 2;
mode Work = 0 initial;
mode Done = 1 final;
action Step in Work when left > 0 {
    1 - P_FAIL: left -= 1, t += DUR;
    P_FAIL: t += DUR;
}
action Finish in Work when left == 0 {
    goto Done;
}
label done = mode == Done;
rewards steps { [Step] true : 1; }
property by_deadline = P=? [ F "done" && t <= D ];
property steps = R{"steps"}=? [ F "done" ];
"""

# A record variable and mode ranges: the IR has `ret_px` and `mode >= Run`, which afsm
# does not accept; the formula shown must be afsm.
RECORD = """
machine rec;
var ret : (px: [0..2], py: [0..2]) init (0, 0);
mode Start = 0 initial;
mode Run = 1;
mode Walk = 2;
mode Other = 3;
mode End = 4 final;
action Go in Start {
    0.5: goto Run, ret.px := 1;
    0.25: goto Walk, ret.py := 2;
    0.25: goto Other;
}
action Stop in {1..3} when ret.py < 2 {
    goto End;
}
action Back in Walk when ret.py == 2 {
    goto Start, ret.py := 0;
}
label fin = mode == End;
rewards moves { [Go] true : 1; }
property q = P=? [ F mode in {1..3} && ret.px == 1 ];
property g = P=? [ G<=3 /* not yet */ !(mode in {Run, Walk})  ];
property u = P=? [ mode == Start U<=(2) ret.px == 1 ];
property r = R{"moves"}=? [ F "fin" ];
"""

# About 2.25 M reachable states: too big for a small --max-states, built in a child.
BIG = """
machine big;
var a : [0..1500] init 0;
var b : [0..1500] init 0;
mode Run = 0 initial;
action Go in Run when a < 1500 {
    0.5: a += 1;
    0.5: b := min(b + 1, 1500);
}
action Stay in Run when a == 1500 {
    skip;
}
label top = a == 1500;
property top = P=? [ F "top" ];
"""


Spec = Callable[[str, str], str]


@pytest.fixture
def spec(tmp_path: Path) -> Spec:
    def write(name: str, text: str) -> str:
        p = tmp_path / f"{name}.afsm"
        p.write_text(text)
        return str(p)

    return write


def test_dtmc_matches_closed_forms(spec: Spec) -> None:
    path = spec("geo", GEO)
    for p_ok in (0.3, 0.55):
        res = run(path, consts={"P_OK": str(p_ok)})
        assert res.kind == "dtmc" and res.uniform_model is None
        soon, tries = res.property("soon"), res.property("tries")
        assert soon.min is None and soon.max is None and soon.uniform is None
        assert soon.value == pytest.approx(1 - (1 - p_ok) ** 5, abs=1e-9)  # time-bounded
        assert tries.value == pytest.approx(1 / p_ok, rel=1e-5)  # expected reward
        assert res.model.states == 2


@pytest.mark.parametrize(("d", "lo", "hi", "uni"), [
    (3, 0.0, 0.0, 0.0), (4, 0.0, 1.0, 0.25), (5, 0.0, 1.0, 0.75), (6, 1.0, 1.0, 1.0)])
def test_mdp_min_max_uniform_match_hand_computation(spec: Spec, d: int, lo: float, hi: float,
                                                     uni: float) -> None:
    res = run(spec("deadline", DEADLINE), consts={"D": str(d), "P_FAIL": "0"})
    assert res.kind == "mdp" and res.uniform_model is not None
    r = res.property("by_deadline")
    assert r.min == pytest.approx(lo, abs=1e-9) and r.max == pytest.approx(hi, abs=1e-9)
    assert r.uniform == pytest.approx(uni, abs=1e-9)
    assert r.value is None
    steps = res.property("steps")  # exactly two Step actions, whatever is chosen
    assert steps.min == steps.max == steps.uniform == pytest.approx(2.0)


def test_time_bounded_and_reward_on_patrol_route_agreement() -> None:
    """Both routes into Storm give the same model and values (JANI is an independent
    backend written from the same IR)."""
    pytest.importorskip("afsmc.backends.jani")
    try:
        a = run(PATROL, via="prism")
        b = run(PATROL, via="jani")
    except CompileError as exc:  # a property the JANI backend cannot express
        pytest.skip(str(exc))
    for ma, mb in ((a.model, b.model), (a.uniform_model, b.uniform_model)):
        assert ma is not None and mb is not None
        assert (ma.states, ma.transitions, ma.choices) == (mb.states, mb.transitions, mb.choices)
    kinds = set()
    for pa, pb in zip(a.properties, b.properties, strict=True):
        assert pa.name == pb.name
        kinds.add(pa.formula.split("[")[1].split()[0])
        for key in ("min", "max", "uniform"):
            assert getattr(pa, key) == pytest.approx(getattr(pb, key), abs=1e-9)
        assert pa.min is not None and pa.max is not None and pa.uniform is not None
        assert pa.min - 1e-6 <= pa.uniform <= pa.max + 1e-6


def test_jani_route_on_small_specs(spec: Spec) -> None:
    pytest.importorskip("afsmc.backends.jani")
    for name, text in (("geo", GEO), ("deadline", DEADLINE)):
        path = spec(name, text)
        a, b = run(path, via="prism"), run(path, via="jani")
        assert (a.model.states, a.model.transitions) == (b.model.states, b.model.transitions)
        for pa, pb in zip(a.properties, b.properties, strict=True):
            for key in ("min", "max", "uniform", "value"):
                va, vb = getattr(pa, key), getattr(pb, key)
                assert (va is None) == (vb is None)
                if va is not None:
                    assert va == pytest.approx(vb, abs=1e-9)


@pytest.mark.slow
@pytest.mark.parametrize("engine", ["hybrid", "dd"])
def test_symbolic_engines_agree_with_sparse(spec: Spec, engine: str) -> None:
    path = spec("deadline", DEADLINE)
    sparse = run(path, consts={"D": "7"})
    sym = run(path, consts={"D": "7"}, engine=engine)  # type: ignore[arg-type]
    assert (sym.model.states, sym.model.transitions) == (sparse.model.states,
                                                          sparse.model.transitions)
    for a, b in zip(sparse.properties, sym.properties, strict=True):
        for key in ("min", "max", "uniform"):
            assert getattr(a, key) == pytest.approx(getattr(b, key), abs=1e-5)


FORMULAS = """machine fl;
var a : [0..5] init 0;
mode A = 0 initial;
mode B = 1 final;
formula high = a >= 3;
action Inc in A when a < 5 { 0.5: a := a + 1; 0.5: goto B; }
action Stop in A when a >= 5 { goto B; }
label hi = high;
rewards r { high : 1; }
property p  = P=? [ F "hi" ];
property q  = R{"r"}=? [ F mode == B ];
property p2 = P=? [ F high && a < 5 ];
"""


@pytest.mark.slow
@pytest.mark.parametrize(("engine", "via"), [("hybrid", "prism"), ("dd", "prism"),
                                             ("hybrid", "jani")])
def test_symbolic_engines_take_formulas_in_labels_and_rewards(spec: Spec, engine: str,
                                                              via: str) -> None:
    # By hand: a reaches 3 only through three heads in a row (1/8); the reward is collected
    # once in each of a = 3, 4, 5 of mode A, reached with 1/8, 1/16, 1/32, until mode B.
    res = run(spec("fl", FORMULAS), engine=engine, via=via)  # type: ignore[arg-type]
    assert res.property("p").value == pytest.approx(1 / 8, abs=1e-9)
    assert res.property("p2").value == pytest.approx(1 / 8, abs=1e-9)
    assert res.property("q").value == pytest.approx(1 / 8 + 1 / 16 + 1 / 32, abs=1e-9)


@pytest.mark.slow
def test_json_shape(spec: Spec) -> None:
    r = run_cli("verify", spec("deadline", DEADLINE), "--json", "--engine", "hybrid")
    assert r.code == 0, r.err
    obj = json.loads(r.out)  # stdout is exactly one JSON object (Storm's logs silenced)
    assert isinstance(obj, dict)
    assert obj["model"]["type"] == "mdp"
    assert isinstance(obj["model"]["states"], int) and isinstance(obj["model"]["transitions"], int)
    assert obj["uniform_model"]["type"] == "dtmc"
    assert [p["name"] for p in obj["properties"]] == ["by_deadline", "steps"]
    for p in obj["properties"]:
        assert set(p) >= {"name", "formula", "min", "max", "uniform", "value"}
        assert p["value"] is None and isinstance(p["min"], float)
        # Storm's time for each answer (the hybrid engine asks each Pmax as 1 - Pmin: its
        # time is that query's)
        assert set(p["seconds"]) == {"min", "max", "uniform"}, p
        assert all(isinstance(v, float) and 0 <= v <= obj["timings"]["total"]
                   for v in p["seconds"].values()), p
    assert {"build", "check", "total"} <= set(obj["timings"])
    assert obj["engine"] == "hybrid" and obj["via"] == "prism"
    assert r.err == ""  # silent under --json


def test_table_and_ad_hoc_formula(spec: Spec) -> None:
    path = spec("deadline", DEADLINE)
    r = run_cli("verify", path, "-c", "P_FAIL=0", "-p", "steps", "--formula",
                'Pmax=? [ F<=2 "done" ]', "--formula", 'P=? [ F "done" && t <= 5 ]')
    assert r.code == 0, r.err
    assert "min" in r.out and "max" in r.out and "uniform" in r.out
    lines = {line.split()[0]: line.split() for line in r.out.splitlines() if line.strip()}
    assert "by_deadline" not in lines  # only what was asked
    assert lines["steps"][-3:] == ["2", "2", "2"]
    # the time needs two Step actions and a Finish: 3 steps, so nothing by step 2
    assert lines["adhoc"][-3:] == ["-", "0", "0"]
    assert lines["adhoc2"][-3:] == ["0", "1", "0.75"]
    assert "states" in r.out and "transitions" in r.out and "build" in r.out


@pytest.mark.slow
@pytest.mark.parametrize(("name", "consts"), [
    ("patrol", {}), ("uav", {"WIDTH": "2", "HEIGHT": "2", "T_LIMIT": "100", "DEADLINE": "80"}),
    ("record", {})])
def test_shown_formulas_are_afsm_with_the_same_values(spec: Spec, name: str,
                                                      consts: dict[str, str]) -> None:
    """verify's formula column (docs/verification.md: afsm syntax) re-parses as --formula
    and gives the property's values."""
    path = spec(name, RECORD) if name == "record" else str(EXAMPLES / f"{name}.afsm")
    res = run(path, consts=consts, isolate=False)
    if name == "record":
        assert [p.formula for p in res.properties] == [
            "P=? [ F mode in {1..3} && ret.px == 1 ]", "P=? [ G<=3 !(mode in {Run, Walk}) ]",
            "P=? [ mode == Start U<=(2) ret.px == 1 ]", 'R{"moves"}=? [ F "fin" ]']
    again = run(path, consts=consts, formulas=[p.formula for p in res.properties],
                isolate=False)
    assert len(again.properties) == len(res.properties)
    for p, q in zip(res.properties, again.properties, strict=True):
        assert q.formula == p.formula
        for key in ("min", "max", "uniform", "value"):
            a, b = getattr(p, key), getattr(q, key)
            assert (a is None) == (b is None) and (a is None or a == pytest.approx(b, abs=1e-12)), \
                (p.name, key)


def test_formula_errors_point_into_the_formula(spec: Spec) -> None:
    r = run_cli("verify", spec("geo", GEO), "--formula", 'P=? [ F "don" ]')
    assert r.code == 1
    assert "--formula:1:9: error[E203]" in r.err and "did you mean 'done'" in r.err
    assert "Traceback" not in r.err


def test_storm_rejection_is_a_diagnostic_at_the_property(spec: Spec) -> None:
    # Storm's symbolic engines have no total reward R[C] (it returns no result).
    path = spec("geo", GEO + 'property total = R{"tries"}=? [ C ];\n')
    r = run_cli("verify", path, "-p", "total", "--engine", "hybrid")
    assert r.code == 1
    assert "error[E404]" in r.err and "geo.afsm:14:1" in r.err and "--engine sparse" in r.err
    assert "Traceback" not in r.err and "Error:" not in r.err
    ok = run_cli("verify", path, "-p", "total")  # the sparse engine has it: E[attempts]
    assert ok.code == 0 and "3.33333" in ok.out


def test_unknown_property(spec: Spec) -> None:
    r = run_cli("verify", spec("geo", GEO), "-p", "tires")
    assert r.code == 1 and "E407" in r.err and "did you mean 'tries'" in r.err


def test_max_states_stops_patrol() -> None:
    r = run_cli("verify", PATROL, "--max-states", "10")
    assert r.code == 1
    assert "error[E405]" in r.err and "more than --max-states 10" in r.err


@pytest.mark.slow
def test_default_max_states_binds_the_sparse_engine_only(monkeypatch: pytest.MonkeyPatch) -> None:
    """The default limit predicts sparse memory; the symbolic engines are held by the
    memory guard (scenario 1's 77.6 M states are over the default of 50 M). A limit above
    every variable's range: a counter beyond it is refused before a symbolic build (E420,
    tests/e2e/test_deep_guard.py)."""
    import afsmc.verify.core.api as api
    import afsmc.verify.core.model_loop as model_loop
    import afsmc.verify.core.runner as runner
    from afsmc.compiler import CompileError
    from afsmc.verify import run

    monkeypatch.setattr(api, "default_max_states", lambda: 30)
    monkeypatch.setattr(runner, "default_max_states", lambda: 30)
    monkeypatch.setattr(model_loop, "default_max_states", lambda: 30)
    hybrid = run(PATROL, engine="hybrid", isolate=False)
    assert hybrid.model.states > 30
    with pytest.raises(CompileError) as sparse:
        run(PATROL, engine="sparse", isolate=False)
    assert "E405" in str(sparse.value.diagnostics[0].code)
    with pytest.raises(CompileError) as explicit:
        run(PATROL, engine="hybrid", isolate=False, max_states=10)
    assert "E405" in str(explicit.value.diagnostics[0].code)


@pytest.mark.slow
def test_max_states_stops_a_big_build_early(spec: Spec) -> None:
    """The child process is stopped while Storm explores, long before 2.25 M states."""
    from afsmc.compiler import load

    path = spec("big", BIG)
    assert upper_bound(load(path).model) > 2_000_000
    t0 = time.monotonic()
    r = run_cli("verify", path, "--max-states", "1000")
    assert r.code == 1, r.out
    assert "error[E405]" in r.err and "--max-states 1,000" in r.err
    assert "at most" in r.err  # the estimate shown before building
    assert time.monotonic() - t0 < 60


@pytest.mark.slow
def test_isolated_build_reports_progress(spec: Spec) -> None:
    lines: list[str] = []
    res = run(spec("geo", GEO), isolate=True, progress=lines.append)
    assert res.property("tries").value == pytest.approx(1 / 0.3, rel=1e-5)
    assert any(line.startswith("built the DTMC: 2 states") for line in lines), lines


def test_open_constant_required_value(spec: Spec) -> None:
    r = run_cli("verify", spec("geo", GEO), "-c", "NOPE=3")
    assert r.code == 1 and "E209" in r.err


def test_the_max_states_hint_speaks_of_bytes_per_state_only_for_sparse(spec: Spec) -> None:
    path = spec("deadline", DEADLINE)
    sparse = run_cli("verify", path, "--max-states", "2", "--engine", "sparse")
    dd = run_cli("verify", path, "--max-states", "2", "--engine", "dd")
    assert sparse.code == dd.code == 1 and "E405" in sparse.err and "E405" in dd.err
    assert "250 bytes per state" in sparse.err and "bytes per state" not in dd.err, dd.err


HAZARDS_IN_ORDER = """machine hz;
mode S = 0 initial;
mode E1 = 1 final;
mode E2 = 2 final;
mode D = 3 final;
action Go in S { goto D; }
hazard H1 from {S} with probability 0.3 { goto E1; }
hazard H2 from {S} with probability 0.3 { goto E2; }
property e1 = P=? [ F mode == E1 ];
property e2 = P=? [ F mode == E2 ];
property d = P=? [ F mode == D ];
"""


@pytest.mark.parametrize("via", ["prism", "jani"])
def test_hazards_of_a_mode_apply_in_declaration_order(tmp_path: Path, via: str) -> None:
    # docs/language.md: each hazard takes its share of what the earlier ones left.
    path = tmp_path / "hz.afsm"
    path.write_text(HAZARDS_IN_ORDER)
    res = run(str(path), via=via)  # type: ignore[arg-type]
    got = {p.name: p.value for p in res.properties}
    assert got == pytest.approx({"e1": 0.3, "e2": 0.7 * 0.3, "d": 0.7 * 0.7}, abs=1e-12)


def test_total_rewards_on_symbolic_engines_are_refused_before_building(
        spec: Spec, tmp_path: Path) -> None:
    # afsmc refuses R [ C ] on hybrid and dd at once (E404) instead of after the build: the
    # refusal stands only while Storm itself has no answer there, which this checks too.
    import stormpy

    path = spec("geo", GEO + 'property total = R{"tries"}=? [ C ];\n')
    for engine in ("hybrid", "dd"):
        r = run_cli("verify", path, "--engine", engine, "--progress")
        assert r.code == 1 and f"error[E404]: the {engine} engine cannot check 'total', an " \
            "unbounded total reward" in r.err, r.err
        assert "building" not in r.err and "built" not in r.err
    out = run_cli("compile", path, "-o", str(tmp_path / "geo.prism"))
    assert out.code == 0, out.err
    prog = stormpy.parse_prism_program(str(tmp_path / "geo.prism")).substitute_constants()
    [prop] = stormpy.parse_properties('R{"tries"}=? [ C ]', prog)
    model = stormpy.build_symbolic_model(prog, [prop])
    try:
        res = stormpy.model_checking(model, prop, engine=stormpy.Engine.HYBRID)
    except RuntimeError:
        res = None
    assert res is None  # Storm has no result: if it ever has one, drop the refusal


BOUNDED_CUMULATIVE = """machine c;
const int STEP = [1, 2];
var x : [0..4] init 0 clamp;
mode Run = 0 initial;
mode Done = 1 final;
action Go in Run when x < 4 { x += STEP; }
action Fin in Run when x == 4 { goto Done; }
rewards r { true : 1; }
property cum = R{"r"}=? [ C<=3 ];
"""


def test_bounded_cumulative_state_rewards_on_an_mdp_are_refused_on_hybrid(
        spec: Spec, tmp_path: Path) -> None:
    # Storm's hybrid engine gives the minimum of R [ C<=3 ] here as 1 (the first step's
    # reward); sparse and dd agree on 3, the reward being 1 in every state. afsmc refuses
    # the hybrid engine for it (E404) while Storm still gets it wrong, which this checks.
    import stormpy

    path = spec("cum", BOUNDED_CUMULATIVE)
    values = {}
    for engine in ("sparse", "dd"):
        r = run_cli("verify", path, "--engine", engine, "--json")
        assert r.code == 0, r.err
        values[engine] = json.loads(r.out)["properties"][0]["min"]
    assert values["sparse"] == pytest.approx(3.0) and values["dd"] == pytest.approx(3.0)
    r = run_cli("verify", path, "--engine", "hybrid")
    assert r.code == 1 and "error[E404]: the hybrid engine cannot check 'cum'" in r.err, r.err
    assert "--engine dd" in r.err
    out = run_cli("compile", path, "-o", str(tmp_path / "cum.prism"))
    assert out.code == 0, out.err
    prog = stormpy.parse_prism_program(str(tmp_path / "cum.prism")).substitute_constants()
    [prop] = stormpy.parse_properties('R{"r"}min=? [ C<=3 ]', prog)
    model = stormpy.build_symbolic_model(prog, [prop])
    res = stormpy.model_checking(model, prop, only_initial_states=True,
                                 engine=stormpy.Engine.HYBRID)
    wrong = stormpy.filter_initial_states(res, model).get_min()
    assert wrong != pytest.approx(3.0)  # if Storm gets it right one day, drop the refusal


def test_api_takes_python_numbers_and_names_a_missing_property() -> None:
    """`run(consts={"CELLS": 5})` raised a raw TypeError, and `res.property("zzz")` a bare
    StopIteration."""
    from afsmc.verify import run as api_run

    patrol = str(EXAMPLES / "patrol.afsm")
    as_text = api_run(patrol, consts={"CELLS": "3"}, properties=["finish"])
    as_int = api_run(patrol, consts={"CELLS": 3}, properties=["finish"])
    assert as_int.property("finish").max == as_text.property("finish").max is not None
    with pytest.raises(KeyError, match="no property 'zzz'; there are 'finish'"):
        as_int.property("zzz")


@pytest.mark.slow
@pytest.mark.parametrize(("users", "child"), [
    (None, "glibc.malloc.hugetlb=1"), ("glibc.malloc.hugetlb=0", "glibc.malloc.hugetlb=0")])
def test_the_storm_child_allocates_in_huge_pages(monkeypatch: pytest.MonkeyPatch,
                                                 users: str | None, child: str) -> None:
    """The watched Storm process starts with glibc's malloc huge pages (about 5% shorter
    hybrid checks, docs/benchmarks.md) unless the user's GLIBC_TUNABLES sets that key;
    this process's environment is left as it was. Read from the child's /proc environ
    (where glibc keeps only the first of several tunables: see the second half)."""
    import multiprocessing
    import os

    from afsmc.verify.engines.guard import child_environment

    if users is None:
        monkeypatch.delenv("GLIBC_TUNABLES", raising=False)
    else:
        monkeypatch.setenv("GLIBC_TUNABLES", users)
    seen: list[list[bytes]] = []

    def progress(text: str) -> None:  # called while the child runs
        for p in multiprocessing.active_children():
            try:
                env = Path(f"/proc/{p.pid}/environ").read_bytes().split(b"\0")
            except OSError:
                continue
            seen.append([e for e in env if e.startswith(b"GLIBC_TUNABLES=")])

    res = run(str(EXAMPLES / "patrol.afsm"), isolate=True, progress=progress)
    assert res.property("finish").max is not None
    assert [f"GLIBC_TUNABLES={child}".encode()] in seen, seen
    assert os.environ.get("GLIBC_TUNABLES") == users
    # another tunable of the user's is kept beside it
    monkeypatch.setenv("GLIBC_TUNABLES", "glibc.malloc.arena_max=2")
    with child_environment():
        assert os.environ["GLIBC_TUNABLES"] == "glibc.malloc.arena_max=2:glibc.malloc.hugetlb=1"
    assert os.environ["GLIBC_TUNABLES"] == "glibc.malloc.arena_max=2"


@pytest.mark.parametrize("via", ["prism", "jani"])
def test_a_negative_expected_reward_is_the_same_on_every_engine(tmp_path: Path,
                                                                via: str) -> None:
    """The symbolic engines read the initial state's value, not the largest value over all
    states counted with the 0 of states outside the filter: that turned -2 into 0. The
    oracle is the sparse engine, and the hand count of the rewards along the one path."""
    path = tmp_path / "neg.afsm"
    path.write_text(
        "machine neg;\nvar v : [0..3] init 0;\nmode A initial;\nmode B final;\n"
        "action Go in A when v < 3 { v += 1; }\naction Stop in A when v == 3 { goto B; }\n"
        "rewards r { true : v - 2; }\n"
        "property total = R{\"r\"}=? [ F mode == B ];\n"
        "property first = R{\"r\"}=? [ C<=2 ];\n"
        "property reach = P=? [ F v == 2 ];\n")
    sparse = run(str(path), engine="sparse", via=via, isolate=False)
    # the states v = 0, 1, 2, 3 in A are left once each: -2 - 1 + 0 + 1
    assert sparse.property("total").value == pytest.approx(-2.0, abs=1e-12)
    assert sparse.property("first").value == pytest.approx(-3.0, abs=1e-12)
    for engine in ("hybrid", "dd"):
        res = run(str(path), engine=engine, via=via, isolate=False)
        for name in ("total", "first", "reach"):
            assert res.property(name).value == pytest.approx(
                sparse.property(name).value, abs=1e-9), (engine, name)
