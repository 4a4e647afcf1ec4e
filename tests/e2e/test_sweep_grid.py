"""`afsmc sweep` over several constants: the grid of their values, each point equal to a
`verify` run there; long-format CSV and JSON; heat maps; the same numbers however split."""

from __future__ import annotations

import csv
import io
import json
from pathlib import Path

import pytest

from afsmc.verify import run, sweep
from tests.conftest import EXAMPLES, run_cli
from tests.unit.verify.test_verify import DEADLINE

PATROL = str(EXAMPLES / "patrol.afsm")
KEYS = ("min", "max", "uniform", "value")


def rows(text: str) -> list[dict[str, str]]:
    return list(csv.DictReader(io.StringIO(text)))


@pytest.mark.slow
@pytest.mark.storm
def test_a_3x3_grid_of_patrol_equals_verify_at_each_point() -> None:
    res = sweep(PATROL, {"CELLS": [2, 3, 4], "ROUNDS": [1, 2, 3]}, jobs=1)
    assert res.grid == ["CELLS", "ROUNDS"]
    assert [res.coords(pt) for pt in res.points] == [[c, r] for c in (2, 3, 4)
                                                    for r in (1, 2, 3)]
    names = res.names
    assert len(names) == 6
    for pt in res.points:
        cells, rounds = res.coords(pt)
        alone = run(PATROL, consts={"CELLS": cells, "ROUNDS": rounds}, isolate=False)
        assert pt.states == alone.model.states
        for name in names:
            got, want = pt.property(name), alone.property(name)
            for key in KEYS:
                a, b = getattr(got, key), getattr(want, key)
                assert (a is None) == (b is None), (cells, rounds, name, key)
                if a is not None:
                    assert a == pytest.approx(b, rel=1e-9, abs=1e-12), (cells, rounds, name, key)


@pytest.mark.slow
@pytest.mark.storm
def test_cli_grid_csv_json_and_heat_map(tmp_path: Path) -> None:
    spec = tmp_path / "deadline.afsm"
    spec.write_text(DEADLINE)
    png, out = tmp_path / "grid.png", tmp_path / "grid.csv"
    # D is read only by the property: the inner constant, one build per P_FAIL
    args = ["sweep", str(spec), "--const", "P_FAIL=0.1:0.3:0.1", "--const", "D=4:6",
            "-p", "by_deadline", "-p", "steps"]
    r = run_cli(*args, "-o", str(out), "--plot", str(png), "--jobs", "1")
    assert r.code == 0, r.err
    assert png.read_bytes().startswith(b"\x89PNG")
    table = rows(out.read_text())
    assert list(table[0])[:3] == ["P_FAIL", "D", "property"]
    assert len(table) == 9 * 2  # a row per point and property
    for name in ("by_deadline", "steps"):
        points = [(row["P_FAIL"], row["D"]) for row in table if row["property"] == name]
        assert points == [(p, d) for p in ("0.1", "0.2", "0.3") for d in ("4", "5", "6")]
    for row in table:
        alone = run(str(spec), consts={"P_FAIL": row["P_FAIL"], "D": row["D"]},
                    properties=[row["property"]], isolate=False)
        one = alone.properties[0]
        for key in ("min", "max", "uniform"):
            assert float(row[key]) == pytest.approx(getattr(one, key), abs=1e-9)
    # the same numbers split over processes, and as JSON in long format
    r2 = run_cli(*args, "--jobs", "2")
    assert r2.code == 0, r2.err
    assert r2.out == out.read_text()
    r3 = run_cli(*args, "--jobs", "1", "--json")
    data = json.loads(r3.out)
    assert data["variables"] == ["P_FAIL", "D"]
    assert len(data["rows"]) == 18
    assert data["rows"][0]["point"] == {"P_FAIL": 0.1, "D": 4}
    assert data["rows"][0]["property"] == "by_deadline"
    assert float(table[0]["min"]) == data["rows"][0]["min"]


@pytest.mark.storm
def test_grid_of_requirements_counts_verdicts(tmp_path: Path) -> None:
    spec = tmp_path / "deadline.afsm"
    spec.write_text(DEADLINE + 'property need = P>=0.5 [ F "done" && t <= D ];\n')
    r = run_cli("sweep", str(spec), "--const", "P_FAIL=0.1,0.3", "--const", "D=4,6",
                "-p", "need", "--jobs", "1")
    assert r.code == 0, r.err
    assert "verdict" in rows(r.out)[0]
    line = next(x for x in r.err.splitlines() if x.startswith("afsmc: need (P_FAIL x D)"))
    counts = {row["verdict"]: 0 for row in rows(r.out)}
    for row in rows(r.out):
        counts[row["verdict"]] += 1
    for verdict, n in counts.items():
        assert f"{verdict} at {n}" in line


def test_a_grid_too_large_is_a_usage_error(tmp_path: Path) -> None:
    spec = tmp_path / "deadline.afsm"
    spec.write_text(DEADLINE)
    r = run_cli("sweep", str(spec), "--const", "P_FAIL=0:0.999:0.001", "--const", "D=0:20")
    assert r.code == 2
    assert "at most 10,000" in r.err


@pytest.mark.storm
def test_the_api_sweeps_a_grid_from_a_mapping(tmp_path: Path) -> None:
    import afsmc

    spec = tmp_path / "deadline.afsm"
    spec.write_text(DEADLINE)
    sw = afsmc.load(str(spec)).sweep({"P_FAIL": "0.1,0.2", "D": [4, 6]},
                                     properties="by_deadline", jobs=1)
    df = sw.to_pandas()
    assert list(df.columns[:3]) == ["P_FAIL", "D", "property"]
    assert [tuple(r) for r in df[["P_FAIL", "D"]].itertuples(index=False)] == [
        (0.1, 4), (0.1, 6), (0.2, 4), (0.2, 6)]
    assert sw.to_csv() == run_cli("sweep", str(spec), "--const", "P_FAIL=0.1,0.2", "--const",
                                  "D=4,6", "-p", "by_deadline", "--jobs", "1").out


@pytest.mark.storm
def test_a_failed_point_of_a_grid_is_named_and_the_others_kept(tmp_path: Path) -> None:
    spec = tmp_path / "deadline.afsm"
    spec.write_text(DEADLINE)
    r = run_cli("sweep", str(spec), "--const", "P_FAIL=0.5,1.5", "--const", "D=4,6",
                "-p", "by_deadline", "--jobs", "1")
    assert r.code == 1
    assert "error[E207]: at P_FAIL=1.5, D=4; P_FAIL=1.5, D=6:" in r.err
    assert [(row["P_FAIL"], row["D"]) for row in rows(r.out)] == [("0.5", "4"), ("0.5", "6")]


@pytest.mark.slow
@pytest.mark.storm
def test_a_grid_on_dask_equals_one_process(tmp_path: Path) -> None:
    distributed = pytest.importorskip("distributed")
    spec = tmp_path / "deadline.afsm"
    spec.write_text(DEADLINE)
    grid = {"P_FAIL": [0.1, 0.3], "D": [3, 5, 7]}
    one = sweep(str(spec), grid, properties=["by_deadline"], jobs=1)
    with distributed.LocalCluster(n_workers=1, threads_per_worker=1, processes=False,
                                  dashboard_address=None) as cluster:
        remote = sweep(str(spec), grid, properties=["by_deadline"],
                       dask=cluster.scheduler_address)
    assert remote.to_csv() == one.to_csv()
    assert remote.to_json() == one.to_json()
