"""`afsmc verify --baseline old.json`: a change to a probability in the spec that turns a
requirement from holds to fails is flagged and exits 1; a bound that moves within the
tolerance is not flagged; a bad baseline is E418. The JSON's "baseline" validates
against the published schema."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from afsmc.answer.schema import typed
from afsmc.report.baseline import compare
from tests.conftest import EXAMPLES, run_cli

pytestmark = pytest.mark.storm

REQUIREMENT = '\nproperty fault_low = P<=0.2 [ F "halted" ];\n'


def _spec(tmp: Path, fault: str) -> Path:
    text = (EXAMPLES / "patrol.afsm").read_text(encoding="utf-8") + REQUIREMENT
    path = tmp / "patrol.afsm"
    path.write_text(text.replace("const prob P_FAULT  = 0.01;",
                                 f"const prob P_FAULT  = {fault};"), encoding="utf-8")
    return path


def test_a_flip_to_worse_is_flagged_and_exits_1(tmp_path: Path) -> None:
    spec = _spec(tmp_path, "0.01")
    old = run_cli("verify", str(spec), "-p", "fault_low", "-p", "finish", "--json")
    assert old.code == 0, old.err
    base = tmp_path / "old.json"
    base.write_text(old.out, encoding="utf-8")
    _spec(tmp_path, "0.02")  # twice the faults: the max is 0.33, no longer <= 0.2
    new = run_cli("verify", str(spec), "-p", "fault_low", "-p", "finish", "--baseline",
                  str(base), "--json")
    assert new.code == 1, new.err
    data = json.loads(new.out)
    typed("verify", data)  # the published schema
    changes = {c["name"]: c for c in data["baseline"]["changes"]}
    assert changes["fault_low"]["old_verdict"] == "holds"
    assert changes["fault_low"]["new_verdict"] == "fails"
    assert changes["fault_low"]["flipped"] and changes["fault_low"]["worse"]
    assert changes["finish"]["flagged"] and not changes["finish"]["flipped"]
    old_props = {p["name"]: p for p in json.loads(old.out)["properties"]}
    new_props = {p["name"]: p for p in data["properties"]}
    for name, c in changes.items():
        for k in ("min", "max"):
            assert c["old"][k] == old_props[name][k] and c["new"][k] == new_props[name][k]
    text = run_cli("verify", str(spec), "-p", "fault_low", "--baseline", str(base))
    assert text.code == 1 and "WORSE" in text.out


def test_no_change_exits_0_and_flags_nothing(tmp_path: Path) -> None:
    spec = _spec(tmp_path, "0.01")
    old = run_cli("verify", str(spec), "-p", "fault_low", "--json")
    base = tmp_path / "old.json"
    base.write_text(old.out, encoding="utf-8")
    again = run_cli("verify", str(spec), "-p", "fault_low", "--baseline", str(base), "--json")
    assert again.code == 0, again.err
    (c,) = json.loads(again.out)["baseline"]["changes"]
    assert not c["flagged"] and c["moved"] == 0


def test_a_move_within_the_tolerance_is_not_flagged() -> None:
    old = {"properties": [{"name": "p", "min": 0.5, "max": 0.6, "value": None,
                           "verdict": "holds"}]}
    new = {"properties": [{"name": "p", "min": 0.5, "max": 0.61, "value": None,
                           "verdict": "holds"}, {"name": "q", "value": 1.0}]}
    (p, q) = compare(old, new, tolerance=0.02).changes
    assert p.moved == pytest.approx(0.01) and not p.flagged and not p.worse
    assert q.only == "new" and q.flagged
    (p, _) = compare(old, new, tolerance=0.005).changes
    assert p.flagged and not p.flipped
    better = compare({"properties": [{"name": "p", "value": 0.1, "verdict": "fails"}]},
                     {"properties": [{"name": "p", "value": 0.9, "verdict": "holds"}]})
    assert better.changes[0].flipped and not better.changes[0].worse


@pytest.mark.parametrize(("content", "words"), [
    ("not json", "is not JSON"),
    ('{"points": [], "properties": []}', "not the output of `afsmc verify --json`"),
    ('{"machine": "uav", "properties": []}', "machine uav, not patrol"),
    ('[1, 2]', "expected an object"),
])
def test_a_bad_baseline_is_e418(tmp_path: Path, content: str, words: str) -> None:
    base = tmp_path / "old.json"
    base.write_text(content, encoding="utf-8")
    r = run_cli("verify", str(EXAMPLES / "patrol.afsm"), "-p", "fault", "--baseline",
                str(base))
    assert r.code == 1 and "E418" in r.err and words in r.err, r.err
