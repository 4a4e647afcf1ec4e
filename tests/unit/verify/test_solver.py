"""`--solver`: how Storm solves the equations (an MDP's min/max, a DTMC's linear ones).
Value iteration (the hybrid engine's default) and Storm's topological solver must give the
same values, on acyclic missions (the UAV) and on cyclic ones (the patrol robot's dock loop,
a machine that may spin forever), on both engines, for the MDP and the uniform DTMC."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from afsmc.verify import run
from tests.conftest import EXAMPLES, run_cli
from tests.unit.backends.test_prism import SMALL
from tests.unit.verify.test_engine_choice import FOREVER, UAV, _close, _values

pytestmark = pytest.mark.storm

PATROL = str(EXAMPLES / "patrol.afsm")


@pytest.mark.slow
@pytest.mark.parametrize("engine", ["sparse", "hybrid"])
def test_value_iteration_gives_the_topological_solver_s_values_on_the_uav(engine: str) -> None:
    vi = run(UAV, consts=SMALL["uav"], engine=engine, isolate=False, solver="value-iteration")
    topo = run(UAV, consts=SMALL["uav"], engine=engine, isolate=False, solver="topological")
    assert vi.model.solver == "value-iteration" and topo.model.solver == "topological"
    # the uniform DTMC's linear equations too
    assert vi.uniform_model is not None and vi.uniform_model.solver == "value-iteration"
    assert topo.uniform_model is not None and topo.uniform_model.solver == "topological"
    # 1e-10 relative: on an acyclic mission the iteration reaches the fixed point
    _close(_values(vi), _values(topo), 1e-9)
    assert vi.model.states == topo.model.states


@pytest.mark.slow
@pytest.mark.parametrize("engine", ["sparse", "hybrid"])
def test_value_iteration_on_cyclic_machines(engine: str, tmp_path: Path) -> None:
    forever = tmp_path / "forever.afsm"
    forever.write_text(FOREVER, encoding="utf-8")
    for path in (PATROL, str(forever)):
        vi = run(path, engine=engine, isolate=False, solver="value-iteration")
        topo = run(path, engine=engine, isolate=False, solver="topological")
        # Inside a cycle the topological solver iterates too, to Storm's default relative
        # precision of 1e-6 (the patrol's expected duration, about 19, differs by 4e-8)
        _close(_values(vi), _values(topo), 1e-9, rel=1e-6)
        # and not a trivial agreement: the machines have choices that matter
        assert any(p.min is not None and p.max is not None and p.max - p.min > 1e-3
                   for p in topo.properties), path


@pytest.mark.slow
def test_auto_solver_is_value_iteration_on_hybrid_only() -> None:
    hybrid = run(UAV, consts=SMALL["uav"], engine="hybrid", isolate=False, uniform=False,
                 properties=["success"])
    sparse = run(UAV, consts=SMALL["uav"], engine="sparse", isolate=False, uniform=False,
                 properties=["success"])
    assert hybrid.model.solver == "value-iteration"
    # on sparse: one backward pass, as the UAV is acyclic (tests/unit/verify/test_acyclic.py)
    assert sparse.model.solver == "acyclic"
    _close(_values(hybrid), _values(sparse), 1e-9)
    # the dd engine iterates on decision diagrams whatever --solver says: no solver to name
    dd = run(PATROL, engine="dd", isolate=False, uniform=False, properties=["fault"],
             solver="value-iteration")
    assert dd.model.solver == "" and "solver" not in dd.model.to_json()


def test_cli_reports_the_solver_and_refuses_an_unknown_one() -> None:
    r = run_cli("verify", PATROL, "--json", "--solver", "value-iteration", "--no-uniform")
    assert r.code == 0, r.err
    assert json.loads(r.out)["model"]["solver"] == "value-iteration"
    r = run_cli("verify", PATROL, "--no-uniform")
    assert r.code == 0, r.err
    assert "solver" in r.out and "topological" in r.out, r.out
    r = run_cli("verify", PATROL, "--solver", "gauss")
    assert r.code == 2 and "invalid choice: 'gauss'" in r.err, r.err
    with pytest.raises(ValueError, match="solver"):
        run(PATROL, solver="gauss")  # type: ignore[arg-type]


@pytest.mark.slow
def test_sweep_takes_the_solver(tmp_path: Path) -> None:
    out = tmp_path / "sweep.json"
    args = ["sweep", PATROL, "--const", "CELLS=2:3", "--engine", "hybrid", "--no-uniform",
            "-p", "fault", "-o", str(out)]
    vi = run_cli(*args, "--solver", "value-iteration")
    assert vi.code == 0, vi.err
    first = json.loads(out.read_text(encoding="utf-8"))
    topo = run_cli(*args, "--solver", "topological")
    assert topo.code == 0, topo.err
    second = json.loads(out.read_text(encoding="utf-8"))
    a = [(r["min"], r["max"]) for pt in first["points"] for r in pt["properties"]]
    b = [(r["min"], r["max"]) for pt in second["points"] for r in pt["properties"]]
    assert len(a) == len(b) == 2
    for x, y in zip(a, b, strict=True):  # the patrol's dock loop: as above
        assert x == pytest.approx(y, rel=1e-6, abs=1e-9)
