"""A mission whose agents write shared variables: afsmc's PRISM declares them global and
updates them in labelled commands, which Storm's sparse builder builds right and its
symbolic builder (dd, hybrid, and the count "auto" would take first) wrongly, with too
few states. Such a mission is refused on a symbolic engine via PRISM (E404), built sparse
by "auto", and via JANI the hybrid engine's values equal the sparse engine's."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from tests.conftest import EXAMPLES, run_cli

pytestmark = pytest.mark.storm

CHARGING = str(EXAMPLES / "charging.afsm")


def _values(*args: str) -> tuple[int, dict[str, tuple[float, float]]]:
    r = run_cli("verify", CHARGING, "--no-uniform", "--json", *args)
    assert r.code == 0, r.err
    d = json.loads(r.out)
    return d["model"]["states"], {p["name"]: (p["min"], p["max"]) for p in d["properties"]}


@pytest.mark.parametrize("engine", ["hybrid", "dd"])
def test_a_symbolic_engine_via_prism_is_refused_where_agents_write_shared_variables(
        engine: str) -> None:
    r = run_cli("verify", CHARGING, "--engine", engine, "-p", "shift")
    assert r.code == 1
    assert "E404" in r.out + r.err and "shared variables" in r.out + r.err
    assert "--via jani" in r.out + r.err


def test_auto_builds_such_a_mission_sparse_and_via_jani_hybrid_agrees() -> None:
    states, sparse = _values("--engine", "sparse")
    auto_states, auto = _values()
    assert (auto_states, auto) == (states, sparse)
    jani_states, jani = _values("--engine", "hybrid", "--via", "jani")
    assert jani_states == states
    for name, (lo, hi) in sparse.items():
        if lo is None:
            continue
        assert jani[name][0] == pytest.approx(lo, rel=1e-5, abs=1e-8)
        assert jani[name][1] == pytest.approx(hi, rel=1e-5, abs=1e-8)


TRIO = """machine trio;
compose interleaving;
const prob P_GRASP = 0.9;
agent Robot() {
    var done : [0..2] init 0;
    mode Work = 0 initial;
    mode Finished = 1 final;
    action Pick in Work when done < 2 { P_GRASP: done += 1; 1 - P_GRASP: goto Finished; }
    action Stop in Work when done == 2 { goto Finished; }
}
agents r1 = Robot(), r2 = Robot(), r3 = Robot();
label all = r1.done == 2 && r2.done == 2 && r3.done == 2;
property all = P=? [ F "all" ];
"""


def test_under_symmetry_the_agents_write_each_others_variables_so_the_same_holds(
        tmp_path: Path) -> None:
    """Three robots without a shared variable: under --symmetry each robot's move writes
    the others' variables (the canonical order), which the compiled PRISM declares global;
    a symbolic engine via PRISM is refused there (and not without --symmetry: the default
    then checks the mission whole and says why), auto builds sparse, and the value is the
    mission's whole (0.9^6)."""
    path = tmp_path / "trio.afsm"
    path.write_text(TRIO, encoding="utf-8")
    refused = run_cli("verify", str(path), "--symmetry", "--engine", "hybrid")
    assert refused.code == 1 and "E404" in refused.out + refused.err
    assert "each other's variables" in refused.out + refused.err
    whole = run_cli("verify", str(path), "--engine", "hybrid", "--json")
    assert whole.code == 0, whole.err
    assert json.loads(whole.out)["symmetry"]["reason"].startswith(
        "the hybrid engine via PRISM: the reduced agents write each other's variables")
    for args in ([], ["--symmetry"], ["--symmetry", "--via", "jani", "--engine", "hybrid"],
                 ["--via", "jani", "--engine", "hybrid"]):
        r = run_cli("verify", str(path), "--json", *args)
        assert r.code == 0, r.err
        (p,) = json.loads(r.out)["properties"]
        assert (p["min"], p["max"]) == pytest.approx((0.9 ** 6, 0.9 ** 6), rel=1e-6)
    (p,) = json.loads(whole.out)["properties"]
    assert (p["min"], p["max"]) == pytest.approx((0.9 ** 6, 0.9 ** 6), rel=1e-6)
