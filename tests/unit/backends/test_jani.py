"""The JANI backend against an independent oracle: Storm reading our PRISM output.

For every example and for small specs covering the language, Storm must build exactly
the same state space from both routes and give the same value for every property.
"""

from __future__ import annotations

import json
import math
from collections.abc import Mapping
from dataclasses import replace
from pathlib import Path

import pytest
import stormpy

from afsmc.backends import jani, prism
from afsmc.compiler import load
from afsmc.compiler import lowered as compiler_lowered
from afsmc.lower.lowering import RESOLUTIONS, Lowered
from tests.conftest import EXAMPLES, run_cli

# `--const`-style overrides that keep an example's instance small enough for a test.
OVERRIDES: dict[str, dict[str, str]] = {"uav": {"WIDTH": "2", "HEIGHT": "2", "T_LIMIT": "60"},
                                        "two_uav": {"OBJECTS": "1", "T_LIMIT": "25"}}


# Two interval constants in one action, a tuple variable, clamping, a weight that refers
# to another weight, a preemptive and a probabilistic hazard, pow/mod/floor/ceil, labels
# inside compound property expressions, and every property kind both routes accept.
GRID = """
machine grid;
param int WIDTH = 3;
param int HORIZON = 5;
const int STEP = [1, 2];
const int COST = [1, 3];
const prob P_WIND = 0.2;
const prob P_CRASH = 0.05;
const double HALF = 0.5;

var pos : (x: [0..WIDTH], y: [0..2]) init (0, 0);
var fuel : [0..8] init 8 clamp;
var carrying : bool init false;
var t : [0..6] init 0 clamp;

mode Fly = 0 initial;
mode Land = 1;
mode Crashed = 2 final;
mode Home = 3 final;

action Go in Fly when pos.x < WIDTH weight (fuel > 2 ? 0.8 : 0.1) {
    1 - P_WIND: pos.x := min(pos.x + STEP, WIDTH), fuel -= COST, t += 1;
    P_WIND:     pos := (pos.x, mod(pos.y + 1, 3)), fuel -= 1, t += 1;
}
action Turn in Fly weight 0.5 * (1 - w(Go)) + 0.05 {
    pos.y := floor(pos.y / 2), carrying := !carrying, t += 1;
}
action Down in Fly when pos.x == WIDTH weight 0.9 {
    goto Land;
}
action Settle in Land weight ceil(HALF) * 0.5 {
    HALF: goto Home, fuel := pow(2, 3);
    1 - HALF: fuel -= 1;
}
hazard Empty from {Fly, Land} when fuel == 0 {
    goto Crashed;
}
hazard Gust from Fly with probability P_CRASH {
    goto Crashed;
}

formula far = pos.x >= WIDTH - 1;
label home = mode == Home;
label crashed = mode == Crashed;
label far_out = far && !carrying;

rewards fuel_used {
    [Go] true : 2;
    [Turn] carrying : 1;
}
rewards time {
    mode == Fly || mode == Land : 1;
    [Down] true : 2.5;
    pos.y > 0 : 0.5;
}

property home = P=? [ F "home" ];
property home_soon = Pmax=? [ F<=4 "home" ];
property home_by = P=? [ F<=HORIZON "home" && !carrying ];
property safe = P=? [ G !"crashed" ];
property until = P=? [ !"crashed" U "home" ];
property until_soon = Pmin=? [ pos.y == 0 || "far_out" U<=5 "home" && fuel > 2 ];
property next = P=? [ X "far_out" ];
property next_far = P=? [ X far && t == 1 ];
property fuel = R{"fuel_used"}=? [ F mode == Home || mode == Crashed ];
property time_total = R{"time"}=? [ C ];
property time_fuel = R{"fuel_used"}=? [ C ];
property time5 = R{"time"}max=? [ C<=5 ];
property time_at = R{"time"}=? [ I=3 ];
property time_at2 = R{"time"}min=? [ I=HORIZON ];
"""


# One reward structure with state rewards only, one with action rewards only, one with
# both: JANI keeps them apart (location values vs edge assignments).
REWARDS = """
machine rew;
const int GAIN = [1, 2];
var n : [0..3] init 0 clamp;
var m : [0..2] init 0;
mode A = 0 initial;
mode B = 1 final;
action Step in A weight 1 {
    0.5: n += GAIN;
    0.3: m := mod(m + 1, 3);
    0.2: goto B;
}
label b = mode == B;
label odd = mod(m, 2) == 1;
rewards s { mode == A : 1; n == 3 : 0.25; }
rewards a { [Step] true : 10; [Step] m > 0 : m; }
rewards sa { mode == A : 1; [Step] true : 10; }
property s = R{"s"}=? [ C<=5 ];
property a = R{"a"}=? [ C<=5 ];
property sa = R{"sa"}=? [ C<=5 ];
property sf = R{"s"}=? [ F "b" ];
property af = R{"a"}=? [ F "b" ];
property saf = R{"sa"}=? [ F "b" || "odd" ];
property si = R{"s"}=? [ I=2 ];
property sc = R{"sa"}=? [ C ];
property odd_first = P=? [ !"b" U "odd" ];
property odd_next = P=? [ X !"odd" ];
"""


# Probabilities that are exactly 0 or 1: both routes must drop or keep the same branches.
EDGES = """
machine edges;
const prob P_ERR = 0;
const prob P_ONE = 1;
const int D = [1, 2];
var n : [0..4] init 0 clamp;
mode A = 0 initial;
mode B = 1;
mode E = 2 final;
action Step in A weight 1 {
    P_ONE: n += D;
    1 - P_ONE: goto B;
}
action Back in B weight 1 { goto A; }
hazard Err from * with probability P_ERR { goto E; }
label full = n == 4;
property f = P=? [ F "full" ];
property f2 = P=? [ F<=2 "full" ];
"""


SPECS = {"grid": GRID, "rewards": REWARDS, "edges": EDGES}


def lowered(path: str, resolution: str = "nondet", text: str | None = None,
            overrides: Mapping[str, str] | None = None) -> Lowered:
    model = load(path, overrides or {}, text=text).model
    # as `afsmc compile` does: with the exact reductions (PRISM and JANI share them)
    return compiler_lowered(model, resolution)  # type: ignore[arg-type]


def storm_prism(low: Lowered, directory: Path) -> tuple[object, list[object]]:
    out = prism.emit(low)
    path = directory / "model.prism"
    path.write_text(out.model)
    prog = stormpy.parse_prism_program(str(path))
    props = stormpy.parse_properties(" ".join(out.properties.split("\n")), prog)
    return stormpy.build_model(prog, props), props


def storm_jani(low: Lowered, directory: Path) -> tuple[object, list[object]]:
    path = directory / "model.jani"
    path.write_text(jani.dumps(jani.emit(low)), encoding="utf-8")
    model, props = stormpy.parse_jani_model(str(path))
    return stormpy.build_model(model, props), props


def value(model: object, prop: object) -> float:
    result = stormpy.model_checking(model, prop)
    return float(result.get_value(model.initial_states[0]))  # type: ignore[attr-defined]


def assert_same_as_prism(low: Lowered, directory: Path) -> None:
    pm, pprops = storm_prism(low, directory)
    jm, jprops = storm_jani(low, directory)
    assert str(jm.model_type) == str(pm.model_type)  # type: ignore[attr-defined]
    assert (jm.nr_states, jm.nr_transitions, jm.nr_choices) == (  # type: ignore[attr-defined]
        pm.nr_states, pm.nr_transitions, pm.nr_choices)  # type: ignore[attr-defined]
    names = [p.get_name() for p in pprops]  # type: ignore[attr-defined]
    assert [p.get_name() for p in jprops] == names == jani.property_names(low)  # type: ignore[attr-defined]
    assert names, "nothing compared"
    for pp, jp in zip(pprops, jprops, strict=True):
        vp, vj = value(pm, pp), value(jm, jp)
        assert math.isclose(vp, vj, rel_tol=1e-9, abs_tol=1e-9), (
            f"{pp.get_name()}: PRISM {vp!r}, JANI {vj!r}")  # type: ignore[attr-defined]


EXAMPLE_FILES = sorted(EXAMPLES.glob("*.afsm"))
# Examples whose default instance takes more than about 2 s on both routes.
SLOW_EXAMPLES = {"charging"}
EXAMPLE_PARAMS = [pytest.param(p, id=p.stem, marks=[pytest.mark.slow] if p.stem in SLOW_EXAMPLES
                               else []) for p in EXAMPLE_FILES]


@pytest.mark.storm
@pytest.mark.parametrize("resolution", ["nondet", "uniform"])
@pytest.mark.parametrize("path", EXAMPLE_PARAMS)
def test_examples_agree_with_prism(path: Path, resolution: str, tmp_path: Path) -> None:
    low = lowered(str(path), resolution, overrides=OVERRIDES.get(path.stem, {}))
    assert_same_as_prism(low, tmp_path)


@pytest.mark.storm
@pytest.mark.parametrize("resolution", RESOLUTIONS)
@pytest.mark.parametrize("name", sorted(SPECS))
def test_specs_agree_with_prism(name: str, resolution: str, tmp_path: Path) -> None:
    low = lowered(f"{name}.afsm", resolution, text=SPECS[name])
    assert low.kind == ("mdp" if resolution == "nondet" else "dtmc")
    assert_same_as_prism(low, tmp_path)


def test_structure_follows_the_ir() -> None:
    low = lowered("grid.afsm", "nondet", text=GRID)
    model = jani.emit(low)
    assert model["jani-version"] == 1 and model["type"] == "mdp"
    [automaton] = model["automata"]
    assert len(automaton["edges"]) == len(low.commands)
    # the final modes' self-loops are silent, every other edge carries its action
    silent = [e for e in automaton["edges"] if "action" not in e]
    assert len(silent) == sum(c.kind == "final" for c in low.commands) == 2
    variables = {v["name"]: v for v in model["variables"]}
    assert variables["mode"]["type"]["upper-bound"] == 3
    assert variables["pos_x"]["type"] == {"kind": "bounded", "base": "int", "lower-bound": 0,
                                         "upper-bound": 3}
    assert variables["carrying"] == {**variables["carrying"], "type": "bool",
                                     "initial-value": False}
    for label in ("home", "crashed", "far_out"):
        assert variables[label]["transient"] is True and variables[label]["type"] == "bool"
    for reward in ("fuel_used", "time"):
        assert variables[reward]["transient"] is True and variables[reward]["type"] == "real"
    constants = {c["name"]: c["value"] for c in model["constants"]}
    assert {k: constants[k] for k in low.bounds} == {k: v for k, (_, v) in low.bounds.items()}
    assert "STEP" not in constants  # interval constants live on as their generated bounds
    names = [p["name"] for p in model["properties"]]
    assert names == jani.property_names(low) == list(prism.emit(low).property_names)
    assert "home_min" in names and "home_max" in names and "home_soon" in names


@pytest.mark.storm
def test_name_clashes_get_fresh_names(tmp_path: Path) -> None:
    # JANI has one namespace: a label or reward named like a variable must be renamed
    text = """
    machine clash;
    var n : [0..2] init 0;
    mode A = 0 initial;
    action Up in A weight 1 { 0.5: n := min(n + 1, 2); 0.5: skip; }
    label n_top = n == 2;
    rewards n { [Up] true : 1; }
    property p = P=? [ F "n_top" ];
    property r = R{"n"}=? [ C<=3 ];
    """
    low = lowered("clash.afsm", "nondet", text=text)
    names = [v["name"] for v in jani.emit(low)["variables"]]
    assert len(names) == len(set(names)) and "n_" in names
    assert_same_as_prism(low, tmp_path)


@pytest.mark.storm
def test_bounded_globally_is_written_as_its_dual(tmp_path: Path) -> None:
    # Storm's JANI has no bounded G: the file holds P [F<=k !φ] (min and max swapped) under
    # NAME_complement, and W401 says so. Oracle: the dual written by hand, checked by Storm
    # from the PRISM file (whose reader has no bounded G either).
    text = GRID + 'property safe3 = P=? [ G<=3 !"crashed" ];\n' \
        'property hand = P=? [ F<=3 "crashed" ];\n' \
        'property safe3_min_complement = Pmax=? [ G !"crashed" ];\n'  # takes the first name
    low = lowered("grid.afsm", "nondet", text=text)
    by_name = {p.name: p for p in low.model.properties}
    props = tuple(by_name[n] for n in ("safe3", "hand", "safe3_min_complement"))
    low = replace(low, model=replace(low.model, properties=props))
    [note] = jani.notes(low)
    assert note.code == "W401" and note.span == by_name["safe3"].span
    assert "safe3_min = 1 - safe3_min_complement_, safe3_max = 1 - safe3_max_complement" \
        in note.message, note.message
    jm, jprops = storm_jani(low, tmp_path)
    jnames = [p.get_name() for p in jprops]  # type: ignore[attr-defined]
    assert jnames == jani.property_names(low) == [
        "safe3_min_complement_", "safe3_max_complement", "hand_min", "hand_max",
        "safe3_min_complement"]
    jvalues = dict(zip(jnames, (value(jm, p) for p in jprops), strict=True))
    pm, pprops = storm_prism(replace(low, model=replace(low.model, properties=props[1:2])),
                             tmp_path)
    hand = {p.get_name(): value(pm, p) for p in pprops}  # type: ignore[attr-defined]
    assert 0 < hand["hand_min"] < hand["hand_max"] < 1, hand
    assert jvalues["safe3_min_complement_"] == pytest.approx(hand["hand_max"], abs=1e-12)
    assert jvalues["safe3_max_complement"] == pytest.approx(hand["hand_min"], abs=1e-12)
    assert "1 - this value is safe3_min " in jani.dumps(jani.emit(low))


@pytest.mark.storm
def test_next_via_jani_on_a_symbolic_engine_says_to_use_prism(tmp_path: Path) -> None:
    # JANI writes X as a one-step bounded until, which only Storm's sparse engine takes.
    model = tmp_path / "nx.afsm"
    model.write_text("machine nx;\nvar x : [0..3] init 0;\nmode A = 0 initial;\n"
                     "mode B = 1 final;\n"
                     "action Go in A when x < 3 { 0.3: x := x + 1; 0.7: goto B; }\n"
                     "action Stop in A when x >= 3 { goto B; }\n"
                     "property nxt = P=? [ X x == 1 ];\n", encoding="utf-8")
    r = run_cli("verify", str(model), "--engine", "hybrid", "--via", "jani")
    assert r.code == 1 and "E404" in r.err and "use --via prism or --engine sparse" in r.err
    for argv in (["--engine", "hybrid"], ["--via", "jani"]):
        ok = run_cli("verify", str(model), *argv, "--json")
        assert ok.code == 0, ok.err
        assert json.loads(ok.out)["properties"][0]["value"] == pytest.approx(0.3)


NEVER_ASSIGNED = """machine cv;
var cfg : [0..2] init 1;
var n : [0..3] init 0;
mode A = 0 initial;
mode E = 1 final;
action Go in A when n < 3 { 0.5: n := n + 1; 0.5: skip; }
action Fin in A when n == 3 { goto E; }
rewards r { cfg == 1 : 1; }
property g  = P=? [ G cfg == 1 ];
property f  = P=? [ F mode == E && cfg == 1 ];
property rf = R{"r"}=? [ F cfg == 1 ];
"""


ONE_MODE = """machine fi;
var x : [0..2] init 1;
mode A = 0 initial final;
rewards r { x == 1 : 2; }
property c = R{"r"}=? [ C<=5 ];
property i = R{"r"}=? [ I=3 ];
property g = P=? [ G x == 1 ];
"""


@pytest.mark.storm
@pytest.mark.parametrize("text", [NEVER_ASSIGNED, ONE_MODE], ids=["never-assigned", "one-mode"])
def test_variables_that_never_change_give_the_same_values_via_jani(
        text: str, tmp_path: Path) -> None:
    # Storm's JANI builder drops a variable that no edge assigns and then evaluated `G cfg == 1`
    # as 0 (and the reward as infinite); afsmc writes such variables as JANI constants.
    path = tmp_path / "m.afsm"
    path.write_text(text, encoding="utf-8")
    got = {}
    for via in ("prism", "jani"):
        r = run_cli("verify", str(path), "--via", via, "--engine", "sparse", "--json")
        assert r.code == 0, r.err
        got[via] = {p["name"]: p["value"] for p in json.loads(r.out)["properties"]}
    assert got["jani"] == pytest.approx(got["prism"])
    assert got["jani"]["g"] == 1.0, got  # the variable keeps its initial value by construction


@pytest.mark.storm
def test_a_model_whose_variables_never_change_is_refused_by_the_symbolic_engines(
        tmp_path: Path) -> None:
    # Storm's symbolic build counts no state for it, and its hybrid engine then died with a
    # segmentation fault on C<=k and I=k (exit 139, no diagnostic).
    path = tmp_path / "m.afsm"
    path.write_text(ONE_MODE, encoding="utf-8")
    for engine in ("hybrid", "dd"):
        r = run_cli("verify", str(path), "--engine", engine, "-p", "c")
        assert r.code == 1 and "error[E403]" in r.err and "no states" in r.err, r.err
        assert "--engine sparse" in r.err
