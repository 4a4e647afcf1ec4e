"""`Mission.simulate` and `Mission.sim_check` against the commands that run through them:
`afsmc simulate --json` and `afsmc sim-check --json` are the oracles, object for object."""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import pytest

import afsmc
from tests.conftest import CASES, EXAMPLES, run_cli

PATROL = str(EXAMPLES / "patrol.afsm")
MISSION = CASES / "sim_mission" / "mission.afsm"
NO_PROPERTIES = ("machine m;\nvar x : [0..3] init 0;\nmode A = 0 initial;\nmode B = 1 final;\n"
                 "action go in A { goto B; }\n")


def cli_json(*argv: str, code: int = 0) -> dict[str, object]:
    res = run_cli(*argv, "--json")
    assert res.code == code, res.out + res.err
    out: dict[str, object] = json.loads(res.out)
    return out


def test_simulate_to_json_is_simulate_json() -> None:
    est = afsmc.load(PATROL).simulate(runs=300, seed=5, traces=1, at="max")
    cli = cli_json("simulate", PATROL, "--runs", "300", "--seed", "5", "--traces", "1",
                   "--at", "max")
    assert est.to_json() == cli
    df = est.to_pandas()
    assert list(df.index) == [p["name"] for p in cli["properties"]]  # type: ignore[attr-defined]
    assert len(est.traces) == 1 and "300 runs" in est._repr_html_()


def test_simulate_with_constants_and_a_resolution_is_simulate_json() -> None:
    est = afsmc.load(PATROL, consts={"CELLS": 3}).simulate(runs=200, resolve="hi",
                                                             confidence=0.99)
    cli = cli_json("simulate", PATROL, "--const", "CELLS=3", "--runs", "200", "--resolve", "hi",
                   "--confidence", "0.99")
    assert est.to_json() == cli


@pytest.mark.storm
def test_simulate_following_a_storm_strategy_is_simulate_json() -> None:
    est = afsmc.load(PATROL).simulate(runs=50, strategy="max:finish")
    cli = cli_json("simulate", PATROL, "--runs", "50", "--strategy", "max:finish")
    assert est.to_json() == cli
    assert est.policy is not None and est.policy.property == "finish"
    with pytest.raises(ValueError, match="not both"):
        afsmc.load(PATROL).simulate(runs=10, strategy="max:finish", resolve="lo")


def test_a_mission_without_properties_is_e407_unless_traces_are_asked_for(
        tmp_path: Path) -> None:
    f = tmp_path / "none.afsm"
    f.write_text(NO_PROPERTIES)
    m = afsmc.load(str(f))
    with pytest.raises(afsmc.AfsmError) as info:
        m.simulate(runs=10)
    cli = cli_json("simulate", str(f), "--runs", "10", code=1)
    assert [d.to_json() for d in info.value.diagnostics] == cli["diagnostics"]
    traced = m.simulate(runs=1, traces=1)
    assert traced.to_json() == cli_json("simulate", str(f), "--runs", "1", "--traces", "1")


def _drifted(tmp_path: Path, name: str = "drift.afsm") -> Path:
    path = tmp_path / name
    path.write_text(MISSION.read_text().replace("const int T_AP = [1, 4] from",
                                                "const int T_AP = [7, 9] from"))
    return path


def test_sim_check_is_sim_check_json(tmp_path: Path) -> None:
    path = _drifted(tmp_path)
    res = afsmc.load(str(path)).sim_check(runs=2000, seed=3)
    cli = cli_json("sim-check", str(path), "--runs", "2000", "--seed", "3", code=1)
    assert res.to_json() == cli
    assert not res.ok and [d.code for d in res.errors] == ["E502"]
    df = res.to_pandas()
    assert list(df.index) == [c["name"] for c in cli["constants"]]  # type: ignore[attr-defined]
    assert df.loc["T_AP", "verdict"] == "drifted" == res["T_AP"].verdict
    assert (df["verdict"].drop("T_AP") == "consistent").all()
    assert "1 drifted" in res._repr_html_()


def test_sim_check_of_a_mission_without_simulated_constants() -> None:
    res = afsmc.load(PATROL).sim_check(runs=100)
    assert res.ok and res.evidence == []
    assert res.to_json() == cli_json("sim-check", PATROL, "--runs", "100")


def test_sim_check_update_needs_a_file() -> None:
    m = afsmc.load(MISSION.read_text())
    with pytest.raises(ValueError, match="not a file"):
        m.sim_check(update=True)
    with pytest.raises(ValueError, match="at least 2"):
        m.sim_check(runs=1)


@pytest.mark.slow  # two sim-checks of every simulated constant
def test_sim_check_update_rewrites_the_file_as_sim_check_update(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv("SOURCE_DATE_EPOCH", "86400")  # the provenance comment's date
    api_file = _drifted(tmp_path, "api.afsm")
    cli_file = tmp_path / "cli.afsm"
    shutil.copy(api_file, cli_file)
    res = afsmc.load(str(api_file)).sim_check(update=True)
    cli = run_cli("sim-check", str(cli_file), "--update")
    assert cli.code == 0 and res.ok
    assert [e.name for e in res.updated] == ["T_AP"]
    assert api_file.read_text() == cli_file.read_text() != MISSION.read_text()
