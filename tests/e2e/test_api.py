"""The Python API against the CLI it stands beside: the same numbers as `afsmc verify
--json`, `sweep` and `simulate`, and the issue's snippet run as a user runs it (a plain
script, and `python - < file`), with no `if __name__ == "__main__":` guard."""

from __future__ import annotations

import csv
import io
import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

import afsmc
from afsmc.verify import upper_bound
from tests.conftest import EXAMPLES, ROOT, run_cli

pytestmark = pytest.mark.storm

PATROL = str(EXAMPLES / "patrol.afsm")
# The lines, then what the test compares; {file}, {const} and {prop} vary.
SNIPPET = """\
import json
import afsmc
m = afsmc.load("examples/{file}")
df = m.verify().to_pandas()
svg = m.diagram()._repr_svg_()
r = m.with_consts({const}).verify(["{prop}"])
# Storm in its watched child process, as for a model above 200,000 states (uav.afsm)
iso = m.verify(["{prop}"], isolate=True)
print(json.dumps({{"isolated": iso["{prop}"].uniform, "direct": df.loc["{prop}", "uniform"],
                  "rows": list(df.index), "columns": list(df.columns),
                  "svg": svg.lstrip()[:5], "has_svg": "<svg" in svg,
                  "result": r.to_json()}}))
"""
TIMES = ("timings",)


def without_times(obj: dict[str, object]) -> dict[str, object]:
    """A verify --json object without what differs from run to run: the times."""
    out = {k: v for k, v in obj.items() if k not in TIMES}
    out["properties"] = [{k: v for k, v in p.items() if k != "seconds"}
                         for p in obj["properties"]]  # type: ignore[union-attr]
    return out


def cli_json(*argv: str) -> dict[str, object]:
    res = run_cli("verify", "--json", *argv)
    assert res.code == 0, res.err
    out: dict[str, object] = json.loads(res.out)
    return out


@pytest.mark.slow  # two Python processes that import Storm: about 10 s
@pytest.mark.parametrize("how", ["script", "stdin"])
def test_the_snippet_works_as_a_plain_script_and_from_stdin(tmp_path: Path, how: str,
                                                            monkeypatch: pytest.MonkeyPatch
                                                            ) -> None:
    script = tmp_path / "snippet.py"
    script.write_text(SNIPPET.format(file="patrol.afsm", const="CELLS=6", prop="finish"))
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    if how == "script":
        proc = subprocess.run([sys.executable, str(script)], cwd=ROOT, env=env,
                              capture_output=True, text=True, timeout=300)
    else:
        with open(script, encoding="utf-8") as f:
            proc = subprocess.run([sys.executable, "-"], stdin=f, cwd=ROOT, env=env,
                                  capture_output=True, text=True, timeout=300)
    assert proc.returncode == 0, proc.stderr
    got = json.loads(proc.stdout)
    assert got["rows"] == afsmc.load(PATROL).properties  # one row per declared property
    assert got["columns"] == ["formula", "kind", "min", "max", "uniform", "value", "verdict"]
    assert got["svg"] == "<?xml" and got["has_svg"]
    assert got["isolated"] == got["direct"]
    monkeypatch.chdir(ROOT)  # the file named as the snippet names it
    cli = cli_json("examples/patrol.afsm", "--const", "CELLS=6", "--property", "finish")
    assert without_times(got["result"]) == without_times(cli)


def test_to_json_is_verify_json() -> None:
    res = afsmc.load(PATROL).verify()
    assert without_times(res.to_json()) == without_times(cli_json(PATROL))
    assert len(res) == 6 and res.kind == "mdp"


def test_with_consts_gives_the_value_of_verify_const() -> None:
    api = afsmc.load(PATROL).with_consts(CELLS=6).verify(["finish"])
    cli = cli_json(PATROL, "--const", "CELLS=6", "--property", "finish")
    (entry,) = cli["properties"]  # type: ignore[misc]
    p = api["finish"]
    assert (p.min, p.max, p.uniform) == (entry["min"], entry["max"], entry["uniform"])
    df = api.to_pandas()
    assert df.loc["finish", "uniform"] == entry["uniform"]
    assert "<table" in api._repr_html_()


def test_options_flow_to_verify_run() -> None:
    # options of afsmc.verify.run, passed on as given: the input language, a formula
    res = afsmc.load(PATROL).verify([], via="jani", formulas=['P=? [ F "halted" ]'])
    cli = cli_json(PATROL, "--via", "jani", "--formula", 'P=? [ F "halted" ]')
    assert without_times(res.to_json()) == without_times(cli)
    with pytest.raises(ValueError, match="engine must be one of"):
        afsmc.load(PATROL).verify(engine="fast")


def test_strategy_and_witness_k_are_verify_strategy_and_witness_k() -> None:
    # witness=K, as `--witness K` is written on the command line, for the one property
    res = afsmc.load(PATROL).verify(["finish"], strategy=True, witness=2)
    cli = cli_json(PATROL, "-p", "finish", "--strategy", "--witness", "2")
    assert without_times(res.to_json()) == without_times(cli)
    props = cli["properties"]
    assert isinstance(props, list) and len(props[0]["witnesses"]) == 2
    assert props[0]["strategy"] is not None


def test_a_failed_verify_raises_afsm_error() -> None:
    with pytest.raises(afsmc.AfsmError) as info:
        afsmc.load(PATROL).verify(["nope"])
    assert info.value.diagnostics[0].code == "E407"
    assert "did you mean" in str(info.value) or "properties:" in str(info.value)


@pytest.mark.slow
def test_sweep_is_the_csv_of_afsmc_sweep() -> None:
    sw = afsmc.load(PATROL).sweep("ROUNDS", "1:3:1", properties=["finish", "fault"], jobs=1)
    cli = run_cli("sweep", PATROL, "--const", "ROUNDS=1:3:1", "-p", "finish", "-p", "fault",
                  "--jobs", "1")
    assert cli.code == 0, cli.err
    rows = list(csv.DictReader(io.StringIO(cli.out)))
    df = sw.to_pandas()
    assert len(df) == len(rows) == 6
    for (_, got), want in zip(df.iterrows(), rows, strict=True):
        assert str(got["ROUNDS"]) == want["ROUNDS"] and got["property"] == want["property"]
        for k in ("min", "max", "uniform"):
            assert repr(float(got[k])) == want[k]
    assert sw.to_csv() == cli.out
    fig = sw.plot()
    assert len(fig.axes) == 2
    assert [ax.get_title().split(":")[0] for ax in fig.axes] == ["finish", "fault"]


def test_sweep_of_the_step_bound() -> None:
    sw = afsmc.load(PATROL).sweep("bound", [10, 20], properties="finish_soon", jobs=1)
    df = sw.to_pandas()
    assert list(df["bound"]) == [10, 20]
    at20 = afsmc.load(PATROL).verify("finish_soon")["finish_soon"]
    assert df["uniform"].iloc[1] == pytest.approx(at20.uniform, rel=1e-9)


@pytest.mark.slow
def test_simulate_is_afsmc_simulate() -> None:
    est = afsmc.load(PATROL).simulate(runs=1000, seed=7)
    cli = run_cli("simulate", PATROL, "--runs", "1000", "--seed", "7", "--json")
    assert cli.code == 0, cli.err
    want = {p["name"]: p for p in json.loads(cli.out)["properties"]}
    df = est.to_pandas()
    assert list(df.index) == list(want)
    for name, row in df.iterrows():
        assert (row["estimate"], row["low"], row["high"]) == (
            want[name]["estimate"], want[name]["low"], want[name]["high"])
    # the exact value lies within the interval (0.999 confidence)
    exact = afsmc.load(PATROL).verify("finish")["finish"].uniform
    assert df.loc["finish", "low"] <= exact <= df.loc["finish", "high"]


def test_the_diagram_with_reach_draws_the_probabilities() -> None:
    svg = afsmc.load(PATROL).diagram(reach=True)._repr_svg_()
    assert "P(reach)" in svg


@pytest.mark.slow  # the UAV mission: about a minute
def test_the_snippet_on_uav_runs_storm_isolated_from_a_plain_script(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    # uav.afsm's upper bound is above 200,000 states: Storm runs in its watched child
    # process, which must not run the script again.
    script = tmp_path / "uav.py"
    script.write_text(SNIPPET.format(file="uav.afsm", const="T_LIMIT=100", prop="success"))
    monkeypatch.chdir(ROOT)
    assert upper_bound(afsmc.load("examples/uav.afsm").model) > 200_000
    proc = subprocess.run([sys.executable, str(script)], cwd=ROOT,
                          env={**os.environ, "PYTHONPATH": str(ROOT)},
                          capture_output=True, text=True, timeout=600)
    assert proc.returncode == 0, proc.stderr
    got = json.loads(proc.stdout)
    assert got["rows"] == afsmc.load("examples/uav.afsm").properties
    assert got["isolated"] == got["direct"]
    cli = cli_json("examples/uav.afsm", "--const", "T_LIMIT=100", "--property", "success")
    assert without_times(got["result"]) == without_times(cli)


def _with_slip_interval(tmp_path: Path) -> Path:
    text = Path(PATROL).read_text(encoding="utf-8")
    wide = text.replace("const prob P_SLIP   = 0.1;", "const prob P_SLIP = [0.05, 0.15];")
    assert wide != text
    f = tmp_path / "patrol_slip.afsm"
    f.write_text(wide.replace('property finish      = P=? [ F "done" ];',
                              'property finish = P>=0.8 [ F "done" ];'), encoding="utf-8")
    return f


@pytest.mark.slow  # Storm's parametric engine on every property, twice: about 15 s
def test_interval_probabilities_give_the_bounds_of_verify(tmp_path: Path) -> None:
    f = _with_slip_interval(tmp_path)
    res = afsmc.load(str(f)).verify()
    run = run_cli("verify", "--json", str(f))
    assert run.code == 1, run.err  # finish >= 0.8 fails somewhere in P_SLIP's interval
    cli = json.loads(run.out)
    assert without_times(res.to_json()) == without_times(cli)
    assert res.intervals is not None and res.intervals.box == {"P_SLIP": (0.05, 0.15)}
    df = res.to_pandas()
    for entry, prop in zip(cli["probability_intervals"]["properties"], cli["properties"],
                           strict=True):
        # min and max are the bounds over the interval; the midpoint is a reference
        assert (df.loc[entry["name"], "min"], df.loc[entry["name"], "max"]) \
            == (entry["min_attained"], entry["max_attained"]) == (prop["min"], prop["max"])
        ref = prop["reference"]
        assert (df.loc[entry["name"], "midpoint_min"], df.loc[entry["name"], "midpoint_max"]) \
            == (ref["min"], ref["max"])
    # the requirement is judged once, over the interval, and rendered as the CLI renders it
    assert df.loc["finish", "verdict"] == cli["properties"][0]["verdict"] == "depends"
    assert "midpoint_min" in res._repr_html_()
    # the same from the mission's text, for one property
    text = afsmc.load(f.read_text(encoding="utf-8")).verify("fault")
    one = json.loads(run_cli("verify", "--json", str(f), "-p", "fault").out)
    assert text.to_json()["probability_intervals"] == one["probability_intervals"]


def test_a_mission_without_interval_probabilities_has_no_interval_columns() -> None:
    res = afsmc.load(PATROL).verify("finish")
    assert res.intervals is None and "probability_intervals" not in res.to_json()
    assert "midpoint_min" not in res.to_pandas().columns
