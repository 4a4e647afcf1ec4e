"""Constants backed by a data file (`from data "PATH" column NAME`): parsed and formatted,
checked, judged by `afsmc sim-check` by the rules of simulators (the file's values standing
for the runs), rewritten by `--update`, and every bad file a diagnostic with a code."""

from __future__ import annotations

import json
import math
import random
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from afsmc.sim import stats
from tests.conftest import run_cli

SPEC = """machine carry;
const prob P_OK = {p} from data "runs.csv" column success with confidence = 0.95;
const int T_X = {t} from data "logs/t.csv" column "time (s)";
var left : [0..2] init 2;
var t : [0..40] init 0 clamp;
mode Carry = 0 initial;
mode Done = 1 final;
action Step in Carry when left > 0 {{
    P_OK: left -= 1, t += T_X;
    1 - P_OK: t += T_X;
}}
action Finish in Carry when left == 0 {{ goto Done; }}
label done = mode == Done;
property done = P=? [ F<=4 "done" ];
"""


def write_data(folder: Path, successes: list[int] | None = None,
               times: list[str] | None = None) -> tuple[list[int], list[float]]:
    rng = random.Random(1)
    ok = successes if successes is not None else [int(rng.random() < 0.85) for _ in range(400)]
    ts = times if times is not None else [f"{rng.gauss(2.0, 0.4):.3f}" for _ in range(1000)]
    (folder / "runs.csv").write_text("run,success\n" + "".join(
        f"{i},{v}\n" for i, v in enumerate(ok)))
    (folder / "logs").mkdir(exist_ok=True)
    (folder / "logs" / "t.csv").write_text("run,time (s)\n" + "".join(
        f"{i},{v}\n" for i, v in enumerate(ts)))
    return ok, [float(x) for x in ts] if times is None else []


def spec(folder: Path, p: str = "[0.8, 0.9]", t: str = "[1, 3]") -> Path:
    path = folder / "carry.afsm"
    path.write_text(SPEC.format(p=p, t=t))
    return path


def sim_check(path: Path, *args: str) -> tuple[int, dict[str, Any], str]:
    r = run_cli("sim-check", str(path), "--json", *args)
    return r.code, json.loads(r.out), r.err


def test_fmt_prints_a_data_source_back(tmp_path: Path) -> None:
    path = spec(tmp_path)
    r = run_cli("fmt", str(path))
    assert r.code == 0, r.err
    text = path.read_text()
    assert 'from data "runs.csv" column success with confidence = 0.95;' in text
    assert 'from data "logs/t.csv" column "time (s)";' in text
    assert run_cli("fmt", "--check", str(path)).code == 0


def test_judged_as_simulations_are_against_the_files_values(tmp_path: Path) -> None:
    ok, times = write_data(tmp_path)
    code, data, err = sim_check(spec(tmp_path))
    assert code == 0, err
    p, t = data["constants"]
    assert p["ref"] == 'data "runs.csv" column success' and p["seed"] is None
    assert p["runs"] == len(ok) and p["shape"] == "probability interval"
    # the oracle: the Clopper-Pearson interval of the file's outcomes at its confidence
    assert (p["mean_low"], p["mean_high"]) == pytest.approx(
        stats.clopper_pearson(sum(ok), len(ok), 0.95))
    assert p["verdict"] == ("consistent" if p["mean_low"] >= 0.8 and p["mean_high"] <= 0.9
                            else "drifted")
    # ... and the integer hull of the central 95% of the file's durations
    assert t["runs"] == len(times) and t["shape"] == "interval"
    xs = np.sort(np.asarray(times))
    assert t["hull"] == [math.floor(float(np.quantile(xs, 0.025))),
                         math.ceil(float(np.quantile(xs, 0.975)))]
    assert t["verdict"] == "consistent"


def test_update_rewrites_from_the_file(tmp_path: Path, monkeypatch: Any) -> None:
    monkeypatch.setenv("SOURCE_DATE_EPOCH", "86400")
    ok, _ = write_data(tmp_path)
    path = spec(tmp_path, p="[0.9, 0.95]", t="[3, 5]")
    code, data, _ = sim_check(path)
    assert code == 1 and [c["verdict"] for c in data["constants"]] == ["drifted", "drifted"]
    r = run_cli("sim-check", str(path), "--update")
    assert r.code == 0, r.err
    lines = path.read_text().splitlines()
    low, high = stats.clopper_pearson(sum(ok), len(ok), 0.95)
    p_line = lines[1]
    written = json.loads(p_line.split(" = ", 1)[1].split(" from", 1)[0])
    assert written[0] <= low and high <= written[1]
    assert p_line.endswith(f'// sim-check: data "runs.csv" column success, {len(ok)} rows, '
                           "1970-01-02")
    assert lines[2].startswith('const int T_X = [1, 3] from data "logs/t.csv" column "time (s)";')
    code, data, _ = sim_check(path)
    assert code == 0


def _error(tmp_path: Path, code: str) -> str:
    if not (tmp_path / "carry.afsm").exists():
        spec(tmp_path)
    r = run_cli("sim-check", str(tmp_path / "carry.afsm"))
    assert r.code == 1, r.err
    assert f"error[{code}]" in r.err, r.err
    assert "carry.afsm:" in r.err and "^^^" in r.err and "hint:" in r.err
    assert "Traceback" not in r.err
    return r.err


def test_a_missing_file_is_e510_with_the_path_tried(tmp_path: Path) -> None:
    spec(tmp_path)
    err = _error(tmp_path, "E510")
    assert "cannot read data file 'runs.csv' of constant 'P_OK': there is no such file" in err
    assert str(tmp_path / "runs.csv") in err  # relative to the spec, not the working folder


def test_a_missing_column_is_e511_with_the_closest_name(tmp_path: Path) -> None:
    write_data(tmp_path)
    path = spec(tmp_path)
    path.write_text(path.read_text().replace("column success", "column sucess"))
    err = _error(tmp_path, "E511")
    assert "has no column 'sucess'" in err and "did you mean 'success'?" in err


def test_a_cell_that_is_no_number_is_e512_and_never_code(tmp_path: Path) -> None:
    write_data(tmp_path, times=["2.1", "", "__import__('os').system('touch pwned')", "inf"])
    err = _error(tmp_path, "E512")
    assert "line 4 (not a number); line 5 (not finite)" in err
    assert "__import__" not in err  # a message never quotes the file's text
    assert not (tmp_path / "pwned").exists() and not Path("pwned").exists()


def test_an_empty_column_is_e513(tmp_path: Path) -> None:
    write_data(tmp_path, times=["", " "])
    err = _error(tmp_path, "E513")
    assert "holds no values for constant 'T_X'" in err


def test_an_outcome_other_than_0_or_1_is_e514(tmp_path: Path) -> None:
    write_data(tmp_path, successes=[1, 0, 2])
    (tmp_path / "runs.csv").write_text("run,success\n1,1\n2,true\n3,0.85\n")
    err = _error(tmp_path, "E514")
    assert "line 4 (not 0, 1, true or false)" in err and "0.85" not in err


def test_a_bool_from_data_and_a_bad_policy_are_check_errors(tmp_path: Path) -> None:
    path = tmp_path / "b.afsm"
    path.write_text(SPEC.format(p="[0.8, 0.9]", t="[1, 3]").replace(
        "machine carry;", 'machine carry;\nconst bool B = true from data "x.csv" column b;'))
    r = run_cli("check", str(path))
    assert r.code == 1 and "E503" in r.err and "cannot back a 'bool' constant 'B'" in r.err
    path.write_text(SPEC.format(p="[0.8, 0.9]", t="[1, 3]").replace(
        "with confidence = 0.95", "with coverage = 0.9"))
    r = run_cli("check", str(path))
    assert r.code == 1 and "E504" in r.err


@pytest.mark.parametrize(("wrong", "hint"), [
    ('from data runs.csv column success', "expected a quoted string"),
    ('from data "runs.csv" success', "expected 'column'"),
    ('from dat "runs.csv" column success', "expected 'data', 'sim'"),
])
def test_a_malformed_data_source_is_a_syntax_error(tmp_path: Path, wrong: str,
                                                   hint: str) -> None:
    path = spec(tmp_path)
    path.write_text(path.read_text().replace('from data "runs.csv" column success', wrong))
    r = run_cli("check", str(path))
    assert r.code == 1 and "error[E101]" in r.err and f"hint: {hint}" in r.err
    assert "carry.afsm:2:" in r.err and "^" in r.err
