"""afsmc.backends.jani.emit on a lowered model: the model type, actions, constants,
variables (labels as transient variables), one automaton with one location, one edge per
lowered command, and the properties."""

from __future__ import annotations

import json
from typing import Any

from afsmc.backends.jani import dumps, emit, files, property_names
from afsmc.lower.lowering import lower
from tests.unit.lower.models import CLIMB, GEOMETRIC, model_of


def _edges(doc: dict[str, Any]) -> list[dict[str, Any]]:
    (automaton,) = doc["automata"]
    edges: list[dict[str, Any]] = automaton["edges"]
    return edges


def test_the_model_declares_its_type_actions_constants_and_variables() -> None:
    doc = emit(lower(model_of(CLIMB), "nondet"))
    assert doc["jani-version"] == 1 and doc["type"] == "mdp" and doc["name"] == "climb"
    assert [a["name"] for a in doc["actions"]] == ["Stop", "Up"]
    assert {c["name"]: c["value"] for c in doc["constants"]} == {
        "K": 5, "P_OK": 0.9, "STEP_lo": 1, "STEP_hi": 2}
    variables = {v["name"]: v for v in doc["variables"]}
    assert variables["mode"]["type"] == {"kind": "bounded", "base": "int",
                                         "lower-bound": 0, "upper-bound": 2}
    assert variables["x"]["initial-value"] == 0
    assert variables["top"]["transient"] is True and variables["top"]["type"] == "bool"


def test_one_automaton_with_one_location_and_an_edge_per_command() -> None:
    low = lower(model_of(CLIMB), "nondet")
    doc = emit(low)
    (automaton,) = doc["automata"]
    (location,) = automaton["locations"]
    assert automaton["initial-locations"] == [location["name"]]
    assert location["transient-values"] == [
        {"ref": "top", "value": {"op": "=", "left": "mode", "right": 1}}]
    edges = _edges(doc)
    assert len(edges) == len(low.commands) == 5
    assert [e.get("action") for e in edges] == ["Up", "Up", "Stop", None, None]
    up_lo = edges[0]
    assert up_lo["guard"]["exp"]["left"] == {"op": "=", "left": "mode", "right": 0}
    assert [d["probability"]["exp"] for d in up_lo["destinations"]] == [
        "P_OK", {"op": "-", "left": 1, "right": "P_OK"}]
    assert up_lo["destinations"][0]["assignments"][0]["value"]["left"]["right"] == "STEP_lo"
    assert edges[1]["destinations"][0]["assignments"][0]["value"]["left"]["right"] == "STEP_hi"
    # a final mode's self-loop: probability 1, nothing assigned
    assert edges[3]["destinations"] == [{"location": location["name"], "probability": {"exp": 1},
                                         "assignments": []}]


def test_properties_and_the_file() -> None:
    low = lower(model_of(CLIMB), "nondet")
    doc = emit(low)
    assert [p["name"] for p in doc["properties"]] == ["top_min", "top_max"]
    top_max = doc["properties"][1]["expression"]
    assert top_max["values"] == {"op": "Pmax", "exp": {"op": "F", "exp": "top"}}
    assert top_max["states"] == {"op": "initial"}
    assert property_names(low) == ["top_min", "top_max"]
    text = files(low)[".jani"]
    assert text == dumps(doc) and json.loads(text) == doc


def test_a_dtmc_weaves_the_hazard_into_the_destinations() -> None:
    doc = emit(lower(model_of(GEOMETRIC)))
    assert doc["type"] == "dtmc"
    (attempt,) = [e for e in _edges(doc) if e.get("action") == "Attempt"]
    assert attempt["destinations"][0]["probability"]["exp"] == "Q"
    assert attempt["destinations"][0]["assignments"] == [{"ref": "mode", "value": 2}]
    assert len(attempt["destinations"]) == 3
