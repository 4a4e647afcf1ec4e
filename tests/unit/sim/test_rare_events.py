"""Rare events in Monte Carlo (issue 50): when no run shows the event, the interval of an
expected reward stays valid. A step-bounded reward gets [c - q (c - L), c + q (B - c)] from
the Clopper-Pearson bound q on a run that differs and the model's range [L, B] of a run's
total; an unbounded one is one-sided, with the reason. Checked against Storm's exact values
and the closed forms of a model whose repair happens with probability 1e-6 per step."""

from __future__ import annotations

import json
import math
from fractions import Fraction
from pathlib import Path
from typing import Any

import pytest

from afsmc.sim import stats
from afsmc.verify import VerifyOptions, run
from tests.conftest import run_cli

RARE = """// A rare repair: a step fails with probability 1e-6, and the repair earns 5.
machine rare;
const prob P_RARE = 0.000001;
var n : [0..3] init 0;
mode Go = 0 initial;
mode Repair = 1;
mode Done = 2 final;
action Step in Go when n < 3 { 1 - P_RARE: n += 1; P_RARE: goto Repair; }
action Finish in Go when n == 3 { goto Done; }
action Fix in Repair { goto Done; }
rewards repairs { [Fix] true : 5; }
rewards broken { mode == Repair : 2; }
rewards steps { true : 1; }
property repairs_soon = R{"repairs"}=? [ C<=10 ];
property repairs = R{"repairs"}=? [ F mode == Done ];
property broken_at_2 = R{"broken"}=? [ I=2 ];
property steps_3 = R{"steps"}=? [ C<=3 ];
property fails = P=? [ F mode == Repair ];
"""
P = Fraction(1, 10**6)
CLOSED = {  # the exact values, by hand
    "repairs_soon": 5 * (1 - (1 - P) ** 3),  # every repair happens within 4 steps
    "repairs": 5 * (1 - (1 - P) ** 3),
    "broken_at_2": 2 * (1 - P) * P,  # the second step fails: in Repair at step 2
    "steps_3": Fraction(3),
    "fails": 1 - (1 - P) ** 3,
}
RUNS, CONFIDENCE = 2000, 0.999


Simulated = tuple[Path, dict[str, dict[str, Any]]]


@pytest.fixture(scope="module")
def simulated(tmp_path_factory: pytest.TempPathFactory) -> Simulated:
    path = tmp_path_factory.mktemp("rare") / "rare.afsm"
    path.write_text(RARE)
    r = run_cli("simulate", str(path), "--json", "--runs", str(RUNS), "--seed", "3")
    assert r.code == 0, r.err
    return path, {p["name"]: p for p in json.loads(r.out)["properties"]}


@pytest.mark.storm
def test_every_interval_holds_storm_s_exact_value(simulated: Simulated) -> None:
    path, props = simulated
    exact = {p.name: p.value for p in run(str(path), VerifyOptions(exact=True)).properties}
    for name, value in exact.items():
        assert value == pytest.approx(float(CLOSED[name]), rel=1e-12), name
        p = props[name]
        high = math.inf if p["high"] == "inf" else p["high"]
        assert p["low"] <= value <= high, (name, value, p)
        assert high > 0, p  # the collapse to [0, 0]: the event no run saw


def test_a_step_bounded_reward_gets_the_model_s_range(
        simulated: Simulated) -> None:
    _, props = simulated
    q = stats.clopper_pearson(0, RUNS, CONFIDENCE)[1]
    assert q == pytest.approx(1 - ((1 - CONFIDENCE) / 2) ** (1 / RUNS))
    soon = props["repairs_soon"]
    assert (soon["estimate"], soon["method"]) == (0.0, "range")
    # a run earns at most 5 per step for 10 steps
    assert (soon["low"], soon["high"]) == (0.0, pytest.approx(50 * q))
    assert "every one of 2,000 runs earned 0" in soon["reason"]
    assert props["broken_at_2"]["high"] == pytest.approx(2 * q)  # the state reward, at one step
    steps = props["steps_3"]  # every run earns 3: the range reaches no higher than 3
    assert (steps["estimate"], steps["high"], steps["method"]) == (3.0, 3.0, "range")
    assert steps["low"] == pytest.approx(3 - 3 * q)
    assert props["fails"]["method"] == "clopper-pearson"


def test_an_unbounded_reward_no_run_earned_is_one_sided_with_the_reason(
        simulated: Simulated) -> None:
    path, props = simulated
    f = props["repairs"]
    assert (f["estimate"], f["low"], f["high"], f["method"]) == (0.0, 0.0, "inf", "one-sided")
    assert "the interval is one-sided" in f["reason"]
    r = run_cli("simulate", str(path), "--runs", str(RUNS), "--seed", "3")
    assert r.code == 0, r.err
    line = next(x for x in r.out.splitlines() if x.strip().startswith("repairs "))
    assert "[0, inf]" in line and "the model bounds no run's total from above" in line


def test_runs_that_vary_keep_the_normal_interval(tmp_path: Path) -> None:
    path = tmp_path / "often.afsm"
    path.write_text(RARE.replace("0.000001", "0.3"))
    r = run_cli("simulate", str(path), "--json", "--runs", "2000")
    assert r.code == 0, r.err
    props = {p["name"]: p for p in json.loads(r.out)["properties"]}
    assert props["repairs"]["method"] == "normal" and "reason" not in props["repairs"]
