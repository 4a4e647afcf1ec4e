"""`afsmc regions` over the box of a file's interval probability comes to `afsmc verify`'s
verdict on the same requirement (issue 44): patrol.afsm with P_FAULT = [0.005, 0.03], an
MDP (MOVE_COST is an interval constant) and a DTMC (MOVE_COST fixed). The regions at the
ends of the box agree with `verify` on the file with P_FAULT fixed there."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from tests.conftest import EXAMPLES, run_cli

pytestmark = [pytest.mark.storm, pytest.mark.slow]

BOX = (0.005, 0.03)


def patrol(tmp_path: Path, p_fault: str, mdp: bool = True) -> str:
    text = (EXAMPLES / "patrol.afsm").read_text(encoding="utf-8")
    text = text.replace("const prob P_FAULT  = 0.01;", f"const prob P_FAULT  = {p_fault};")
    if not mdp:
        text = text.replace("const int MOVE_COST = [1, 2];", "const int MOVE_COST = 1;")
    path = tmp_path / f"patrol-{p_fault.strip('[]').replace(', ', '-')}-{mdp}.afsm"
    path.write_text(text, encoding="utf-8")
    return str(path)


def verdict_of_verify(path: str, req: str) -> str:
    r = run_cli("verify", path, "-f", req, "--json")
    assert r.code in (0, 1), r.err
    (p,) = json.loads(r.out)["properties"]
    return str(p["verdict"])


@pytest.mark.parametrize(("bound", "mdp"), [(0.5, True), (0.6, True), (0.9, True),
                                            (0.95, True), (0.55, False), (0.7, False),
                                            (0.95, False)])
def test_regions_over_the_interval_come_to_verifys_verdict(tmp_path: Path, bound: float,
                                                           mdp: bool) -> None:
    path = patrol(tmp_path, f"[{BOX[0]}, {BOX[1]}]", mdp)
    req = f'P>={bound} [ F "done" ]'
    r = run_cli("regions", path, "--require", req, "--json")
    assert r.code == 0, r.err
    out = json.loads(r.out)
    assert out["box"] == {"P_FAULT": list(BOX)} and out["from_file"] == ["P_FAULT"]
    assert out["verdict"] == verdict_of_verify(path, req), out["reason"]
    verdicts = {reg["verdict"] for reg in out["regions"]}
    if out["verdict"] == "depends" and not mdp:
        assert {"holds", "fails"} <= verdicts  # one value per point: the box is mixed
    # each end of the box: a region decided there says what verify says at that value
    for end in BOX:
        (there,) = [reg for reg in out["regions"]
                    if reg["bounds"]["P_FAULT"][0] <= end <= reg["bounds"]["P_FAULT"][1]]
        if there["verdict"] == "unknown":
            continue
        at = verdict_of_verify(patrol(tmp_path, repr(end), mdp), req)
        # a region holds where every choice meets it (verify: holds), fails where some
        # choice misses it (verify: fails, or depends on an MDP)
        if there["verdict"] == "holds":
            assert at == "holds"
        else:
            assert at in (("fails", "depends") if mdp else ("fails",))


def test_the_box_of_issue_44_is_mixed_and_verify_says_depends(tmp_path: Path) -> None:
    path = patrol(tmp_path, f"[{BOX[0]}, {BOX[1]}]")
    req = 'P>=0.6 [ F "done" ]'
    assert verdict_of_verify(path, req) == "depends"
    r = run_cli("regions", path, "--require", req, "--summary")
    assert r.code == 0, r.err
    assert "from the file: P_FAULT in [0.005, 0.03]" in r.out
    assert "over the whole box: depends" in r.out
    # the summary only: no table of regions
    assert not [line for line in r.out.splitlines()
                if line.endswith(("holds", "fails", "unknown"))], r.out
    out = json.loads(run_cli("regions", path, "--require", req, "--json").out)
    assert {reg["verdict"] for reg in out["regions"]} >= {"holds", "fails"}
    assert out["holds"] > 0 and out["fails"] > 0
