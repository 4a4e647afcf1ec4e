"""The exact reductions: reduced and unreduced models give equal values for every
property (to 1e-9) and the reduced model has no more states."""

from __future__ import annotations

from pathlib import Path

import pytest

from afsmc.compiler import load
from afsmc.lower.lowering import lower
from afsmc.lower.reduce import Reductions, live_variables, observable, reduce
from tests.conftest import EXAMPLES
from tests.storm_util import storm_prism
from tests.unit.backends.test_prism import CLIMB, GEOMETRIC, SMALL

EXAMPLE_FILES = sorted(EXAMPLES.glob("*.afsm"))
# the composed examples at the sizes tests/unit/compose takes (their defaults are large)
SIZES = SMALL | {"two_uav": {"OBJECTS": "1", "T_LIMIT": "25"},
                 "charging": {"ORDERS": "2", "T_LIMIT": "10"}}
OPTIONS = [Reductions(dead_reset=True, reorder=False, saturate=False),
           Reductions(dead_reset=False, reorder=True, saturate=False),
           Reductions(dead_reset=False, reorder=False, saturate=True),
           Reductions()]


def _cases(tmp: Path) -> list[tuple[str, object]]:
    out = []
    for path in EXAMPLE_FILES:
        out.append((path.stem, load(str(path), SIZES.get(path.stem, {})).model))
    for name, text in (("geometric", GEOMETRIC), ("climb", CLIMB)):
        p = tmp / f"{name}.afsm"
        p.write_text(text)
        out.append((name, load(str(p)).model))
    return out


@pytest.mark.slow
@pytest.mark.storm
@pytest.mark.parametrize("resolution", ["nondet", "uniform"])
def test_reductions_are_exact_and_never_grow_the_state_space(resolution: str, tmp_path: Path) -> None:
    for name, model in _cases(tmp_path):
        base = lower(model, resolution)  # type: ignore[arg-type]
        plain, plain_values = storm_prism(base, tmp_path, f"{name}_plain")
        for opt in OPTIONS:
            reduced, values = storm_prism(reduce(base, opt), tmp_path, f"{name}_red")
            assert reduced.nr_states <= plain.nr_states, (name, opt)
            assert values.keys() == plain_values.keys()
            for prop, value in plain_values.items():
                assert values[prop] == pytest.approx(value, abs=1e-9), (name, opt, prop)
            if not opt.dead_reset and not opt.saturate:  # reordering keeps the state space
                assert reduced.nr_states == plain.nr_states


@pytest.mark.storm
def test_dead_reset_shrinks_the_uav_state_space(tmp_path: Path) -> None:
    model = load(str(EXAMPLES / "uav.afsm"), SMALL["uav"]).model
    plain, _ = storm_prism(lower(model, "lo"), tmp_path, "p")
    reduced, _ = storm_prism(reduce(lower(model, "lo")), tmp_path, "r")
    assert reduced.nr_states < 0.9 * plain.nr_states


def test_live_variables_of_the_uav() -> None:
    """ret is dead while searching (it is always rewritten before it is read); what the
    labels read is live wherever it may still be read, and nowhere else: the labels about
    the mission's outcome hold only in Done, so EmergencyLand keeps no variable."""
    model = load(str(EXAMPLES / "uav.afsm"), SMALL["uav"]).model
    live = live_variables(lower(model))
    search = model.mode("Search").number
    assert "ret_x" not in live[search] and "ret_y" not in live[search]
    assert "ret_x" in live[model.mode("GoToSearch").number]
    assert {"obj", "t", "exhausted", "aborted"} <= observable(model)
    for var in observable(model):
        assert all(var in live[m.number] for m in model.modes if not m.final)
    done, emergency = model.mode("Done").number, model.mode("EmergencyLand").number
    assert {"obj", "t", "exhausted", "aborted"} <= observable(model, done) <= live[done]
    assert observable(model, emergency) == set() == live[emergency]


@pytest.mark.storm
def test_a_final_mode_no_label_looks_into_is_one_state(tmp_path: Path) -> None:
    """Every emergency landing of the reduced UAV is the same state; unreduced, there is
    one per (objects left, time, ...) it happened at. The probabilities are equal (the
    exactness test above)."""
    model = load(str(EXAMPLES / "uav.afsm"), SMALL["uav"]).model
    plain, _ = storm_prism(lower(model, "lo"), tmp_path, "p")
    reduced, _ = storm_prism(reduce(lower(model, "lo")), tmp_path, "r")

    def landings(m: object) -> int:
        return int(m.labeling.get_states("emergency").get_number_of_set_bits())  # type: ignore[attr-defined]

    assert landings(plain) > 100 and landings(reduced) == 1


def test_reorder_puts_wide_counters_last_and_interleaves_tuples() -> None:
    model = load(str(EXAMPLES / "uav.afsm"), SMALL["uav"]).model
    names = [v.name for v in reduce(lower(model), Reductions(False, True, False)).model.variables]
    assert names.index("pos_x") < names.index("ret_x") < names.index("pos_y") < names.index("ret_y")
    assert names[-2:] == ["b", "t"]
    assert names.index("obj") < names.index("pos_x")


def test_counters_saturate_beyond_the_constants_they_are_compared_with() -> None:
    """t is only compared with T_LIMIT and DEADLINE and only grows: it saturates at
    max(T_LIMIT, DEADLINE + 1), and the PRISM output says so."""
    model = load(str(EXAMPLES / "uav.afsm"), {"T_LIMIT": "100", "DEADLINE": "120"}).model
    low = reduce(lower(model), Reductions(dead_reset=False, reorder=False, saturate=True))
    t = next(v for v in low.model.variables if v.name == "t")
    assert t.hi == 121
    assert any("saturated t at 121" in r for r in low.reductions)
    # b only decreases and is compared with B_LOW, B_FULL: every level up to B_LOW (25)
    # behaves alike, so it saturates from below
    b = next(v for v in low.model.variables if v.name == "b")
    assert (b.lo, b.hi) == (25, 100)
    assert any("b from 25" in r for r in low.reductions)


@pytest.mark.slow
@pytest.mark.storm
def test_saturation_shrinks_the_uav_scenario_and_keeps_its_values(tmp_path: Path) -> None:
    """On an instance where the battery runs low, downward saturation merges states and
    every property keeps its value."""
    model = load(str(EXAMPLES / "uav.afsm"), {"WIDTH": "3", "HEIGHT": "2", "T_LIMIT": "400",
                                               "B_LOW": "85"}).model
    base = lower(model, "nondet")
    plain, plain_values = storm_prism(reduce(base, Reductions(True, True, False)), tmp_path, "a")
    sat, sat_values = storm_prism(reduce(base, Reductions(True, True, True)), tmp_path, "b")
    assert sat.nr_states < plain.nr_states
    for name, value in plain_values.items():
        assert sat_values[name] == pytest.approx(value, abs=1e-9), name


def _model(tmp: Path, text: str) -> object:
    path = tmp / "spec.afsm"
    path.write_text(text)
    return load(str(path)).model


@pytest.mark.storm
def test_saturation_keeps_an_authors_own_cap(tmp_path: Path) -> None:
    """`t := min(t + 1, 3)` is not a plain counter: t never passes 3."""
    model = _model(tmp_path, """
machine sat1;
var t : [0..10] init 0;
mode A = 0 initial;
mode B = 1 final;
action Tick in A when t < 8 { t := min(t + 1, 3); }
action Stop in A when t >= 8 { goto B; }
label late = t >= 5;
property p = P=? [ F<=20 "late" ];
""")
    _, plain = storm_prism(lower(model), tmp_path, "plain")  # type: ignore[arg-type]
    _, reduced = storm_prism(reduce(lower(model), Reductions()), tmp_path, "red")  # type: ignore[arg-type]
    assert plain["p"] == 0.0 and reduced["p"] == 0.0
