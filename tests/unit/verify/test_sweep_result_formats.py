"""The outputs of a sweep, from a SweepResult built by hand: `to_csv` and `to_json`."""

from __future__ import annotations

import csv
import io
import json
import math

from afsmc.verify.outcome.results import PropertyResult
from afsmc.verify.reports.sweep_result import SweepPoint, SweepResult


def _mdp_result() -> SweepResult:
    points = [
        SweepPoint(0, [PropertyResult("reach", "P=? [ F \"done\" ]", "P", min=0.25, max=0.5,
                                      uniform=0.375, seconds={"min": 0.1})],
                   states=10, transitions=20, uniform_states=8, uniform_transitions=12),
        SweepPoint(5, [PropertyResult("reach", "P=? [ F \"done\" ]", "P", min=0.5, max=1.0,
                                      uniform=None)],
                   states=10, transitions=21, seconds=3.0),
    ]
    return SweepResult("m.afsm", "T", "const", "mdp", points, ["reach"], seconds=4.0)


def test_the_csv_has_one_row_per_point_and_property() -> None:
    text = _mdp_result().to_csv()
    assert text == (
        "T,property,min,max,uniform,value,states,transitions,uniform_states,"
        "uniform_transitions\n"
        "0,reach,0.25,0.5,0.375,,10,20,8,12\n"
        "5,reach,0.5,1.0,,,10,21,,\n")


def test_the_csv_writes_values_as_the_language_does() -> None:
    points = [SweepPoint(x, [PropertyResult("r", "R=? [ F \"done\" ]", "R", value=v)], 3, 4)
              for x, v in ((False, 2.0), (True, math.inf))]
    res = SweepResult("m.afsm", "FAST", "const", "dtmc", points, ["r"])
    got = list(csv.DictReader(io.StringIO(res.to_csv())))
    assert [(r["FAST"], r["value"], r["min"]) for r in got] == \
        [("false", "2.0", ""), ("true", "inf", "")]


def test_the_json_of_a_const_sweep_gives_each_formula_once() -> None:
    got = _mdp_result().to_json()
    assert json.loads(json.dumps(got)) == got  # plain JSON
    assert got["file"] == "m.afsm" and got["variable"] == "T" and got["kind"] == "const"
    assert got["type"] == "mdp"
    assert got["properties"] == [{"name": "reach", "formula": "P=? [ F \"done\" ]"}]
    points = got["points"]
    assert isinstance(points, list)
    assert points[0] == {
        "x": 0, "states": 10, "transitions": 20, "uniform_states": 8,
        "uniform_transitions": 12,
        # no formula (given once above) and no check times
        "properties": [{"name": "reach", "min": 0.25, "max": 0.5, "uniform": 0.375,
                        "value": None}],
    }
    assert points[1]["uniform_states"] is None


def test_the_json_of_a_bound_sweep_gives_each_points_formula() -> None:
    points = [SweepPoint(k, [PropertyResult("p", f"P=? [ F<={k} \"done\" ]", "P", value=v)],
                         5, 6)
              for k, v in ((1, 0.5), (2, math.inf))]
    got = SweepResult("m.afsm", "bound", "bound", "dtmc", points, ["p"]).to_json()
    assert got["properties"] == [{"name": "p"}]
    pts = got["points"]
    assert isinstance(pts, list)
    assert [pt["properties"] for pt in pts] == [
        [{"name": "p", "formula": "P=? [ F<=1 \"done\" ]", "min": None, "max": None,
          "uniform": None, "value": 0.5}],
        # JSON has no infinity: null, and named as infinite
        [{"name": "p", "formula": "P=? [ F<=2 \"done\" ]", "min": None, "max": None,
          "uniform": None, "value": None, "infinite": ["value"]}],
    ]


def test_a_result_gives_its_axis_and_curves() -> None:
    res = _mdp_result()
    assert res.xs == [0, 5]
    assert res.curve("reach", "max") == [0.5, 1.0]
    assert res.curve("reach", "uniform") == [0.375, None]
    assert res.points[1].property("reach").min == 0.5


def test_an_empty_result_writes_a_header_and_no_points() -> None:
    res = SweepResult("m.afsm", "T", "const", "dtmc", [])
    assert res.to_csv().count("\n") == 1
    got = res.to_json()
    assert got["properties"] == [] and got["points"] == []
