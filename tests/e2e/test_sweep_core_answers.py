"""A sweep renders what the verification core answers at each point, and builds each
distinct model once.

- A constant that only labels read (a deadline in `label on_time = ... && t <= D`) does not
  rebuild the model: the points share one build, with the label written out in each
  point's properties, and give the values of the old route (a build per point).
- Each point's values and verdict are the `PropertyResult` that `afsmc.verify.run` gives
  at that point (the core: min, max, verdict, reason), in the CSV, the JSON, the sub-ranges
  and `Sweep.to_pandas()` alike; the sweep never judges on its own.
"""

from __future__ import annotations

import csv
import dataclasses
import io
import json
import math
from pathlib import Path
from typing import Any

import pytest

import afsmc
from afsmc.verify import run, sweep
from afsmc.verify.core.options import VerifyOptions
from afsmc.verify.reports import sweep_verdicts
from afsmc.verify.reports.sweep_result import SweepResult
from afsmc.verify.reports.sweep_tasks import Task, evaluate, make_tasks
from tests.conftest import EXAMPLES, run_cli

TOL = 1e-6  # the requirements make the check sound to 1e-6: two builds agree within that

# D is read by labels only (directly, and through a formula that no action reads); the
# requirement `need` holds for late deadlines, fails for early ones.
LABELLED = """
machine labelled;
param int D = 5;
param prob P_FAIL = 0.2;
const int DUR = [2, 3];
var t : [0..20] init 0 clamp;
var left : [0..2] init 2;
mode Work = 0 initial;
mode Done = 1 final;
formula late = t > D;
action Step in Work when left > 0 {
    1 - P_FAIL: left -= 1, t += DUR;
    P_FAIL: t += DUR;
}
action Finish in Work when left == 0 {
    goto Done;
}
label done = mode == Done;
label on_time = mode == Done && !late;
label tight = mode == Done && t <= D - 2;
rewards steps { [Step] true : 1; }
property by_deadline = P=? [ F "on_time" ];
property tight = P=? [ F "tight" ];
property need = P>=0.5 [ F "on_time" ];
property steps = R{"steps"}=? [ F "done" ];
"""

DS = [0, 2, 4, 5, 6, 8, 10, 14]


@pytest.fixture
def labelled(tmp_path: Path) -> str:
    p = tmp_path / "labelled.afsm"
    p.write_text(LABELLED)
    return str(p)


def _task(path: str, variable: str) -> Task:
    return Task(path=path, text=Path(path).read_text(), consts=(), properties=(),
                formulas=(), variable=variable, kind="const", xs=(),
                options=VerifyOptions())


def _same_values(got: afsmc.verify.PropertyResult, want: afsmc.verify.PropertyResult,
                 where: object) -> None:
    """The values of two builds of one point, within the precision (the shared build's
    reductions differ), and the same verdict; the reference point's too, if any."""
    a_json, b_json = got.to_json(), want.to_json()
    pairs = [(k, a_json.get(k), b_json.get(k)) for k in ("min", "max", "uniform", "value")]
    a_ref, b_ref = a_json.get("reference"), b_json.get("reference")
    assert (a_ref is None) == (b_ref is None), where
    if isinstance(a_ref, dict) and isinstance(b_ref, dict):
        pairs += [(f"reference {k}", a_ref[k], b_ref[k]) for k in ("min", "max", "uniform")]
    for key, a, b in pairs:
        assert (a is None) == (b is None), (where, key)
        if a is not None:
            assert a == pytest.approx(b, abs=TOL), (where, key)
    assert got.formula == want.formula
    assert (got.verdict is None) == (want.verdict is None), where
    if got.verdict is not None and want.verdict is not None:
        assert got.verdict.kind == want.verdict.kind, where


@pytest.mark.storm
@pytest.mark.parametrize("fail", ["param prob P_FAIL = 0.2;",
                                  "const prob P_FAIL = [0.1, 0.3];"],  # an interval probability
                         ids=["fixed", "interval"])
def test_a_constant_only_labels_read_shares_one_build_with_the_values_of_a_build_per_point(
        tmp_path: Path, fail: str) -> None:
    labelled = tmp_path / "labelled.afsm"
    labelled.write_text(LABELLED.replace("param prob P_FAIL = 0.2;", fail))
    path = str(labelled)
    tasks = make_tasks(_task(path, "D"), DS, jobs=1, dask=None, progress=None)
    assert len(tasks) == 1 and tasks[0].shared and tasks[0].xs == tuple(DS)
    shared = sweep(path, "D", DS, jobs=1)
    assert [pt.x for pt in shared.points] == DS
    for pt in shared.points:
        # the old route: this point's model built and checked on its own
        (alone,), errors = evaluate(dataclasses.replace(_task(path, "D"), xs=(pt.x,)))
        assert not errors
        assert [r.name for r in pt.properties] == [r.name for r in alone.properties]
        for got, want in zip(pt.properties, alone.properties, strict=True):
            _same_values(got, want, (pt.x, got.name))
    # `need` is decided in more than one way over the sweep, so the verdicts say something
    kinds = {v.kind for pt in shared.points if (v := pt.property("need").verdict) is not None}
    assert len(kinds) >= 2


@pytest.mark.storm
def test_a_label_written_out_in_the_properties_keeps_the_formula_as_written(
        labelled: str) -> None:
    res = sweep(labelled, "D", [3, 7], jobs=1, properties=["by_deadline"])
    out: dict[str, Any] = res.to_json()
    assert out["properties"] == [{"name": "by_deadline", "formula": 'P=? [ F "on_time" ]'}]


def _core(path: str, consts: dict[str, str]) -> dict[str, afsmc.verify.PropertyResult]:
    """What the core answers at one point: `afsmc.verify.run` there."""
    res = run(path, consts=consts)
    return {r.name: r for r in res.properties}


@pytest.mark.storm
def test_each_point_renders_the_cores_answer(labelled: str) -> None:
    """A sweep over a constant the model reads (a build per point): every point's values,
    verdict and reason are `run`'s at that point, and the CSV, the JSON, the sub-ranges
    and the plot say that verdict."""
    fails = [0.1, 0.3, 0.5, 0.7]
    res = sweep(labelled, "P_FAIL", fails, consts={"D": "6"}, jobs=1)
    core = {x: _core(labelled, {"D": "6", "P_FAIL": str(x)}) for x in fails}
    for pt in res.points:
        for r in pt.properties:
            want = core[pt.x][r.name]
            assert (r.min, r.max, r.uniform, r.value) == \
                (want.min, want.max, want.uniform, want.value), (pt.x, r.name)
            assert r.verdict == want.verdict and r.error == want.error, (pt.x, r.name)
    need = [core[x]["need"].verdict for x in fails]
    assert {v.kind for v in need if v is not None} >= {"holds", "fails"}
    _renders(res, "need", [v.kind if v is not None else None for v in need])
    # the JSON keeps the core's reason word for word
    out: dict[str, Any] = res.to_json()
    got = [p for pt in out["points"] for p in pt["properties"] if p["name"] == "need"]
    assert [(p["verdict"], p["reason"]) for p in got] == \
        [(v.kind, v.reason) for v in need if v is not None]


def _renders(res: SweepResult, name: str, kinds: list[str | None]) -> None:
    """The CSV's verdict column, the JSON's sub-ranges and the plot's marks of requirement
    `name` are `kinds`, one per point."""
    csv_kinds = [row["verdict"] or None for row in csv.DictReader(io.StringIO(res.to_csv()))
                 if row["property"] == name]
    assert csv_kinds == kinds
    ranges = sweep_verdicts.ranges(res, name)
    spelled = [k for k, a, b in ranges for pt in res.points if a <= pt.x <= b]
    assert spelled == [k or "no value" for k in kinds]
    out: dict[str, Any] = res.to_json()
    reqs = {r["name"]: r["ranges"] for r in out["requirements"]}
    assert [(r["verdict"], r["from"], r["to"]) for r in reqs[name]] == ranges
    fig = res.figure()
    ax = fig.axes[res.names.index(name)]
    marked = {c.get_label(): [float(x) for x, _ in c.get_offsets()] for c in ax.collections
              if c.get_label() in sweep_verdicts.COLOURS}
    for kind, xs in marked.items():
        assert xs == [float(pt.x) for pt, k in zip(res.points, kinds, strict=True)
                      if k == kind]
    assert sum(map(len, marked.values())) == sum(k is not None for k in kinds)


@pytest.mark.storm
def test_to_pandas_is_the_csv_of_the_same_sweep(labelled: str) -> None:
    pd = pytest.importorskip("pandas")
    s = afsmc.load(labelled).sweep("D", [2, 6, 10], jobs=1)
    df = s.to_pandas()
    want = pd.read_csv(io.StringIO(s.to_csv()), keep_default_na=False)
    assert list(df.columns) == list(want.columns)
    assert "verdict" in df.columns
    for got_row, want_row in zip(df.to_dict("records"), want.to_dict("records"), strict=True):
        for col, w in want_row.items():
            g = got_row[col]
            if g is None or (isinstance(g, float) and math.isnan(g)):
                assert w == "", col
            elif isinstance(g, float):
                assert g == float(w), col
            else:
                assert str(g) == str(w), col
    # a sweep without requirements has no verdict column, in either
    plain = afsmc.load(labelled).sweep("D", [2, 6], jobs=1,
                                       properties=["by_deadline"])
    assert "verdict" not in plain.to_pandas().columns
    assert "verdict" not in plain.to_csv().splitlines()[0].split(",")


@pytest.mark.storm
def test_the_cli_renders_the_same_verdicts_as_the_api(labelled: str) -> None:
    r = run_cli("sweep", labelled, "--const", "D=2,6,10", "-p", "need", "--json", "--jobs", "1")
    assert r.code == 0, r.err
    cli = json.loads(r.out)
    api = sweep(labelled, "D", [2, 6, 10], jobs=1, properties=["need"])
    assert cli["requirements"] == api.to_json()["requirements"]
    verdicts = [pt.property("need").verdict for pt in api.points]
    assert [p["properties"][0]["verdict"] for p in cli["points"]] == \
        [v.kind if v is not None else None for v in verdicts]


@pytest.fixture
def patrol_box(tmp_path: Path) -> str:
    """patrol.afsm with an interval probability: the issue's reproducer."""
    text = (EXAMPLES / "patrol.afsm").read_text()
    fixed = "const prob P_FAULT  = 0.01;"
    assert fixed in text
    p = tmp_path / "patrol.afsm"
    p.write_text(text.replace(fixed, "const prob P_FAULT  = [0.005, 0.03];"))
    return str(p)


@pytest.mark.storm
def test_with_interval_probabilities_each_point_is_the_cores_answer(patrol_box: str) -> None:
    need = 'P>=0.6 [ F "done" ]'
    res = sweep(patrol_box, "CELLS", [3, 4], formulas=[need], jobs=1)
    for pt in res.points:
        (got,) = pt.properties
        (want,) = run(patrol_box, consts={"CELLS": str(pt.x)}, formulas=[need]).properties
        assert (got.min, got.max, got.verdict, got.error) == \
            (want.min, want.max, want.verdict, want.error), pt.x
        assert got.to_json().get("reference") == want.to_json().get("reference"), pt.x
    # the CSV carries the core's reference values (its midpoint's), if it gives any, as
    # the JSON does
    out: dict[str, Any] = res.to_json()
    refs = [p.get("reference") for pt in out["points"] for p in pt["properties"]]
    rows = list(csv.DictReader(io.StringIO(res.to_csv())))
    assert len(rows) == len(refs) == 2
    for row, ref in zip(rows, refs, strict=True):
        if ref is None:
            assert "midpoint_min" not in row
            continue
        assert ref["point"] == "midpoint"
        for key in ("min", "max", "uniform", "value"):
            assert row[f"midpoint_{key}"] == ("" if ref[key] is None else repr(ref[key]))


@pytest.mark.storm
def test_with_interval_probabilities_sweep_and_verify_say_the_same(patrol_box: str) -> None:
    need = 'P>=0.6 [ F "done" ]'
    r = run_cli("sweep", patrol_box, "--const", "CELLS=3:4", "-f", need, "--json", "--jobs",
                "1")
    assert r.code in (0, 1), r.err
    for point in json.loads(r.out)["points"]:
        (got,) = point["properties"]
        v = run_cli("verify", patrol_box, "--const", f"CELLS={point['x']}", "-f", need,
                    "--json")
        (want,) = json.loads(v.out)["properties"]
        assert (got["verdict"], got["reason"]) == (want["verdict"], want["reason"])
        assert got["min"] == pytest.approx(want["min"], abs=1e-9)
        assert got["max"] == pytest.approx(want["max"], abs=1e-9)
