"""`afsmc conform FILE LOGS...` on runs that `afsmc simulate --traces-out` writes in the
robot's log format (docs/robot.md): runs simulated from the spec conform (no violation,
no drift); runs simulated from a copy with one outcome probability doubled flag exactly
that constant; a log with one impossible step gets an E720 at that line; bad logs get
E711-E713 at their lines, never a traceback; `--json` is valid under its published
schema; `--update` rewrites the drifted figure with provenance.

The fast cases simulate 1,000 runs of uav.afsm (the doubled probability is ALPHA, drawn
at every searched square, so that 1,000 runs tell 0.4 from 0.2); the issue's own figures,
10,000 runs and the doubled P_DROP_LIFT, are the `slow` case."""

from __future__ import annotations

import json
from pathlib import Path

import jsonschema
import pytest

from afsmc.answer.schema import schema
from tests.conftest import EXAMPLES, run_cli

UAV = EXAMPLES / "uav.afsm"
PATROL = EXAMPLES / "patrol.afsm"


def simulate(spec: Path, out: Path, runs: int, seed: int = 1) -> Path:
    r = run_cli("simulate", str(spec), "--runs", str(runs), "--traces", str(runs),
                "--seed", str(seed), "--traces-out", str(out))
    assert r.code == 0, r.err
    return out


def doubled(tmp: Path, name: str, old: str) -> Path:
    """A copy of uav.afsm whose constant `name` is twice `old`."""
    text = UAV.read_text(encoding="utf-8")
    line = f"{name} = {old}"
    assert line in text
    new = f"{float(old) * 2:g}"
    copy = tmp / "uav_doubled.afsm"
    copy.write_text(text.replace(line, f"{name} = {new}"), encoding="utf-8")
    return copy


def conform(*args: str) -> dict[str, object]:
    r = run_cli("conform", *args, "--json")
    assert "Traceback" not in r.err, r.err
    out = json.loads(r.out)
    jsonschema.validate(out, schema("conform"))
    assert r.code == (0 if not out.get("violations") and not out.get("diagnostics") else 1)
    return out  # type: ignore[no-any-return]


def drifted(out: dict[str, object]) -> list[str]:
    consts = out["constants"]
    assert isinstance(consts, list)
    return [c["name"] for c in consts if c["verdict"] == "drifted"]


@pytest.fixture(scope="module")
def uav_runs(tmp_path_factory: pytest.TempPathFactory) -> Path:
    return simulate(UAV, tmp_path_factory.mktemp("logs") / "uav.jsonl", 1000)


def test_simulated_runs_conform(uav_runs: Path) -> None:
    out = conform(str(UAV), str(uav_runs))
    assert out["violations"] == [] and drifted(out) == []
    assert out["runs"] == 1000 and isinstance(out["steps"], int) and out["steps"] > 10_000
    names = {c["name"] for c in out["constants"]}  # type: ignore[attr-defined]
    assert {"ALPHA", "P_EMERGENCY", "P_DROP_LIFT", "T_MOVE", "T_FLY"} <= names


def test_runs_of_a_spec_with_one_probability_doubled_flag_exactly_it(tmp_path: Path) -> None:
    logs = simulate(doubled(tmp_path, "ALPHA", "0.2"), tmp_path / "runs.jsonl", 1000)
    out = conform(str(UAV), str(logs))
    assert out["violations"] == [] and drifted(out) == ["ALPHA"]
    assert [d["code"] for d in out["diagnostics"]] == ["E721"]  # type: ignore[index]


@pytest.mark.slow
def test_ten_thousand_runs_conform_and_a_doubled_probability_is_flagged(tmp_path: Path) -> None:
    out = conform(str(UAV), str(simulate(UAV, tmp_path / "uav.jsonl", 10_000)))
    assert out["violations"] == [] and drifted(out) == []
    logs = simulate(doubled(tmp_path, "P_DROP_LIFT", "0.047"), tmp_path / "drop.jsonl", 10_000)
    out = conform(str(UAV), str(logs))
    assert out["violations"] == [] and drifted(out) == ["P_DROP_LIFT"]


def test_csv_logs_conform_as_json_lines_do(tmp_path: Path) -> None:
    logs = simulate(PATROL, tmp_path / "patrol.csv", 300)
    assert logs.read_text(encoding="utf-8").startswith(
        "run,step,mode,action,outcome,duration,changes\n")
    out = conform(str(PATROL), str(logs))
    assert out["violations"] == [] and drifted(out) == [] and out["runs"] == 300


def _first_step_changed(src: Path, dst: Path, fields: dict[str, object]) -> Path:
    """The runs of `src`, but for run 0 only its first step, changed by `fields` (a None
    removes the key): one impossible step, after which run 0 has no step to go wrong."""
    lines = src.read_text(encoding="utf-8").splitlines()
    step = json.loads(lines[0])
    assert step["run"] == 0 and step["action"] == "Move" and step["mode"] == "Patrol"
    for k, v in fields.items():
        if v is None:
            del step[k]
        else:
            step[k] = v
    rest = [x for x in lines if json.loads(x)["run"] != 0]
    assert rest
    dst.write_text("\n".join([json.dumps(step), *rest]) + "\n", encoding="utf-8")
    return dst


@pytest.mark.parametrize(("fields", "said"), [
    ({"action": "GoDock"}, "the spec chooses Move here, not GoDock"),
    ({"duration": 3}, "duration 3 of MOVE_COST is outside its interval [1, 2]"),
    ({"changes": {"cell": 3, "battery": 18}, "outcome": None},
     "no outcome of Move makes these changes"),
    ({"changes": {"cell": 1, "battery": 17}}, "battery becomes 17, the outcome makes it"),
    ({"outcome": 7}, "Move has no outcome 7"),
])
def test_an_impossible_step_is_reported_at_its_line(tmp_path: Path, fields: dict[str, object],
                                                     said: str) -> None:
    logs = simulate(PATROL, tmp_path / "p.jsonl", 5)
    bad = _first_step_changed(logs, tmp_path / "bad.jsonl", fields)
    out = conform(str(PATROL), str(bad))
    violations = out["violations"]
    assert isinstance(violations, list) and len(violations) == 1, violations
    v = violations[0]
    assert v["code"] == "E720" and v["file"] == str(bad) and v["line"] == 1
    assert said in v["message"] and "state: mode=Patrol cell=0 battery=20 rounds=0" in v["message"]
    r = run_cli("conform", str(PATROL), str(bad))
    assert r.code == 1 and f"{bad}:1:1: error[E720]" in r.err


BAD_JSONL = [
    ('{"action": "Move", "outcome": 0, "duration": 1}', "E712", "the step has no 'mode'"),
    ('{"mode": "Nowhere", "action": "Move", "outcome": 0, "duration": 1}', "E713",
     "patrol declares no mode 'Nowhere'"),
    ('{"mode": "Patrol", "action": "Fly", "outcome": 0}', "E713", "no action 'Fly'"),
    ('{"mode": "Patrol", "action": "Move", "outcome": 0, "duration": "fast"}', "E712",
     "'duration' is \"fast\""),
    ('{"mode": "Patrol", "action": "Move", "outcome": 0, "dura', "E711", "truncated?"),
    ('["Patrol", "Move"]', "E711", "is a JSON list, not an object"),
    ('{"mode": "Patrol", "action": "Move"}', "E712", "neither 'outcome' nor 'changes'"),
    ('{"mode": "Patrol", "action": "Move", "changes": {"cell": "x"}}', "E712",
     "cell = x in 'changes' is not an int in [0, 4]"),
]


def test_bad_json_lines_are_each_an_error_at_its_line(tmp_path: Path) -> None:
    log = tmp_path / "bad.jsonl"
    good = '{"mode": "Patrol", "action": "Move", "outcome": 0, "duration": 1}'
    log.write_text("\n".join([good] + [b for b, _, _ in BAD_JSONL]) + "\n", encoding="utf-8")
    r = run_cli("conform", str(PATROL), str(log))
    assert r.code == 1 and "Traceback" not in r.err
    for i, (_, code, said) in enumerate(BAD_JSONL, 2):
        line = next((x for x in r.err.splitlines() if x.startswith(f"{log}:{i}:")), "")
        assert f"error[{code}]" in line and said in line, (i, r.err)
    out = json.loads(run_cli("conform", str(PATROL), str(log), "--json").out)
    jsonschema.validate(out, schema("conform"))
    assert sorted(d["line"] for d in out["diagnostics"]) == list(range(2, 2 + len(BAD_JSONL)))


def test_bad_csv_rows_and_unreadable_logs(tmp_path: Path) -> None:
    log = tmp_path / "bad.csv"
    log.write_text("mode,action,outcome,duration\nPatrol,Move,0,abc\nPatrol,Move\n"
                   "Patrol,Move,0,1\n", encoding="utf-8")
    r = run_cli("conform", str(PATROL), str(log))
    assert r.code == 1 and "Traceback" not in r.err
    assert f"{log}:2:1: error[E712]: line 2: 'duration' is \"abc\"" in r.err
    assert f"{log}:3:1: error[E711]: line 3 has 2 cells, the header 4: truncated?" in r.err
    missing = tmp_path / "none.jsonl"
    r = run_cli("conform", str(PATROL), str(missing))
    assert r.code == 1 and f"error[E710]: cannot read log {missing}" in r.err
    header = tmp_path / "h.csv"
    header.write_text("state,act\nPatrol,Move\n", encoding="utf-8")
    r = run_cli("conform", str(PATROL), str(header))
    assert r.code == 1 and "error[E712]" in r.err and "no column mode, action" in r.err


def test_a_composed_mission_is_refused() -> None:
    r = run_cli("conform", str(EXAMPLES / "two_uav.afsm"), str(PATROL))
    assert r.code == 1 and "error[E701]: 'conform' replays the logs of one machine" in r.err


def test_update_rewrites_the_drifted_figure_with_provenance(tmp_path: Path) -> None:
    text = PATROL.read_text(encoding="utf-8")
    assert "const prob P_SLIP   = 0.1;" in text
    slippery = tmp_path / "slippery.afsm"
    slippery.write_text(text.replace("P_SLIP   = 0.1;", "P_SLIP   = 0.2;"), encoding="utf-8")
    logs = simulate(slippery, tmp_path / "runs.jsonl", 300)
    spec = tmp_path / "patrol.afsm"
    spec.write_text(text, encoding="utf-8")
    out = conform(str(spec), str(logs))
    assert drifted(out) == ["P_SLIP"] and out["updated"] == []
    r = run_cli("conform", str(spec), str(logs), "--update")
    assert r.code == 0, r.err
    assert "conform: updated 1 constant(s)" in r.err
    line = next(x for x in spec.read_text(encoding="utf-8").splitlines()
                if x.startswith("const prob P_SLIP"))
    assert "// sim-check: logs runs.jsonl," in line, line
    assert drifted(conform(str(spec), str(logs))) == []  # the figure now agrees with the logs


def test_a_drifted_param_is_reported_not_rewritten(tmp_path: Path) -> None:
    logs = simulate(doubled(tmp_path, "ALPHA", "0.2"), tmp_path / "runs.jsonl", 1000)
    spec = tmp_path / "uav.afsm"
    spec.write_text(UAV.read_text(encoding="utf-8"), encoding="utf-8")
    r = run_cli("conform", str(spec), str(logs), "--update")
    assert r.code == 1 and "error[E721]: param 'ALPHA' = 0.2 has drifted" in r.err
    assert "a param is not rewritten" in r.err
    assert spec.read_text(encoding="utf-8") == UAV.read_text(encoding="utf-8")


def test_each_log_without_run_ids_is_one_run(tmp_path: Path) -> None:
    logs = simulate(PATROL, tmp_path / "p.jsonl", 3)
    files = []
    for r in range(3):
        f = tmp_path / f"run{r}.jsonl"
        steps = [json.loads(x) for x in logs.read_text(encoding="utf-8").splitlines()]
        f.write_text("".join(json.dumps({k: v for k, v in s.items() if k != "run"}) + "\n"
                             for s in steps if s["run"] == r), encoding="utf-8")
        files.append(str(f))
    out = conform(str(PATROL), *files)
    assert out["runs"] == 3 and out["violations"] == []


def test_the_python_api_gives_the_command_s_answer(tmp_path: Path) -> None:
    import afsmc

    logs = simulate(PATROL, tmp_path / "p.jsonl", 100)
    res = afsmc.load(str(PATROL)).conform([str(logs)])
    assert res.ok and res.runs == 100 and not res.violations
    assert res.to_json() == conform(str(PATROL), str(logs))
    text = afsmc.load(str(PATROL)).text.replace("P_SLIP   = 0.1;", "P_SLIP   = 0.5;")
    drifted_ = afsmc.Mission.from_text(text).conform([str(logs)])
    assert not drifted_.ok and [d.code for d in drifted_.errors] == ["E721"]


AMBIGUOUS = """machine amb;
const prob P_UP = 0.3;
var n : [0..3] init 0;
mode A = 0 initial;
mode Done = 1 final;
action Tick in A when n < 3 { P_UP: n := n + 1; 1 - P_UP: n := n + 1; }
action Stop in A when n == 3 { goto Done; }
"""


def test_changes_that_fit_several_outcomes_are_no_evidence_of_which(tmp_path: Path) -> None:
    spec = tmp_path / "amb.afsm"
    spec.write_text(AMBIGUOUS, encoding="utf-8")
    log = tmp_path / "amb.jsonl"
    log.write_text("".join(json.dumps({"mode": "A", "action": "Tick", "changes": {"n": n}})
                           + "\n" for n in (1, 2, 3))
                   + json.dumps({"mode": "A", "action": "Stop", "changes": {"mode": "Done"}})
                   + "\n", encoding="utf-8")
    out = conform(str(spec), str(log))
    assert out["violations"] == [] and out["steps"] == 4 and out["ambiguous"] == 3
    assert out["constants"] == [] and out["unexercised"] == ["P_UP"]


@pytest.mark.parametrize("name", ["patrol", "warehouse", "drone", "auv", "rover", "overtake"])
def test_simulated_runs_of_every_single_agent_example_conform(name: str, tmp_path: Path) -> None:
    spec = EXAMPLES / f"{name}.afsm"
    out = conform(str(spec), str(simulate(spec, tmp_path / "runs.jsonl", 200)))
    assert out["violations"] == [] and drifted(out) == [] and out["runs"] == 200
