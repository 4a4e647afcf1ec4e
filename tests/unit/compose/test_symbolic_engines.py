"""A mission whose agents write shared variables: afsmc's PRISM declares them global and
updates them in labelled commands, which Storm's sparse builder builds right and its
symbolic builder (dd, hybrid, and the count "auto" would take first) wrongly, with too
few states. Such a mission is refused on a symbolic engine via PRISM (E404), built sparse
by "auto", and via JANI the hybrid engine's values equal the sparse engine's."""

from __future__ import annotations

import json

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
