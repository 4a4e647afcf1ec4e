"""The composed examples through every tool: check, fmt, both routes into Storm (the same
states, transitions and values), the diagram, the language server's analysis, a sweep,
and a simulation whose confidence interval holds the exact value."""

from __future__ import annotations

import os

import pytest

from afsmc.api.mission import load as load_mission
from afsmc.backends.dot import source
from afsmc.compiler import load
from afsmc.lsp.analysis import analyse_fast, analyse_full
from afsmc.lsp.index import build
from afsmc.syntax.fmt import format_text
from afsmc.verify.core.api import run
from tests.conftest import ROOT

EXAMPLES = os.path.join(ROOT, "examples")
# small instances, so that each check takes about a second
SMALL = {"two_uav.afsm": {"OBJECTS": 1, "T_LIMIT": 25},
         "charging.afsm": {"ORDERS": 2, "T_LIMIT": 10},
         "charging_fleet.afsm": {"ORDERS": 2, "T_LIMIT": 10}}  # charging's robots as a template


def _path(name: str) -> str:
    return os.path.join(EXAMPLES, name)


@pytest.mark.parametrize("name", sorted(SMALL))
def test_an_example_checks_clean_and_is_formatted(name: str) -> None:
    checked = load(_path(name))
    assert checked.model.composition is not None
    assert not [d for d in checked.diagnostics if d.is_error]
    with open(_path(name), encoding="utf-8") as f:
        text = f.read()
    assert format_text(text, name) == text


@pytest.mark.storm
@pytest.mark.parametrize("name", sorted(SMALL))
def test_prism_and_jani_routes_agree(name: str) -> None:
    pytest.importorskip("stormpy")
    prism = run(_path(name), consts=SMALL[name], via="prism")
    jani = run(_path(name), consts=SMALL[name], via="jani")
    assert (prism.model.states, prism.model.transitions) == (jani.model.states,
                                                             jani.model.transitions)
    assert prism.model.states > 100
    for a, b in zip(prism.properties, jani.properties, strict=True):
        for key in ("min", "max", "uniform", "value"):
            x, y = getattr(a, key), getattr(b, key)
            assert (x is None) == (y is None), (a.name, key)
            if x is not None:
                assert x == pytest.approx(y, rel=1e-5, abs=1e-7), (a.name, key)


def test_the_diagram_has_a_cluster_per_agent_and_the_synchronisations() -> None:
    dot = source(load(_path("charging.afsm")).model)
    for agent in ("r1", "r2", "station"):
        assert f"subgraph cluster_{agent}" in dot
    assert "r1_m1 -> station_m0" in dot and "label=Grant1" in dot
    assert "style=dashed" in dot


def test_the_language_server_analyses_a_composed_mission() -> None:
    with open(_path("charging.afsm"), encoding="utf-8") as f:
        text = f.read()
    fast = analyse_fast(text, "charging.afsm")
    assert fast.model is not None and not fast.diagnostics
    assert not [d for d in analyse_full(text, "charging.afsm") if d.is_error]
    assert fast.module is not None
    idx = build(fast.module, text)
    assert ("action", "Grant1") in idx.defs and ("value", "freed") in idx.defs


@pytest.mark.storm
def test_a_sweep_runs_over_a_composed_mission() -> None:
    pytest.importorskip("stormpy")
    sweep = load_mission(_path("charging.afsm")).with_consts(ORDERS=2).sweep(
        "T_LIMIT", [6, 10], properties=["shift"])
    df = sweep.to_pandas()
    assert len(df) == 2 and (df["states"] > 0).all()


@pytest.mark.storm
def test_simulation_of_a_timed_mission_holds_the_exact_value() -> None:
    pytest.importorskip("stormpy")
    exact = run(_path("charging.afsm"), consts=SMALL["charging.afsm"], properties=["shift"])
    value = exact.properties[0].uniform
    assert value is not None
    mission = load_mission(_path("charging.afsm")).with_consts(**SMALL["charging.afsm"])
    est = mission.simulate(4000, seed=1)["shift"]
    assert est.low <= value <= est.high

