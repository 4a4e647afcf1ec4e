"""The exact reductions on composed missions, tested as for one machine
(tests/unit/lower/test_reduce.py): reduced and unreduced give equal values on every
property, on the PRISM and the JANI route, and the reduced model has no more states
(fewer where a reduction applies)."""

from __future__ import annotations

import os
from pathlib import Path

import pytest

from afsmc.backends.prism import emit
from afsmc.compiler import load
from afsmc.lower.compose import Network
from afsmc.lower.lowering import Lowered, lower
from afsmc.lower.reduce import Reductions, reduce
from afsmc.lower.reduce_compose import _live, _mission_reads
from afsmc.model import ir
from tests.conftest import ROOT

EXAMPLES = os.path.join(ROOT, "examples")
SMALL = {"two_uav": {"OBJECTS": "1", "T_LIMIT": "25"},
         "charging": {"ORDERS": "2", "T_LIMIT": "10"}}
CASES = [("charging", "compose timed ties order;"),
         ("two_uav", "compose timed ties order;"),
         ("two_uav", "compose interleaving;"),
         ("charging", "compose timed ties nondet;")]
OPTIONS = [Reductions(dead_reset=True, reorder=False, saturate=False),
           Reductions(dead_reset=False, reorder=True, saturate=False),
           Reductions(dead_reset=False, reorder=False, saturate=True),
           Reductions()]


def _model(name: str, compose: str) -> ir.Model:
    path = os.path.join(EXAMPLES, f"{name}.afsm")
    with open(path, encoding="utf-8") as f:
        text = f.read()
    assert "compose timed ties order;" in text
    text = text.replace("compose timed ties order;", compose)
    return load(path, SMALL[name], text=text).model


def _storm(low: Lowered, tmp: Path, name: str) -> tuple[tuple[int, int], dict[str, float],
                                                         dict[str, float]]:
    """(states, transitions) and the values by property on the PRISM and JANI routes;
    both routes build the same model."""
    from tests.storm_util import storm_prism
    from tests.unit.backends.test_jani import storm_jani, value

    pm, pvalues = storm_prism(low, tmp, name)
    (tmp / name).mkdir(exist_ok=True)
    jm, jprops = storm_jani(low, tmp / name)
    assert (jm.nr_states, jm.nr_transitions) == (pm.nr_states, pm.nr_transitions)  # type: ignore[attr-defined]
    jvalues = {p.get_name(): value(jm, p) for p in jprops}  # type: ignore[attr-defined]
    return (pm.nr_states, pm.nr_transitions), pvalues, jvalues


@pytest.mark.storm
@pytest.mark.slow
@pytest.mark.parametrize(("name", "compose"), CASES)
def test_reductions_are_exact_on_both_routes(name: str, compose: str, tmp_path: Path) -> None:
    pytest.importorskip("stormpy")
    base = lower(_model(name, compose))
    (states, _), plain, plain_jani = _storm(base, tmp_path, "plain")
    assert plain and plain.keys() == plain_jani.keys()
    for opt in OPTIONS:
        low = reduce(base, opt)
        (reduced, _), values, jani_values = _storm(low, tmp_path, "reduced")
        assert reduced <= states, (name, opt)
        for got in (values, jani_values):
            assert got.keys() == plain.keys()
            for prop, exact in plain.items():
                assert got[prop] == pytest.approx(exact, rel=1e-9, abs=1e-9), (name, opt, prop)
        if opt.dead_reset:
            assert reduced < 0.6 * states, (name, opt)  # agents' dead variables merge
        if not opt.dead_reset and not opt.saturate:
            assert reduced == states  # reordering keeps the state space


@pytest.mark.storm
def test_the_reduced_two_uav_mission_is_smaller_and_equal(tmp_path: Path) -> None:
    pytest.importorskip("stormpy")
    base = lower(_model("two_uav", "compose interleaving;"))
    (plain, _), values, _ = _storm(base, tmp_path, "plain")
    (reduced, _), reduced_values, jani_values = _storm(reduce(base), tmp_path, "reduced")
    assert reduced < plain / 4
    for prop, exact in values.items():
        assert reduced_values[prop] == pytest.approx(exact, rel=1e-9, abs=1e-9), prop
        assert jani_values[prop] == pytest.approx(exact, rel=1e-9, abs=1e-9), prop


def test_a_clock_compared_with_another_agents_is_not_saturated() -> None:
    """Timed: each clock is compared with the others' (who moves first), so no clock is a
    counter read only against constants. Interleaving: the clocks are only compared with
    T_LIMIT, and saturate there."""
    timed = reduce(lower(_model("two_uav", "compose timed ties order;")))
    assert not any(r.startswith("saturated") for r in timed.reductions)
    loose = reduce(lower(_model("two_uav", "compose interleaving;")))
    assert "saturated uav1_t at 25, uav2_t at 25" in loose.reductions
    t = next(v for v in loose.model.variables if v.name == "uav1_t")
    assert t.hi == 25


def test_live_variables_per_agent() -> None:
    """A robot's battery is dead while it waits for the charger (the grant sets it);
    a clock is dead in a final mode (nobody compares with the clock of an agent that
    cannot move); what a label reads stays live there."""
    model = _model("charging", "compose timed ties order;")
    low = lower(model)
    net = low.network
    assert isinstance(net, Network)
    reads = _mission_reads(low)
    r1 = net.parts[0]
    live = _live(reads, r1)
    modes = {m.name: m.number for m in r1.agent.model.modes}
    assert "r1_b" not in live[modes["Wait"]] and "r1_b" in live[modes["Work"]]
    assert "r1_t" not in live[modes["Finished"]] and "r1_t" in live[modes["Wait"]]
    assert "r1_done" in live[modes["Finished"]]  # the label all_done reads it


def test_shared_and_mode_variables_are_never_reset() -> None:
    low = reduce(lower(_model("charging", "compose timed ties order;")),
                 Reductions(dead_reset=True, reorder=False, saturate=False))
    net = low.network
    assert isinstance(net, Network)
    resets = {var for part in net.parts for c in part.local for b in c.branches
              for var, _ in b.updates}
    assert "r1_b" in resets  # a robot that asks for the charger forgets its battery
    base = lower(low.model)
    for part, before in zip(net.parts, base.network.parts, strict=True):
        for new, old in zip(part.local, before.local, strict=True):
            for nb, ob in zip(new.branches, old.branches, strict=True):
                added = dict(nb.updates).keys() - dict(ob.updates).keys()
                assert all(v.startswith(part.agent.prefix) and v != part.agent.mode_var
                           for v in added)


def test_the_header_names_the_reductions_and_no_reduce_is_the_plain_model() -> None:
    model = _model("two_uav", "compose interleaving;")
    reduced = emit(reduce(lower(model))).model
    assert ("// Exact reductions: saturated uav1_t at 25, uav2_t at 25, dead-variable reset, "
            "variable order (afsmc compile --no-reduce: none).") in reduced
    plain = emit(reduce(lower(model), Reductions.none())).model
    assert plain == emit(lower(model)).model and "Exact reductions" not in plain
