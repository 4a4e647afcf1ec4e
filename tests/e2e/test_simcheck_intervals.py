"""`afsmc sim-check` on interval probabilities (`const prob P = [lo, hi] from sim ...`):
consistent when the interval covers the runs' Clopper-Pearson interval at the confidence
the file or `--confidence` states; `--update` writes that interval, rounded outwards."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import pytest

from afsmc.sim import stats
from afsmc.simlib import registry
from tests.conftest import run_cli

REF = "uav.transport.drop"
RUNS = 3000

SPEC = """
machine carry;
const prob P_DROP = {value} from sim uav.transport.drop{policy};
var left : [0..2] init 2;
mode Carry = 0 initial;
mode Done = 1 final;
action Step in Carry when left > 0 {{
    P_DROP: left := left;
    1 - P_DROP: left -= 1;
}}
action Finish in Carry when left == 0 {{ goto Done; }}
label done = mode == Done;
property done = P=? [ F<=4 "done" ];
"""


def spec(tmp_path: Path, value: str, policy: str = "") -> Path:
    path = tmp_path / "carry.afsm"
    path.write_text(SPEC.format(value=value, policy=policy))
    return path


def interval(confidence: float) -> tuple[float, float]:
    """The oracle: the Clopper-Pearson interval of the simulator's own samples."""
    k = int(registry.sample(REF, RUNS, 0).sum())
    return stats.clopper_pearson(k, RUNS, confidence)


def check(path: Path, *args: str) -> tuple[int, dict[str, Any]]:
    r = run_cli("sim-check", str(path), "--runs", str(RUNS), "--json", *args)
    return r.code, json.loads(r.out)


def test_covering_the_runs_interval_is_consistent_and_narrower_drifts(tmp_path: Path) -> None:
    low, high = interval(0.95)
    wide = f"[{low * 0.9:.6f}, {min(1.0, high * 1.1):.6f}]"
    code, data = check(spec(tmp_path, wide, " with confidence = 0.95"))
    (c,) = data["constants"]
    assert code == 0 and c["verdict"] == "consistent", data
    assert c["shape"] == "probability interval" and c["method"] == "Clopper-Pearson"
    assert (c["mean_low"], c["mean_high"]) == pytest.approx((low, high))
    # an interval that leaves out part of the runs' interval has drifted (E502)
    narrow = f"[{(low + high) / 2:.6f}, {high * 1.1:.6f}]"
    code, data = check(spec(tmp_path, narrow, " with confidence = 0.95"))
    assert code == 1 and data["constants"][0]["verdict"] == "drifted"
    assert [d["code"] for d in data["diagnostics"]] == ["E502"]


def test_the_files_confidence_wins_over_the_flag(tmp_path: Path) -> None:
    low95, high95 = interval(0.95)
    low999, _ = interval(0.999)
    # covers the 95% interval, not the 99.9% one
    value = f"[{low95 - 1e-6:.6f}, {high95 + 1e-6:.6f}]"
    assert low999 < low95
    code, data = check(spec(tmp_path, value))  # default 0.999
    assert code == 1 and data["constants"][0]["confidence"] == 0.999
    code, data = check(spec(tmp_path, value), "--confidence", "0.95")
    assert code == 0 and data["constants"][0]["confidence"] == 0.95
    code, data = check(spec(tmp_path, value, " with confidence = 0.999"), "--confidence", "0.95")
    assert code == 1 and data["constants"][0]["confidence"] == 0.999
    r = run_cli("sim-check", str(spec(tmp_path, value)), "--confidence", "1.5")
    assert r.code == 2 and "--confidence" in r.err


def test_update_writes_the_runs_interval_rounded_outwards(tmp_path: Path,
                                                          monkeypatch: Any) -> None:
    monkeypatch.setenv("SOURCE_DATE_EPOCH", "86400")
    path = spec(tmp_path, "[0.2, 0.3]", " with confidence = 0.95")
    r = run_cli("sim-check", str(path), "--runs", str(RUNS), "--update")
    assert r.code == 0, r.err
    line = next(x for x in path.read_text().splitlines() if x.startswith("const prob P_DROP"))
    written = json.loads(line.split(" = ", 1)[1].split(" from", 1)[0])
    low, high = interval(0.95)
    assert written[0] <= low and high <= written[1]
    assert written[1] - written[0] <= (high - low) * 1.05 + 1e-12
    assert f"// sim-check: {REF}, {RUNS} runs, seed 0, 1970-01-02" in line
    code, data = check(path)  # and now it is consistent
    assert code == 0 and data["constants"][0]["verdict"] == "consistent"
    # the rewritten file verifies, over the interval (Storm's parametric engine)
    v = run_cli("verify", str(path), "--json")
    assert v.code == 0, v.err
    assert json.loads(v.out)["probability_intervals"]["box"] == {"P_DROP": written}


def test_coverage_is_no_policy_of_an_interval_probability(tmp_path: Path) -> None:
    r = run_cli("check", str(spec(tmp_path, "[0.01, 0.02]", " with coverage = 0.9")))
    assert r.code == 1 and "E504" in r.err
    assert "does not apply to the interval probability 'P_DROP'" in r.err


@pytest.mark.parametrize(("low", "high", "want"), [
    (0.0053424, 0.0141867, ("0.0053", "0.0142")),
    (0.2, 0.3, ("0.2", "0.3")),
    (0.0, 0.00123, ("0", "0.00123")),
    (0.9991, 1.0, ("0.9991", "1")),
])
def test_outward_decimals(low: float, high: float, want: tuple[str, str]) -> None:
    got = stats.outward_decimals(low, high)
    assert got == want
    assert float(got[0]) <= low and high <= float(got[1])
