"""Why afsmc's JANI writes one automaton per agent, not one per template
(afsmc.backends.jani_network): JANI lets several `system.elements` name one automaton,
each element with its own copy of the automaton's local variables, but Storm 2 does not
give them their copies. On a hand-written pair of walkers (each makes two steps, each
step succeeds with probability 0.9, else the walker stops; a shared counter counts the
walkers that finished) the network of one automaton per walker is right, 36 states and
P(both finish) = 0.9^4 by the closed form, and the same network with one automaton named
twice is built as another model and cannot be flattened. If this test fails, Storm has
learnt it, and afsmc may write a template once."""

from __future__ import annotations

import copy
import json
from pathlib import Path
from typing import Any

import pytest

stormpy = pytest.importorskip("stormpy")


def _int(name: str, hi: int) -> dict[str, Any]:
    return {"name": name, "type": {"kind": "bounded", "base": "int", "lower-bound": 0,
                                   "upper-bound": hi}, "initial-value": 0}


def _eq(var: str, value: int) -> dict[str, Any]:
    return {"op": "=", "left": var, "right": value}


def _and(a: object, b: object) -> dict[str, Any]:
    return {"op": "∧", "left": a, "right": b}


WALKER: dict[str, Any] = {
    "name": "Walker", "locations": [{"name": "l"}], "initial-locations": ["l"],
    "variables": [_int("n", 2), _int("stopped", 1)],
    "edges": [
        {"location": "l", "action": "step",
         "guard": {"exp": _and({"op": "<", "left": "n", "right": 2}, _eq("stopped", 0))},
         "destinations": [
             {"location": "l", "probability": {"exp": 0.9},
              "assignments": [{"ref": "n", "value": {"op": "+", "left": "n", "right": 1}}]},
             {"location": "l", "probability": {"exp": 0.1},
              "assignments": [{"ref": "stopped", "value": 1}]}]},
        {"location": "l", "action": "step", "guard": {"exp": _and(_eq("n", 2), _eq("stopped", 0))},
         "destinations": [{"location": "l", "assignments": [
             {"ref": "stopped", "value": 1},
             {"ref": "done", "value": {"op": "+", "left": "done", "right": 1}}]}]}]}


def _network(automata: list[dict[str, Any]], elements: list[str]) -> dict[str, Any]:
    return {
        "jani-version": 1, "name": "pair", "type": "mdp",
        "actions": [{"name": "step"}, {"name": "a_step"}, {"name": "b_step"}],
        "variables": [_int("done", 2)],
        "properties": [{"name": "both", "expression": {
            "op": "filter", "fun": "max", "states": {"op": "initial"},
            "values": {"op": "Pmin", "exp": {"op": "U", "left": True,
                                             "right": _eq("done", 2)}}}}],
        "automata": automata,
        "system": {"elements": [{"automaton": e} for e in elements],
                   "syncs": [{"synchronise": ["step", None], "result": "a_step"},
                             {"synchronise": [None, "step"], "result": "b_step"}]}}


def _per_instance() -> dict[str, Any]:
    a, b = copy.deepcopy(WALKER), copy.deepcopy(WALKER)
    a["name"], b["name"] = "WalkerA", "WalkerB"
    return _network([a, b], ["WalkerA", "WalkerB"])


def _built(net: dict[str, Any], tmp_path: Path) -> tuple[int, float]:
    path = tmp_path / "pair.jani"
    path.write_text(json.dumps(net), encoding="utf-8")
    model, props = stormpy.parse_jani_model(str(path))
    built = stormpy.build_model(model, props)
    value = stormpy.model_checking(built, props[0]).get_value(built.initial_states[0])
    return built.nr_states, float(value)


@pytest.mark.storm
def test_one_automaton_per_walker_is_the_pair(tmp_path: Path) -> None:
    states, value = _built(_per_instance(), tmp_path)
    assert states == 6 * 6  # n in 0..2 and stopped in 0..1, for each walker (done follows)
    assert value == pytest.approx(0.9 ** 4, abs=1e-12)


@pytest.mark.storm
def test_storm_does_not_give_the_elements_of_one_automaton_their_own_locals(
        tmp_path: Path) -> None:
    shared = _network([copy.deepcopy(WALKER)], ["Walker", "Walker"])
    right = _built(_per_instance(), tmp_path)
    assert _built(shared, tmp_path) != right  # built, but not as the pair
    path = tmp_path / "shared.jani"
    path.write_text(json.dumps(shared), encoding="utf-8")
    model, _ = stormpy.parse_jani_model(str(path))
    with pytest.raises(Exception, match="already exists"):
        model.flatten_composition()
