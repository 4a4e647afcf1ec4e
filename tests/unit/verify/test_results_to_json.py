"""afsmc.verify.outcome.results: the JSON forms `afsmc verify --json` prints (JSON has no infinity:
an infinite value is null and named under "infinite")."""

from __future__ import annotations

import dataclasses
import json
import math

import pytest

from afsmc.diagnostics import Diagnostic, Severity
from afsmc.interrupt import JsonResult
from afsmc.verify import ModelStats, Partial, PropertyResult, VerifyResult
from afsmc.verify.engines.storm import JobResult
from afsmc.verify.outcome.results import add_runs, find_property, stats_of


def _stats(**changes: object) -> ModelStats:
    base = ModelStats("mdp", "nondet", 120, 340, 200, 0.1, 0.2, 0.3, engine="sparse",
                      solver="topological")
    return dataclasses.replace(base, **changes)


def test_model_stats_leave_out_what_was_not_measured() -> None:
    assert _stats().to_json() == {
        "states": 120, "transitions": 340, "choices": 200, "type": "mdp",
        "resolution": "nondet", "engine": "sparse", "processes": 1, "solver": "topological"}
    dd = _stats(solver="", engine="dd", engine_reason="asked", quotient_states=7,
                quotient_transitions=9).to_json()
    assert "solver" not in dd
    assert dd["engine_reason"] == "asked"
    assert (dd["quotient_states"], dd["quotient_transitions"]) == (7, 9)


def test_an_infinite_value_is_null_and_named() -> None:
    r = PropertyResult("steps", "R=? [ F \"done\" ]", "R", min=2.5, max=math.inf,
                       seconds={"min": 0.12345, "max": 1.0})
    assert r.to_json() == {"name": "steps", "formula": "R=? [ F \"done\" ]", "min": 2.5,
                           "max": None, "uniform": None, "value": None,
                           "infinite": ["max"], "seconds": {"min": 0.123, "max": 1.0},
                           "threshold": None, "verdict": None, "error": None}
    json.dumps(r.to_json(), allow_nan=False)  # valid JSON


def test_partial_keeps_what_was_answered_and_is_a_json_result() -> None:
    p = Partial(None, None, [PropertyResult("ok", "P=? [ F \"done\" ]", "P", value=0.5)])
    assert isinstance(p, JsonResult)
    assert p.to_json() == {"model": None, "uniform_model": None, "properties": [
        {"name": "ok", "formula": "P=? [ F \"done\" ]", "min": None, "max": None,
         "uniform": None, "value": 0.5, "seconds": {}, "threshold": None, "verdict": None,
         "error": None}]}


def test_verify_result_json_has_the_cli_keys_and_round_trips() -> None:
    warning = Diagnostic("W602", Severity.WARNING, "a mode the mission cannot end from", None)
    res = VerifyResult("m.afsm", "m", {"N": 3}, "prism", "sparse", 1000, 50_000_000,
                       _stats(), _stats(type="dtmc", resolution="uniform"),
                       [PropertyResult("ok", "P=? [ F \"done\" ]", "P", min=0.25, max=0.5,
                                       uniform=0.375)], 0.01, 0.7, [warning])
    obj = res.to_json()
    assert list(obj) == ["file", "machine", "model", "uniform_model", "properties", "timings",
                         "via", "engine", "constants", "state_space", "warnings",
                         "uncertainty"]
    assert obj["timings"] == {"load": 0.01, "parse": 0.1, "build": 0.2, "check": 0.3,
                              "uniform_build": 0.2, "uniform_check": 0.3, "total": 0.7}
    assert obj["state_space"] == {"upper_bound": 1000, "max_states": 50_000_000}
    assert obj["warnings"] == [warning.to_json()]
    assert json.loads(json.dumps(obj)) == obj
    assert res.kind == "mdp"
    assert res.property("ok").uniform == 0.375


def test_an_unknown_property_names_the_ones_there_are() -> None:
    rs = [PropertyResult("a", "", "P"), PropertyResult("b", "", "P")]
    assert find_property(rs, "b") is rs[1]
    with pytest.raises(KeyError, match="no property 'c'; there are 'a', 'b'"):
        find_property(rs, "c")


def test_two_processes_of_one_model_add_their_times_not_their_sizes() -> None:
    one = stats_of(JobResult(states=10, transitions=20, choices=15, kind="mdp",
                             parse_time=1.0, build_time=2.0, check_time=3.0,
                             engine="sparse"), "nondet")
    both = add_runs(one, one)
    assert (both.states, both.transitions, both.choices) == (10, 20, 15)
    assert (both.parse_time, both.build_time, both.check_time) == (2.0, 4.0, 6.0)
    assert both.processes == 2
