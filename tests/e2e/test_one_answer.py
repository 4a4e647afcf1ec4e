"""One question, one answer: a requirement over interval probabilities gets the same bounds
and verdict from `verify` (text, --json, --junit), `sweep`, `regions` over the same box and
the Python API, and the JSON's min and max are those bounds (docs/verification.md, "What a
result means").

The oracle for the bounds is Storm's ordinary engine at fixed values of the interval
probability: every fixed P_FAULT in the box gives a value within [min, max] (up to the
stated error), and the ends of the box, where the extremes lie for this monotone property,
come within the error of min and max.
"""

from __future__ import annotations

import csv
import io
import json
import xml.etree.ElementTree as ET
from pathlib import Path

import pytest

import afsmc
from tests.conftest import EXAMPLES, run_cli

pytestmark = [pytest.mark.storm, pytest.mark.slow]

REQ = 'P>=0.6 [ F "done" ]'
BOX = (0.005, 0.03)


def _patrol(tmp_path: Path, prob: str) -> Path:
    spec = tmp_path / f"patrol_{prob.replace(' ', '').replace(',', '_')}.afsm"
    spec.write_text((EXAMPLES / "patrol.afsm").read_text(encoding="utf-8").replace(
        "const prob P_FAULT  = 0.01;", f"const prob P_FAULT  = {prob};"), encoding="utf-8")
    return spec


@pytest.fixture(scope="module")
def spec(tmp_path_factory: pytest.TempPathFactory) -> Path:
    return _patrol(tmp_path_factory.mktemp("one"), f"[{BOX[0]}, {BOX[1]}]")


@pytest.fixture(scope="module")
def verified(spec: Path) -> dict[str, object]:
    r = run_cli("verify", str(spec), "-f", REQ, "--json")
    assert r.code == 1, r.err  # a requirement that does not hold everywhere
    out: dict[str, object] = json.loads(r.out)
    return out


def _prop(verified: dict[str, object]) -> dict[str, object]:
    props = verified["properties"]
    assert isinstance(props, list)
    p = props[0]
    assert isinstance(p, dict)
    return p


def test_verify_json_min_and_max_are_the_bounds_over_the_box(verified: dict[str, object]
                                                            ) -> None:
    p = _prop(verified)
    box = verified["probability_intervals"]
    assert isinstance(box, dict)
    (e,) = box["properties"]
    assert (p["min"], p["max"]) == (e["min_attained"], e["max_attained"])
    assert p["verdict"] == "depends" and p["decided_by"] == "min"
    assert verified["uncertainty"] == ["interval constants", "interval probabilities"]


def test_the_bounds_contain_every_fixed_value_and_are_reached_at_the_ends(
        tmp_path: Path, verified: dict[str, object]) -> None:
    p = _prop(verified)
    lo, hi, err = p["min"], p["max"], p["error"]
    assert isinstance(lo, float) and isinstance(hi, float) and isinstance(err, float)
    fixed = {}
    for x in (BOX[0], 0.0125, 0.02, BOX[1]):
        r = run_cli("verify", str(_patrol(tmp_path, repr(x))), "-f", REQ, "--json")
        q = json.loads(r.out)["properties"][0]
        assert lo - err <= q["min"] <= q["max"] <= hi + err, (x, q)
        fixed[x] = q
    # the fault rate lowers the chance to finish: the extremes are at the box's ends
    assert abs(fixed[BOX[1]]["min"] - lo) <= err + 1e-6
    assert abs(fixed[BOX[0]]["max"] - hi) <= err + 1e-6


def test_verify_text_shows_the_same_bounds_and_verdict(spec: Path,
                                                       verified: dict[str, object]) -> None:
    p = _prop(verified)
    out = run_cli("verify", str(spec), "-f", REQ).out
    lines = out.splitlines()
    head = next(i for i, line in enumerate(lines) if line.startswith("property"))
    columns = lines[head].split()
    cells = dict(zip(columns[2:], lines[head + 1].split()[-(len(columns) - 2):], strict=True))
    assert float(cells["min"]) == pytest.approx(p["min"], abs=1e-6)
    assert float(cells["max"]) == pytest.approx(p["max"], abs=1e-6)
    assert cells["verdict"] == "depends"
    assert "midpoint" in cells  # the reference point, in a column of its own


def test_junit_fails_the_requirement_with_the_bounds(spec: Path, tmp_path: Path,
                                                     verified: dict[str, object]) -> None:
    report = tmp_path / "r.xml"
    assert run_cli("verify", str(spec), "-f", REQ, "--junit", str(report)).code == 1
    failure = ET.parse(report).getroot().find("./testsuite/testcase/failure")
    assert failure is not None and failure.get("type") == "depends"
    p = _prop(verified)
    message = failure.get("message") or ""
    assert f"min {p['min']:.6g}" in message and f"max {p['max']:.6g}" in message


def test_sweep_json_and_csv_give_the_same_bounds_and_verdict(
        spec: Path, tmp_path: Path, verified: dict[str, object]) -> None:
    p = _prop(verified)
    r = run_cli("sweep", str(spec), "--const", "CELLS=4:4", "-f", REQ, "--json")
    assert r.code == 0, r.err  # a sweep's verdicts are answers (docs/verification.md)
    (q,) = json.loads(r.out)["points"][0]["properties"]
    assert abs(q["min"] - p["min"]) <= 1e-9 and abs(q["max"] - p["max"]) <= 1e-9
    assert (q["verdict"], q["reason"]) == (p["verdict"], p["reason"])
    out = tmp_path / "s.csv"
    run_cli("sweep", str(spec), "--const", "CELLS=4:4", "-f", REQ, "-o", str(out))
    (row,) = csv.DictReader(io.StringIO(out.read_text(encoding="utf-8")))
    assert row["verdict"] == "depends"
    assert abs(float(row["min"]) - p["min"]) <= 1e-9


def test_regions_over_the_box_give_the_same_bounds_and_verdict(
        spec: Path, verified: dict[str, object]) -> None:
    p = _prop(verified)
    r = run_cli("regions", str(spec), "--require", REQ, "--json")
    assert r.code == 0, r.err
    out = json.loads(r.out)
    assert out["box"] == {"P_FAULT": list(BOX)} and out["from_file"] == ["P_FAULT"]
    assert abs(out["min"] - p["min"]) <= 1e-9 and abs(out["max"] - p["max"]) <= 1e-9
    assert (out["verdict"], out["reason"]) == (p["verdict"], p["reason"])


def test_the_python_api_renders_the_same_answer(spec: Path,
                                                verified: dict[str, object]) -> None:
    p = _prop(verified)
    res = afsmc.load(str(spec)).verify(formulas=[REQ])
    got = res["adhoc"]
    assert got.verdict is not None and got.verdict.kind == "depends"
    assert abs(got.min - p["min"]) <= 1e-9 and abs(got.max - p["max"]) <= 1e-9
    df = res.to_pandas()
    assert df.loc["adhoc", "verdict"] == "depends"
    assert df.loc["adhoc", "min"] == got.min
    assert "depends" in res._repr_html_()
