"""`verify --strategy` and `--witness K` on composed missions: the choices name the agent,
its action and the agents' modes; each path's step names the agent that moved and is
replayed through the mission's lowered commands (`confirmed`)."""

from __future__ import annotations

import math
import os
from pathlib import Path

import pytest

from afsmc.backends.prism import emit
from afsmc.compiler import load
from afsmc.lower.lowering import lower
from afsmc.lower.reduce import reduce
from afsmc.verify.core.api import run
from tests.conftest import ROOT

TWO_UAV = os.path.join(ROOT, "examples", "two_uav.afsm")
SMALL = {"OBJECTS": 1, "T_LIMIT": 25}
AGENTS = ("uav1", "uav2")

pytestmark = pytest.mark.storm


def _interleaving() -> str:
    with open(TWO_UAV, encoding="utf-8") as f:
        return f.read().replace("compose timed ties order;", "compose interleaving;")


def test_the_flat_model_the_strategies_read_is_the_network(tmp_path: Path) -> None:
    """The strategies and paths come from one module of the mission's commands, each
    labelled apart; Storm builds the same model from it as from the agents' modules."""
    from tests.storm_util import storm_prism

    low = reduce(lower(load(TWO_UAV, {k: str(v) for k, v in SMALL.items()}).model))
    flat = emit(low, variant_labels=True).model
    assert flat.count("\nmodule ") == 1 and "[uav1_Look__c" in flat
    net, values = storm_prism(low, tmp_path, "net")
    (tmp_path / "flat.prism").write_text(flat)
    import stormpy

    prog = stormpy.parse_prism_program(str(tmp_path / "flat.prism"))
    props = stormpy.parse_properties(emit(low).properties.replace("\n", " "), prog)
    model = stormpy.build_model(prog, props)
    assert (model.nr_states, model.nr_transitions) == (net.nr_states, net.nr_transitions)
    for p in props:
        got = float(stormpy.model_checking(model, p).get_value(model.initial_states[0]))
        assert got == pytest.approx(values[p.get_name()], rel=1e-12, abs=1e-12)


def test_strategies_name_the_agent_action_and_mode() -> None:
    pytest.importorskip("stormpy")
    res = run(TWO_UAV, consts=SMALL, properties=["success"], strategy=True, uniform=False)
    p = res.property("success")
    assert p.strategy is not None and set(p.strategy) == {"min", "max"}
    entries = [e for opt in ("min", "max") for e in p.strategy[opt]]
    assert entries
    for e in entries:
        assert e.constant in ("T_MOVE", "T_TAKEOFF")
        if e.action == "Launch":  # synchronised: both agents' modes
            assert e.mode == "uav1: Ready; uav2: Ready"
        else:
            assert e.action == "Look" and e.mode in ("uav1: Search", "uav2: Search")
        assert e.states > 0
    assert {e.mode for e in entries} >= {"uav1: Search", "uav2: Search"}


@pytest.mark.parametrize("interleaving", [False, True])
def test_witness_paths_name_the_agent_that_moved(interleaving: bool) -> None:
    pytest.importorskip("stormpy")
    text = _interleaving() if interleaving else None
    res = run(TWO_UAV, text=text, consts=SMALL, properties=["lost"], witness=("lost", 3),
              uniform=False)
    p = res.property("lost")
    assert p.witnesses is not None and len(p.witnesses) == 3 and p.max is not None
    assert math.fsum(w.probability for w in p.witnesses) <= p.max + 1e-12
    for w in p.witnesses:
        assert w.confirmed
        assert "Lost" in w.end_mode and all(a + ": " in w.end_mode for a in AGENTS)
        first = w.steps[0]
        assert first.action == "Launch (uav1, uav2)"
        assert first.mode == "uav1: Ready, uav2: Ready"
        assert first.changes["uav1.mode"] == "Search" and first.changes["uav2.mode"] == "Search"
        # each partner's interval end, named by the agent, is the one its clock shows
        assert [c for c, _ in first.choice] == ["T_TAKEOFF[uav1]", "T_TAKEOFF[uav2]"]
        for c, end in first.choice:
            agent = c[len("T_TAKEOFF["):-1]
            assert first.changes[f"{agent}.t"] == (10 if end == "floor" else 11)
        for s in w.steps[1:]:
            agent, _, action = s.action.partition(": ")
            assert agent in AGENTS and action in ("Look", "Stop", "Grab", "Deliver"), s
            assert all(f"{a}: " in s.mode for a in AGENTS)
        assert w.steps[-1].hazard == "Crash"
        assert math.prod(s.probability for s in w.steps) == pytest.approx(w.probability)


def test_an_interleaving_s_strategies_say_which_agent_moves() -> None:
    """Interleaved, the scheduler also chooses who moves: its turns name the agent, its
    action and mode, where the choice matters; a timed mission with `ties order` has no
    such choice, and no turns."""
    pytest.importorskip("stormpy")
    res = run(TWO_UAV, text=_interleaving(), consts=SMALL, properties=["success"],
              strategy=True, uniform=False)
    p = res.property("success")
    assert p.turns is not None and set(p.turns) == {"min", "max"}
    entries = [e for opt in ("min", "max") for e in p.turns[opt]]
    assert entries and all(e.states > 0 for e in entries)
    for e in entries:
        agent, _, action = e.action.partition(": ")
        assert agent in AGENTS and action in ("Look", "Stop", "Grab", "Deliver"), e
        assert e.mode.startswith(agent + ": ")
    assert {e.action.split(":")[0] for e in entries} == set(AGENTS)
    js = p.to_json()["turns"]
    assert isinstance(js, dict) and set(js["min"][0]) == {"action", "mode", "states"}
    timed = run(TWO_UAV, consts=SMALL, properties=["success"], strategy=True, uniform=False)
    assert timed.property("success").turns is None
