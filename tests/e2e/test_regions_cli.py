"""`afsmc regions`: the JSON and table forms, --summary, the dimensions that come from
the file, the plot, --feasible, and the diagnostics of bad parameters (E440, E441,
E442)."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from tests.conftest import EXAMPLES, run_cli

pytestmark = pytest.mark.storm


@pytest.fixture(scope="module")
def patrol(tmp_path_factory: pytest.TempPathFactory) -> str:
    text = (EXAMPLES / "patrol.afsm").read_text(encoding="utf-8")
    path = tmp_path_factory.mktemp("patrol") / "patrol.afsm"
    path.write_text(text.replace("const prob P_SLIP   = 0.1;",
                                 "const prob P_SLIP   = [0.05, 0.15];"), encoding="utf-8")
    return str(path)


def test_json_lists_regions_with_bounds_verdicts_and_coverage(patrol: str) -> None:
    r = run_cli("regions", patrol, "--require", 'P>=0.81 [ F "done" ]', "--json", "-j", "1",
                "--feasible")
    assert r.code == 0, r.err
    out = json.loads(r.out)
    assert out["box"] == {"P_SLIP": [0.05, 0.15]}
    assert out["coverage"] >= 0.95 and out["coverage"] == pytest.approx(out["holds"] + out["fails"])
    assert {reg["verdict"] for reg in out["regions"]} <= {"holds", "fails", "unknown"}
    assert all(set(reg["bounds"]) == {"P_SLIP"} for reg in out["regions"])
    assert 0.05 <= out["feasible"]["P_SLIP"] <= 0.15
    # no --param: the one dimension is the file's interval probability, and says so
    assert out["from_file"] == ["P_SLIP"]
    assert out["verdict"] in ("holds", "fails", "depends", "undecided") and out["reason"]
    # the patrol has cycles of more than one state, which afsmc's explorer does not take:
    # Storm's parametric engine decides the regions, and the JSON says so
    assert out["engine"] == "parametric"


def test_the_table_the_plot_and_the_feasible_flags(patrol: str, tmp_path: Path) -> None:
    png = tmp_path / "regions.png"
    r = run_cli("regions", patrol, "--param", "P_FAULT=0.005:0.02", "--require",
                'P>=0.81 [ F "done" ]', "--plot", str(png), "--feasible", "--coverage", "0.8",
                "-j", "1")
    assert r.code == 0, r.err
    assert png.read_bytes().startswith(b"\x89PNG")
    assert "coverage" in r.out and "holds" in r.out
    assert "feasible: --const P_FAULT=" in r.out
    # P_FAULT is a 'const prob', which --const cannot set: the output says so
    assert "P_FAULT, P_SLIP are declared 'const'" in r.out
    # one --param named: P_SLIP, the file's interval probability, is a further dimension
    assert "from the file: P_SLIP in [0.05, 0.15] (an interval probability" in r.out
    assert "over the whole box: " in r.out


@pytest.mark.slow
def test_a_long_table_points_to_summary_which_prints_the_summary_only(patrol: str) -> None:
    argv = ["regions", patrol, "--param", "P_FAULT=0.005:0.02", "--require",
            'P>=0.81 [ F "done" ]', "-j", "1"]
    full = run_cli(*argv)
    assert full.code == 0, full.err
    rows = [line for line in full.out.splitlines()
            if line.endswith(("holds", "fails", "unknown"))]
    assert len(rows) > 20
    assert f"({len(rows)} regions listed above; --summary prints the summary only)" in full.out
    short = run_cli(*argv, "--summary")
    assert short.code == 0, short.err
    assert not [line for line in short.out.splitlines()
                if line.endswith(("holds", "fails", "unknown"))]
    assert "--summary prints" not in short.out
    # the same run: each summary line is one of the full output's, timing aside
    def untimed(out: str) -> list[str]:
        return [line.rsplit(",", 1)[0] if line.startswith("holds on") else line
                for line in out.splitlines() if line]

    assert set(untimed(short.out)) <= set(untimed(full.out))
    assert any(line.startswith("over the whole box: ") for line in untimed(short.out))


@pytest.mark.parametrize(("param", "words"), [
    ("CELLS=1:3", "'CELLS' is an int constant"),
    ("done=0:1", "'done' is a label, not a constant"),
    ("P_FAULT=0.2:1.5", "a probability's range lies within [0, 1]"),
    ("cell=0:1", "'cell' is a variable, not a constant"),
    ("NOPE=0:1", "'NOPE' is not declared, not a constant"),
    ("P_FAULT=0.2:0.1", "the range is empty"),
    ("P_FAULT=0.1", "expected NAME=LO:HI"),
])
def test_a_bad_param_is_e441(patrol: str, param: str, words: str) -> None:
    r = run_cli("regions", patrol, "--param", param, "--require", 'P>=0.8 [ F "done" ]')
    assert r.code == 1 and "E441" in r.err and words in r.err, r.err
    assert "Traceback" not in r.err


def test_a_box_reaching_zero_is_e440_with_an_open_bound(patrol: str) -> None:
    r = run_cli("regions", patrol, "--param", "P_FAULT=0:0.02", "--require",
                'P>=0.8 [ F "done" ]')
    assert r.code == 1 and "E440" in r.err and "--param P_FAULT=1e-6:0.02" in r.err, r.err


def test_a_query_is_no_requirement(patrol: str) -> None:
    r = run_cli("regions", patrol, "--require", 'P=? [ F "done" ]')
    assert r.code == 1 and "E442" in r.err


def test_verify_reports_the_bounds_over_the_interval_and_the_midpoint(patrol: str) -> None:
    r = run_cli("verify", patrol, "--json", "-p", "finish")
    assert r.code == 0, r.err
    out = json.loads(r.out)
    iv = out["probability_intervals"]
    assert iv["box"] == {"P_SLIP": [0.05, 0.15]}
    (e,) = iv["properties"]
    (p,) = out["properties"]
    # min and max are the bounds over the interval; the midpoint's lie inside them
    assert (p["min"], p["max"]) == (e["min_attained"], e["max_attained"])
    ref = p["reference"]
    assert p["min"] <= ref["min"] <= ref["max"] <= p["max"]
    text = run_cli("verify", patrol, "-p", "finish").out
    assert "midpoint" in text and "every fixed P_SLIP in [0.05, 0.15]" in text


def test_simulate_at_an_end_of_the_interval_agrees_with_verify_there(
        patrol: str, tmp_path: Path) -> None:
    fixed = tmp_path / "fixed.afsm"
    fixed.write_text(Path(patrol).read_text(encoding="utf-8").replace(
        "[0.05, 0.15]", "0.05"), encoding="utf-8")
    exact = json.loads(run_cli("verify", str(fixed), "--json", "-p", "finish").out)
    (p,) = exact["properties"]
    r = run_cli("simulate", patrol, "--at", "min", "--runs", "4000", "--seed", "3", "--json")
    assert r.code == 0, r.err
    out = json.loads(r.out)
    assert out["at"] == "min"
    est = next(e for e in out["properties"] if e["name"] == "finish")
    assert est["low"] <= p["uniform"] <= est["high"]


def test_the_plot_takes_the_axes_asked_for_and_refuses_others(patrol: str, tmp_path: Path) -> None:
    png = tmp_path / "r.png"
    r = run_cli("regions", patrol, "--param", "P_FAULT=0.005:0.02", "--require",
                'P>=0.81 [ F "done" ]', "--plot", str(png), "--axes", "P_SLIP,P_FAULT",
                "--max-rounds", "2")
    assert r.code == 0 and png.is_file(), r.err
    r = run_cli("regions", patrol, "--require", 'P>=0.81 [ F "done" ]', "--plot", str(png),
                "--axes", "P_SLIP,NOPE")
    assert r.code == 2 and "--axes P_SLIP,NOPE" in r.err
    r = run_cli("regions", patrol, "--require", 'P>=0.81 [ F "done" ]', "--plot", str(png),
                "--axes", "P_SLIP,P_SLIP")
    assert r.code == 2 and "two different parameters" in r.err
    r = run_cli("regions", patrol, "--require", 'P>=0.81 [ F "done" ]', "--coverage", "1.5")
    assert r.code == 2 and "--coverage" in r.err


def test_an_interval_probability_named_with_param_is_not_from_the_file(patrol: str) -> None:
    r = run_cli("regions", patrol, "--param", "P_SLIP=0.05:0.1", "--require",
                'P>=0.81 [ F "done" ]', "--json", "--max-rounds", "2")
    assert r.code == 0, r.err
    out = json.loads(r.out)
    assert out["box"] == {"P_SLIP": [0.05, 0.1]} and out["from_file"] == []
    text = run_cli("regions", patrol, "--param", "P_SLIP=0.05:0.1", "--require",
                   'P>=0.81 [ F "done" ]', "--max-rounds", "2").out
    assert "from the file" not in text
