"""`--witness`, `--strategy` and the diagram's overlays where features meet (issue 44): an
until's paths, a value of 0 (no path, and why; never a Storm crash), the strategies and
paths of composed missions whose agents' turns are a choice, composed diagrams, and the
steps without the reductions' dead-variable resets.

Oracles: the values of the same run without the option, paths enumerated by brute force
on hand-written transition systems, the model checked without the reductions, and
strategies derived by hand."""

from __future__ import annotations

import argparse
import json
import math
from collections.abc import Callable
from pathlib import Path
from typing import Any

import pytest

from afsmc.api.diagram import reach_modes, span_text
from afsmc.backends.dot import diagram
from afsmc.commands.render import diagram_strategy
from afsmc.compiler import load
from afsmc.lower.reduce import Reductions
from afsmc.verify.core.api import run
from afsmc.verify.outcome.results import PropertyResult
from afsmc.verify.outcome.witness import Witness
from tests.conftest import EXAMPLES, run_cli

pytestmark = pytest.mark.storm

PATROL = str(EXAMPLES / "patrol.afsm")

# Two agents that each work once, taking 1 or 2 ticks, and end Done or Broken: the
# clocks decide who moves (ties: a first). `F a.t == 1` has min 0 (T_WORK's ceiling).
PAIR = """
machine pair;
compose timed ties order;

const int T_WORK = [1, 2];
const prob P_OK  = 0.9;

agent a clock t {
    var t : [0..4] init 0 clamp;
    mode Idle   = 0 initial;
    mode Done   = 1 final;
    mode Broken = 2 final;
    action Work in Idle {
        P_OK:     goto Done, t += T_WORK;
        1 - P_OK: goto Broken, t += T_WORK;
    }
}

agent b clock t {
    var t : [0..4] init 0 clamp;
    mode Idle   = 0 initial;
    mode Done   = 1 final;
    mode Broken = 2 final;
    action Work in Idle {
        P_OK:     goto Done, t += T_WORK;
        1 - P_OK: goto Broken, t += T_WORK;
    }
}

label both = a.mode == Done && b.mode == Done;
property both      = P>=0.5 [ F "both" ];
property both_done = P=? [ F "both" ];
"""

# Whoever moves first sets `first`: the order is the scheduler's, and no interval
# constant. By hand: max P(F first == 1) = 1 (a first), min = 0 (b first), decided in
# the initial state only.
RACE = """
machine race;
compose interleaving;

var first : [0..2] init 0 written by a, b;

agent a {
    mode Idle = 0 initial;
    mode Done = 1 final;
    action Go in Idle {
        first := first == 0 ? 1 : first, goto Done;
    }
}

agent b {
    mode Idle = 0 initial;
    mode Done = 1 final;
    action Go in Idle {
        first := first == 0 ? 2 : first, goto Done;
    }
}

label a_first = first == 1;
property a_first = P=? [ F "a_first" ];
"""

# A DTMC whose paths into Goal may loop through Detour; the until forbids Detour. `n` is
# dead in Goal (the reductions reset it there).
DETOUR = """
machine detour;

var n : [0..3] init 0;

mode Start  = 0 initial;
mode Detour = 1;
mode Goal   = 2 final;
mode Fail   = 3 final;

action Step in Start when n < 3 {
    0.6: goto Detour;
    0.3: n += 1;
    0.1: goto Goal;
}
action Finish in Start when n == 3 {
    goto Goal;
}
action Back in Detour {
    0.5: goto Start;
    0.5: goto Fail;
}

label goal = mode == Goal;
property until = P=? [ mode != Detour U "goal" ];
property reach = P=? [ F "goal" ];
"""

State = tuple[str, int]  # DETOUR's (mode, n)


def _detour(s: State) -> list[tuple[float, str, State]]:
    """DETOUR's transitions, written out by hand: (probability, action, successor)."""
    mode, n = s
    if mode == "Start" and n < 3:
        return [(0.6, "Step", ("Detour", n)), (0.3, "Step", ("Start", n + 1)),
                (0.1, "Step", ("Goal", n))]
    if mode == "Start":
        return [(1.0, "Finish", ("Goal", n))]
    if mode == "Detour":
        return [(0.5, "Back", ("Start", n)), (0.5, "Back", ("Fail", n))]
    return []


Path_ = tuple[float, tuple[tuple[str, tuple[tuple[str, object], ...]], ...]]


def _brute_force(allowed: Callable[[State], bool], depth: int) -> list[Path_]:
    """Every path of DETOUR from (Start, 0) into Goal, stopping there, through `allowed`
    states only, of at most `depth` steps: (probability, ((action, what changed), ...)),
    most probable first. What changed is the mission's: `n` only where a step sets it."""
    out: list[Path_] = []

    def walk(s: State, p: float, steps: tuple[tuple[str, tuple[tuple[str, object], ...]], ...]
             ) -> None:
        if s[0] == "Goal":
            out.append((p, steps))
            return
        if len(steps) == depth or not allowed(s):
            return
        for q, action, t in _detour(s):
            changes = tuple(c for c in (("mode", t[0]) if t[0] != s[0] else None,
                                        ("n", t[1]) if t[1] != s[1] else None) if c)
            walk(t, p * q, (*steps, (action, changes)))
    walk(("Start", 0), 1.0, ())
    return sorted(out, key=lambda x: -x[0])


def _paths(p: PropertyResult) -> list[Path_]:
    assert p.witnesses is not None
    return [(w.probability, tuple((s.action, tuple(s.changes.items())) for s in w.steps))
            for w in p.witnesses]


def _same(got: list[Path_], want: list[Path_]) -> None:
    """The same paths in the same order (of distinct probabilities)."""
    assert len(got) == len(want)
    for (p, steps), (q, wsteps) in zip(got, want, strict=True):
        assert p == pytest.approx(q, rel=1e-12)
        assert steps == wsteps


def _file(tmp_path: Path, name: str, text: str) -> str:
    path = tmp_path / f"{name}.afsm"
    path.write_text(text)
    return str(path)


# ---- an until's paths ------------------------------------------------------------------


def test_until_witness_on_patrol_keeps_both_values_and_says_why_there_is_no_path() -> None:
    """The reproducer: E404 from a partial scheduler lost both MDP values."""
    formula = 'P>=0.5 ["halted" U "done"]'
    plain = run(PATROL, formulas=[formula], uniform=False).properties[0]
    got = run(PATROL, formulas=[formula], witness=(None, 2), uniform=False).properties[0]
    assert (got.min, got.max) == (plain.min, plain.max) == (0.0, 0.0)
    assert got.verdict == plain.verdict
    # the requirement's violations follow the min: missed from the start
    assert got.witnesses is not None and len(got.witnesses) == 1
    assert got.witnesses[0].probability == 1.0 and got.witnesses[0].steps == ()
    assert "min is 0" in got.witness_note
    top = run(PATROL, formulas=[formula], witness=(None, 2), witness_dir="max",
              uniform=False).properties[0]
    assert top.witnesses == [] and top.max == 0.0
    assert top.witness_note == "the max is 0: no path satisfies the until under the max strategy"
    r = run_cli("verify", PATROL, "-f", formula, "--witness", "2")
    assert r.code == 1 and "E404" not in r.err, r.err  # 1: the requirement fails
    assert "the min is 0" in r.out


def test_until_paths_are_those_of_brute_force_enumeration(tmp_path: Path) -> None:
    spec = _file(tmp_path, "detour", DETOUR)
    p = run(spec, properties=["until"], witness=("until", 5)).property("until")
    want = _brute_force(lambda s: s[0] != "Detour", depth=10)
    assert p.value == pytest.approx(math.fsum(q for q, _ in want), rel=1e-9)
    assert len(want) == 4  # the until allows four paths: the fifth asked is not there
    _same(_paths(p), want)
    assert p.witness_note == "there are only 4 paths into the target states"
    assert all(w.confirmed for w in p.witnesses or [])


def test_reach_paths_with_loops_are_those_of_brute_force_enumeration(tmp_path: Path) -> None:
    spec = _file(tmp_path, "detour", DETOUR)
    p = run(spec, properties=["reach"], witness=("reach", 4)).property("reach")
    # loops through Detour lose a factor 0.3 each: 14 steps hold every path above 0.009
    want = _brute_force(lambda s: True, depth=14)[:5]
    assert want[3][0] > want[4][0]  # the fourth is not tied with the fifth
    got = _paths(p)
    assert [q for q, _ in got] == pytest.approx([q for q, _ in want[:4]], rel=1e-12)
    # the two paths of 0.03 may come in either order
    assert sorted(map(str, got)) == sorted(map(str, want[:4]))


# ---- a value of 0 ----------------------------------------------------------------------


@pytest.mark.parametrize("compose", ["timed ties order", "timed ties nondet", "interleaving"])
def test_min_zero_requirement_witness_keeps_the_value(tmp_path: Path, compose: str) -> None:
    """With the initial state among the target states, Storm's paths generator crashed
    (signal 11, E406) at the second path: the value was lost."""
    spec = _file(tmp_path, "pair", PAIR.replace("timed ties order", compose))
    formula = "P>=0.5 [ F a.t == 1 ]"
    plain = run(spec, formulas=[formula], uniform=False).properties[0]
    got = run(spec, formulas=[formula], witness=(None, 3), uniform=False).properties[0]
    assert (got.min, got.max, got.verdict) == (plain.min, plain.max, plain.verdict)
    assert got.min == 0.0 and got.max == 1.0
    assert got.witnesses is not None and len(got.witnesses) == 1
    assert got.witnesses[0].steps == () and got.witnesses[0].probability == 1.0
    assert got.witness_note.startswith("the min is 0: ")
    r = run_cli("verify", spec, "-f", formula, "--witness", "3", "--json")
    assert r.code == 1 and "E406" not in r.err, r.err
    (js,) = json.loads(r.out)["properties"]
    assert (js["min"], js["max"]) == (0.0, 1.0) and "min is 0" in js["witness_note"]


def test_no_path_when_the_value_is_zero_says_so(tmp_path: Path) -> None:
    spec = _file(tmp_path, "race", RACE)
    p = run(spec, witness=("a_first", 2), witness_dir="min").property("a_first")
    assert p.min == 0.0 and p.witnesses == []
    assert p.witness_note == "the min is 0: no path reaches a target state under the min strategy"
    r = run_cli("verify", spec, "--witness", "2", "--witness-dir", "min")
    assert r.code == 0, r.err
    assert "no paths of a_first" in r.out and "the min is 0" in r.out


# ---- composed missions whose turns are a choice -----------------------------------------


def test_interleaving_without_intervals_has_strategies_of_turns(tmp_path: Path) -> None:
    """It was refused with E415 ("its model is a DTMC") though it is an MDP."""
    spec = _file(tmp_path, "race", RACE)
    plain = run(spec).property("a_first")
    got = run(spec, strategy=True).property("a_first")
    assert (got.min, got.max) == (plain.min, plain.max) == (0.0, 1.0)
    assert got.turns is not None
    assert [(t.action, t.states, t.agents, t.local) for t in got.turns["min"]] == [
        ("b: Go", 1, ("b",), "Go")]
    assert [(t.action, t.states, t.agents, t.local) for t in got.turns["max"]] == [
        ("a: Go", 1, ("a",), "Go")]
    r = run_cli("verify", spec, "--strategy")
    assert r.code == 0, r.err
    assert "turns of a_first" in r.out and "step-bounded" not in r.out
    assert "no choice" not in r.out  # no floor/ceil table: there is no interval constant
    js = json.loads(run_cli("verify", spec, "--strategy", "--json").out)["properties"][0]
    assert js["turns"] == {"min": [{"action": "b: Go", "mode": "b: Idle", "states": 1}],
                           "max": [{"action": "a: Go", "mode": "a: Idle", "states": 1}]}
    assert js["strategy"] == {"min": [], "max": []}
    w = run(spec, witness=("a_first", 2)).property("a_first")
    assert w.witnesses is not None and len(w.witnesses) == 1
    (step,) = w.witnesses[0].steps
    assert (step.action, step.probability, step.changes) == (
        "a: Go", 1.0, {"a.mode": "Done", "first": 1})


@pytest.mark.parametrize("direction,mover,still", [("max", "a", "b"), ("min", "b", "a")])
def test_diagram_strategy_on_an_interleaving_marks_the_agent_moved(
        tmp_path: Path, direction: str, mover: str, still: str) -> None:
    spec = _file(tmp_path, "race", RACE)
    out = tmp_path / "race.svg"
    r = run_cli("diagram", spec, "--strategy", f"{direction}:a_first", "-o", str(out))
    assert r.code == 0, r.err
    assert "moved: 1 states" in out.read_text()
    model = load(spec).model
    args = argparse.Namespace(file=spec, const=[], strategy=f"{direction}:a_first",
                              witness=None)
    drawn, notes = diagram_strategy.overlay(args, model)
    assert drawn.agents[mover].moved == {"Go": 1} and drawn.agents[still].moved == {}
    assert notes[0] == f"{direction} strategy of a_first: {1 if direction == 'max' else 0}"


# ---- composed diagrams -----------------------------------------------------------------


def test_diagram_witness_on_a_composed_mission_draws_each_agent_s_steps(
        tmp_path: Path) -> None:
    """It was an internal error (KeyError on the mission's modes, exit 3)."""
    spec = _file(tmp_path, "pair", PAIR)
    out = tmp_path / "pair.svg"
    r = run_cli("diagram", spec, "--witness", "max:both_done", "-o", str(out))
    assert r.code == 0, r.err
    model = load(spec).model
    args = argparse.Namespace(file=spec, const=[], strategy=None, witness="max:both_done")
    drawn, notes = diagram_strategy.overlay(args, model)
    # the path: a works first (ties order), then b; each into Done
    w = run(spec, properties=["both_done"], witness=("both_done", 1), witness_dir="max",
            uniform=False).property("both_done")
    assert w.witnesses is not None
    assert [s.action for s in w.witnesses[0].steps] == ["a: Work", "b: Work"]
    assert list(drawn.agents["a"].path) == [(0, 1, "Work"), diagram_strategy.NOWHERE]
    assert list(drawn.agents["b"].path) == [diagram_strategy.NOWHERE, (0, 1, "Work")]
    assert notes == [f"most probable path of both_done: {w.witnesses[0].probability:g}, "
                     f"2 steps, following the max strategy (max {w.max:g})"]
    dot = diagram(model, drawn).source
    assert "a_m0 -> a_m1" in dot and "step 1" in dot and "step 2" in dot


def test_diagram_reach_on_a_composed_mission_gives_each_agent_s_modes(
        tmp_path: Path) -> None:
    """It was E612: `F mode=N` of a `mode` variable a composed mission does not have."""
    spec = _file(tmp_path, "pair", PAIR)
    model = load(spec).model
    got = reach_modes(model, "nondet")
    for agent in ("a", "b"):
        for mode, number in (("Idle", 0), ("Done", 1), ("Broken", 2)):
            # the oracle: verify's own check of the same event
            r = run(spec, formulas=[f"P=? [ F {agent}.mode == {mode} ]"],
                    uniform=False).properties[0]
            assert got.agents[agent].modes[number] == f"P(reach) {span_text(r.min, r.max)}"
    assert got.caption.endswith("min – max over interval choices")
    r2 = run_cli("diagram", spec, "--reach", "-o", str(tmp_path / "pair.svg"))
    assert r2.code == 0, r2.err
    assert "P(reach) 0.9" in (tmp_path / "pair.svg").read_text()


# ---- what a step shows ------------------------------------------------------------------


def _steps(ws: list[Witness] | None) -> list[tuple[float, list[dict[str, object]]]]:
    assert ws is not None
    return sorted(((w.probability, [dict(s.changes) for s in w.steps]) for w in ws),
                  key=lambda x: (-x[0], str(x[1])))


@pytest.mark.parametrize("spec,formula,k", [
    (PATROL, 'P>=0.5 [!"halted" U "done"]', 3),
    (None, 'P=? [ F "both" ]', 2),
])
def test_steps_show_what_the_mission_did_not_the_reductions_resets(
        tmp_path: Path, spec: str | None, formula: str, k: int) -> None:
    """Oracle: the same paths in the model checked without the reductions."""
    path = spec or _file(tmp_path, "pair", PAIR)
    reduced = run(path, formulas=[formula], witness=(None, k), uniform=False).properties[0]
    whole = run(path, formulas=[formula], witness=(None, k), uniform=False,
                reductions=Reductions.none()).properties[0]
    assert _steps(reduced.witnesses) == _steps(whole.witnesses)


def test_patrol_fault_step_changes_only_the_mode() -> None:
    p = run(PATROL, formulas=['P>=0.5 [!"halted" U "done"]'], witness=(None, 2),
            uniform=False).properties[0]
    assert p.witnesses is not None
    last = p.witnesses[1].steps[-1]
    # before: `mode=Halted cell=0 battery=20`, the reductions' resets as if the robot did them
    assert (last.hazard, last.changes) == ("Fault", {"mode": "Halted"})
    trace = p.witnesses[1].trace("Patrol")
    assert trace[-1]["vars"]["battery"] == 19 and trace[-1]["vars"]["cell"] == 1


def test_detour_steps_into_goal_keep_n(tmp_path: Path) -> None:
    spec = _file(tmp_path, "detour", DETOUR)
    p = run(spec, properties=["until"], witness=("until", 2)).property("until")
    assert p.witnesses is not None
    steps = p.witnesses[1].steps
    assert [dict(s.changes) for s in steps] == [{"n": 1}, {"mode": "Goal"}]
    assert [s.probability for s in steps] == pytest.approx([0.3, 0.1])


# ---- over rationals ---------------------------------------------------------------------


def test_exact_strategies_and_paths_keep_the_exact_values() -> None:
    """`--exact` built the model without state valuations: Storm's "bad optional access"
    lost the MDP's values."""
    plain = run(PATROL, properties=["finish"], exact=True, uniform=False).property("finish")
    got = run(PATROL, properties=["finish"], exact=True, uniform=False, strategy=True,
              witness=("finish", 2)).property("finish")
    assert got.exact == plain.exact and set(got.exact) == {"min", "max"}
    assert (got.min, got.max) == (plain.min, plain.max)
    assert got.strategy is not None and got.strategy["max"]
    assert got.witnesses is not None and len(got.witnesses) == 2
    for w in got.witnesses:
        assert w.confirmed
        assert w.probability == pytest.approx(math.prod(s.probability for s in w.steps),
                                              rel=1e-12)
    # the float run's paths: the same probabilities (the max strategy ties nowhere here)
    floats = run(PATROL, properties=["finish"], uniform=False,
                 witness=("finish", 2)).property("finish")
    assert floats.witnesses is not None
    assert [w.probability for w in got.witnesses] == pytest.approx(
        [w.probability for w in floats.witnesses], rel=1e-12)


def test_exact_until_witness_finds_the_initial_state_missed() -> None:
    formula = 'P>=0.5 ["halted" U "done"]'
    got = run(PATROL, formulas=[formula], exact=True, witness=(None, 2),
              uniform=False).properties[0]
    assert (got.min, got.max) == (0.0, 0.0)
    assert got.witnesses is not None and got.witnesses[0].steps == ()
    assert "min is 0" in got.witness_note


@pytest.mark.parametrize("options", [{"solver": "topological"}, {"exact": True}])
def test_no_crash_asking_for_more_paths_than_there_are(tmp_path: Path,
                                                       options: dict[str, Any]) -> None:
    """On Storm's route, its paths generator crashed (signal 11) asking for a path beyond
    the last where a target state (here `first == 1` with b still to move) leads on to
    another: its targets are now those a path reaches first."""
    spec = _file(tmp_path, "race", RACE)
    plain = run(spec, **options).property("a_first")
    got = run(spec, witness=("a_first", 3), **options).property("a_first")
    assert (got.min, got.max) == (plain.min, plain.max) == (0.0, 1.0)
    assert got.witnesses is not None and len(got.witnesses) == 1
    assert [s.action for s in got.witnesses[0].steps] == ["a: Go"]
    assert got.witness_note == "there are only 1 paths into the target states"


def test_mission_diagram_with_reach_on_a_composed_mission(tmp_path: Path) -> None:
    """The Python API's `Mission.diagram(reach=True)`, as `diagram --reach`."""
    import afsmc

    spec = _file(tmp_path, "race", RACE)
    dot = afsmc.load(spec).diagram(reach=True).source
    # each agent reaches Done surely; whoever moves first is the scheduler's choice
    assert dot.count("P(reach) 1") == 4  # a's and b's Idle and Done
    assert "min – max over the agents' turns" in dot
