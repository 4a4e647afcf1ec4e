"""`afsmc simulate` on composed missions whose agents interleave (or tie): the uniform
scheduler over the agents that can move is one scheduler of the MDP, so its Monte Carlo
interval meets verify's [min, max]; `--strategy min:NAME|max:NAME` replays Storm's
scheduler (who moves included), so the interval contains Storm's min or max."""

from __future__ import annotations

import json
import os
import subprocess
import sys

import pytest

from afsmc.api.simulate import simulate_file
from afsmc.sim.scheduler import UNIFORM
from afsmc.verify.core.api import run
from tests.conftest import ROOT

HERE = os.path.dirname(__file__)
PAIR = os.path.join(HERE, "charge_pair.afsm")
TWO_UAV = os.path.join(ROOT, "examples", "two_uav.afsm")
SMALL = {"OBJECTS": "1", "T_LIMIT": "25"}

pytestmark = pytest.mark.storm


def _read(path: str) -> str:
    with open(path, encoding="utf-8") as f:
        return f.read()


def _two_uav(compose: str) -> str:
    return _read(TWO_UAV).replace("compose timed ties order;", compose)


def _overlap(path: str, text: str, consts: dict[str, str], runs: int) -> None:
    pytest.importorskip("stormpy")
    exact = run(path, consts=consts, uniform=False, text=text)
    est = simulate_file(path, text, consts, runs, seed=1)
    assert est.scheduler == UNIFORM
    checked = 0
    for r in exact.properties:
        if r.min is None or r.max is None:
            continue
        e = est[r.name]
        if e.undecided:
            continue
        # the interval meets [min, max] (a little slack for the solver's precision)
        assert e.low <= r.max + 1e-6 and e.high >= r.min - 1e-6, (r.name, e, r.min, r.max)
        checked += 1
    assert checked >= 3


def test_uniform_scheduler_within_verify_bounds_interleaving() -> None:
    _overlap(PAIR, _read(PAIR), {}, 20_000)


@pytest.mark.slow
@pytest.mark.parametrize("compose", ["compose interleaving;", "compose timed ties nondet;"])
def test_uniform_scheduler_within_verify_bounds_two_uav(compose: str) -> None:
    _overlap(TWO_UAV, _two_uav(compose), SMALL, 4_000)


@pytest.mark.parametrize("direction", ["min", "max"])
def test_strategy_replay_contains_storms_value(direction: str) -> None:
    pytest.importorskip("stormpy")
    est = simulate_file(PAIR, _read(PAIR), {}, 20_000, seed=2, strategy=f"{direction}:done")
    assert est.policy is not None and est.scheduler == f"the {direction}:done strategy"
    e = est["done"]
    assert e.low <= est.policy.value <= e.high
    other = run(PAIR, uniform=False).property("done")
    assert est.policy.value == pytest.approx(getattr(other, direction), abs=1e-6)


def test_the_scheduler_is_stated_in_text_and_json() -> None:
    cmd = [sys.executable, "-m", "afsmc", "simulate", PAIR, "--runs", "300"]
    text = subprocess.run(cmd, capture_output=True, text=True, check=True).stdout
    assert f"who moves next: {UNIFORM}" in text
    obj = json.loads(subprocess.run([*cmd, "--json"], capture_output=True, text=True,
                                    check=True).stdout)
    assert obj["scheduler"] == UNIFORM


def test_a_single_machine_states_no_scheduler() -> None:
    path = os.path.join(ROOT, "examples", "uav.afsm")
    est = simulate_file(path, _read(path), {}, 200, seed=0)
    assert est.scheduler is None and "scheduler" not in est.to_json()


def test_a_strategy_of_an_interleaving_without_interval_constants() -> None:
    """Who moves next is the MDP's one choice: still a strategy to follow."""
    pytest.importorskip("stormpy")
    text = _read(PAIR).replace("const int USE     = [1, 2];", "const int USE = 1;")
    est = simulate_file(PAIR, text, {}, 5_000, seed=3, strategy="max:done")
    assert est.policy is not None
    assert est["done"].low <= est.policy.value <= est["done"].high


def test_sample_runs_name_agents_modes_and_actions() -> None:
    est = simulate_file(PAIR, _read(PAIR), {}, 50, seed=0, traces=2)
    for trace in est.traces:
        assert trace[0]["mode"] == "robot: Work, station: Idle"
        assert "robot.b" in trace[0]["vars"] and "charges" in trace[0]["vars"]
        for st in trace[1:]:
            who, _, _ = st["action"].partition(": ")
            assert who in ("robot", "station") or st["action"] in ("Charge",
                                                                   "(no enabled action)")
