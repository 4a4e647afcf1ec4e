"""`afsmc verify --strategy / --witness K / --traces-out` and `afsmc simulate --strategy`
on the command line: the outputs, the replay of Storm's strategies in the simulator
(its confidence interval contains Storm's min and max), and bad input (a code, never a
traceback)."""

from __future__ import annotations

import json
import math
from pathlib import Path

import pytest

from afsmc.compiler import load
from afsmc.diagnostics import CompileError
from afsmc.verify.core.policy import extract
from tests.conftest import EXAMPLES, run_cli

pytestmark = pytest.mark.storm

PATROL = str(EXAMPLES / "patrol.afsm")
UAV = str(EXAMPLES / "uav.afsm")

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
property soon = P=? [ F "done" ];
"""


def test_json_has_strategies_and_witnesses(tmp_path: Path) -> None:
    traces = tmp_path / "paths.json"
    r = run_cli("verify", PATROL, "-p", "finish", "--strategy", "--witness", "3", "--json",
                "--traces-out", str(traces))
    assert r.code == 0, r.err
    (p,) = json.loads(r.out)["properties"]
    assert set(p["strategy"]) == {"min", "max"}
    for entry in p["strategy"]["min"] + p["strategy"]["max"]:
        assert {"constant", "end", "action", "mode", "states"} <= set(entry)
        assert entry["end"] in ("floor", "ceil")
    ws = p["witnesses"]
    assert len(ws) == 3 and p["witness_strategy"] == "max"
    for w in ws:
        assert w["probability"] == pytest.approx(math.prod(s["probability"]
                                                           for s in w["steps"]))
        assert all({"mode", "action", "probability", "changes"} <= set(s) for s in w["steps"])
    assert sum(w["probability"] for w in ws) <= p["max"]
    # the format `simulate --traces-out` writes: a list of runs of {step, mode, vars, ...}
    sim = tmp_path / "sim.json"
    assert run_cli("simulate", PATROL, "--runs", "2", "--traces", "1", "--traces-out",
                   str(sim)).code == 0
    ours, theirs = json.loads(traces.read_text()), json.loads(sim.read_text())
    assert len(ours) == 3
    assert set(ours[0][0]) == set(theirs[0][0]) and set(ours[0][1]) <= set(theirs[0][1]) | {
        "hazard"}
    assert [s["step"] for s in ours[0]] == list(range(len(ours[0])))
    assert ours[0][-1]["mode"] == "Finished"


def test_text_shows_the_table_and_the_paths() -> None:
    r = run_cli("verify", PATROL, "-p", "finish", "--strategy", "--witness", "2",
                "--witness-dir", "min")
    assert r.code == 0, r.err
    assert "MOVE_COST" in r.out and "(ceil)" in r.out and "Patrol" in r.out
    assert "the 2 most probable paths of finish" in r.out and "following the min" in r.out
    assert "% of min 0.810218" in r.out
    assert "step-bounded" not in r.out  # finish is not: its table is all there is
    r = run_cli("verify", PATROL, "-p", "finish_soon", "-p", "finish", "--strategy")
    assert r.code == 0, r.err
    assert r.out.count("step-bounded") == 1 and "strategies of finish_soon" in r.out


@pytest.mark.parametrize(("argv", "code"), [
    (["-p", "nope", "--witness", "3"], "E407"),
    (["--witness", "2"], "E415"),  # six properties: which one?
    (["-p", "charges", "--witness", "2"], "E415"),  # an expected reward: no target
])
def test_bad_witness_requests_are_errors_with_a_code(argv: list[str], code: str) -> None:
    r = run_cli("verify", PATROL, *argv)
    assert r.code == 1 and f"error[{code}]" in r.err, r.err
    assert "Traceback" not in r.err


@pytest.mark.parametrize("k", ["0", "-2"])
def test_a_witness_count_below_one_is_a_usage_error(k: str) -> None:
    r = run_cli("verify", PATROL, "-p", "finish", "--witness", k)
    assert r.code == 2 and "--witness: expected an integer from 1 to 1,000" in r.err, r.err


def test_a_dtmc_has_no_strategy(tmp_path: Path) -> None:
    geo = tmp_path / "geo.afsm"
    geo.write_text(GEO)
    for argv in (["--strategy"], ["--witness", "2", "--witness-dir", "max"]):
        r = run_cli("verify", str(geo), *argv)
        assert r.code == 1 and "error[E415]" in r.err and "DTMC" in r.err, r.err
    r = run_cli("simulate", str(geo), "--strategy", "min:soon", "--runs", "10")
    assert r.code == 1 and "error[E415]" in r.err, r.err
    # a DTMC's paths need no strategy
    r = run_cli("verify", str(geo), "--witness", "2", "--json")
    assert r.code == 0, r.err
    ws = json.loads(r.out)["properties"][0]["witnesses"]
    assert [w["probability"] for w in ws] == pytest.approx([0.3, 0.21])


def test_bad_simulate_strategies_are_errors_with_a_code() -> None:
    for text, code in (("mid:finish", "E415"), ("min:", "E415"), ("min:nope", "E407")):
        r = run_cli("simulate", PATROL, "--strategy", text, "--runs", "10")
        assert r.code == 1 and f"error[{code}]" in r.err, (text, r.err)
        assert "Traceback" not in r.err
    r = run_cli("simulate", PATROL, "--strategy", "min:finish", "--resolve", "lo")
    assert r.code == 2


def test_a_sparse_check_that_fails_is_e416() -> None:
    model = load(PATROL).model
    with pytest.raises(CompileError) as err:
        extract(model, "min:finish", max_states=2)
    assert err.value.diagnostics[0].code == "E416"


def _replay(path: str, text: str, runs: int, *consts: str) -> tuple[float, float, float]:
    r = run_cli("simulate", path, "--strategy", text, "--runs", str(runs), "--json", *consts)
    assert r.code == 0, r.err
    data = json.loads(r.out)
    name = text.split(":")[1]
    est = next(p for p in data["properties"] if p["name"] == name)
    return data["strategy"]["value"], est["low"], est["high"]


@pytest.mark.slow
def test_patrol_replay_contains_storm_s_min_and_max() -> None:
    verified = json.loads(run_cli("verify", PATROL, "-p", "finish", "--json").out)
    storm = verified["properties"][0]
    got = {}
    for direction in ("min", "max"):
        value, low, high = got[direction] = _replay(PATROL, f"{direction}:finish", 60_000)
        # the unreduced MDP against the reduced: equal up to value iteration's error (1e-8)
        assert value == pytest.approx(storm[direction], abs=1e-7)
        assert low <= value <= high, (direction, value, low, high)
    # the two strategies are told apart: their intervals do not meet
    assert got["min"][2] < got["max"][1]


@pytest.mark.slow
def test_uav_default_replay_contains_storm_s_min_and_max() -> None:
    for direction in ("min", "max"):
        value, low, high = _replay(UAV, f"{direction}:success_by", 20_000)
        assert low <= value <= high, (direction, value, low, high)


def test_diagram_draws_the_strategy_s_ends_and_the_path(tmp_path: Path) -> None:
    out = tmp_path / "p.svg"
    r = run_cli("diagram", PATROL, "--strategy", "min:finish", "--witness", "finish",
                "-o", str(out))
    assert r.code == 0, r.err
    svg = out.read_text()
    assert "[ceil]" in svg or "[floor+ceil]" in svg  # Move, where the end matters
    assert "step 1" in svg and "most probable path of finish" in svg
    r = run_cli("diagram", PATROL, "--strategy", "mid:finish", "-o", str(out))
    assert r.code == 1 and "E415" in r.err


def test_step_bounded_properties(tmp_path: Path) -> None:
    """A DTMC's bounded paths stop at the bound; an MDP's step-bounded property has no
    (memoryless) scheduler: no strategy row, and a witness or replay of it is E415."""
    geo = tmp_path / "geo.afsm"
    geo.write_text(GEO.replace('F "done"', 'F<=2 "done"'))
    r = run_cli("verify", str(geo), "--witness", "5", "--json")
    assert r.code == 0, r.err
    p = json.loads(r.out)["properties"][0]
    assert [w["probability"] for w in p["witnesses"]] == pytest.approx([0.3, 0.21])
    assert sum(w["probability"] for w in p["witnesses"]) == pytest.approx(p["value"])
    r = run_cli("verify", PATROL, "-p", "finish_soon", "-p", "finish", "--strategy", "--json")
    assert r.code == 0, r.err
    soon, finish = json.loads(r.out)["properties"]
    assert "strategy" not in soon and finish["strategy"]["max"]
    for argv in (["verify", PATROL, "-p", "finish_soon", "--witness", "2"],
                 ["simulate", PATROL, "--strategy", "max:finish_soon", "--runs", "10"]):
        r = run_cli(*argv)
        assert r.code == 1 and "error[E415]" in r.err and "step-bounded" in r.err, r.err
