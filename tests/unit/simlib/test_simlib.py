"""Tests of the built-in small-scale simulation library (afsmc.simlib)."""

from __future__ import annotations

import builtins
import math
import re
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from afsmc import simlib
from afsmc.simlib import quadrotor, registry, uav
from afsmc.simlib.registry import Simulator, UnknownSimulator

DOCS = Path(__file__).resolve().parents[3] / "docs" / "simulation.md"
FLIGHTS = [s.name for s in uav.SIMULATORS if "battery" in s.outputs]


@pytest.fixture(scope="module")
def summary() -> dict[str, tuple[str, str, str, str]]:
    """The docs table, recomputed: 100,000 runs, seed 0."""
    return {r: (k, m, s, h) for r, k, m, s, h in registry.summary_rows(100_000, 0)}


@pytest.fixture
def fresh_registry() -> Iterator[None]:
    registry.reload()
    yield
    registry.reload()


# --- registry -------------------------------------------------------------


def test_available_is_sorted_and_complete() -> None:
    refs = simlib.available()
    assert refs == sorted(refs)
    assert len(refs) == len(set(refs))
    expected = {f"{s.name}.{o}" for s in uav.SIMULATORS for o in s.outputs}
    assert expected <= set(refs)
    for name in [
        "uav.takeoff",
        "uav.initialise",
        "uav.search",
        "uav.approach",
        "uav.descend_grab",
        "uav.grab",
        "uav.ascend",
        "uav.transport",
        "uav.descend_deposit",
        "uav.deposit",
        "uav.return",
        "uav.land",
    ]:
        assert f"{name}.duration" in refs and f"{name}.battery" in refs
    assert "uav.recharge.duration" in refs
    for ref in ["uav.initialise.fail", "uav.grab.fail", "uav.transport.drop"]:
        assert simlib.kind(ref) == "probability"


def test_lookup_and_kind() -> None:
    sim, out = simlib.lookup("uav.approach.duration")
    assert sim.name == "uav.approach" and out == "duration"
    assert simlib.kind("uav.approach.duration") == "duration"
    assert simlib.kind("uav.approach.battery") == "battery"
    assert simlib.kind("uav.grab.fail") == "probability"
    for ref in simlib.available():
        assert simlib.kind(ref) in simlib.KINDS


@pytest.mark.parametrize(
    "ref",
    [
        "os.system",
        "__import__('os').system",
        "__import__('os')",
        "uav.approach.__class__",
        "uav.approach.run",
        "uav.approach",
        "uav",
        "afsmc.simlib.uav.SIMULATORS",
        "uav.approach.duration ",
        "",
        "uav.approach.duration\x00",
    ],
)
def test_hostile_or_unknown_references_raise(ref: str, monkeypatch: pytest.MonkeyPatch) -> None:
    simlib.available()  # load the registry before imports are forbidden

    def no_import(*args: Any, **kwargs: Any) -> Any:
        raise AssertionError(f"import attempted while resolving {ref!r}: {args[0]!r}")

    monkeypatch.setattr(builtins, "__import__", no_import)
    with pytest.raises(UnknownSimulator):
        simlib.lookup(ref)
    with pytest.raises(UnknownSimulator):
        simlib.kind(ref)
    monkeypatch.undo()
    with pytest.raises(UnknownSimulator):
        simlib.sample(ref, 10, 0)


def test_unknown_reference_suggests_close_matches() -> None:
    with pytest.raises(UnknownSimulator, match=r"uav\.approach\.duration"):
        simlib.lookup("uav.aproach.duration")
    assert issubclass(UnknownSimulator, LookupError)


def test_simulator_validation() -> None:
    def run(runs: int, rng: np.random.Generator) -> dict[str, np.ndarray[Any, Any]]:
        return {"duration": np.ones(runs)}

    with pytest.raises(ValueError, match="kind"):
        Simulator("x.y", "", {"duration": "seconds"}, run)
    with pytest.raises(ValueError, match="name"):
        Simulator("X Y", "", {"duration": "duration"}, run)
    with pytest.raises(ValueError, match="no outputs"):
        Simulator("x.y", "", {}, run)


class _FakeEntryPoint:
    def __init__(self, name: str, value: str, obj: object) -> None:
        self.name, self.value, self._obj = name, value, obj

    def load(self) -> object:
        if isinstance(self._obj, Exception):
            raise self._obj
        return self._obj


def _plugin(name: str, value: float) -> Simulator:
    def run(runs: int, rng: np.random.Generator) -> dict[str, np.ndarray[Any, Any]]:
        return {"duration": np.full(runs, value) + rng.random(runs)}

    return Simulator(name, "third-party test model", {"duration": "duration"}, run)


def test_third_party_entry_points(monkeypatch: pytest.MonkeyPatch, fresh_registry: None) -> None:
    before = simlib.sample("uav.search.duration", 500, 3)
    eps = [
        _FakeEntryPoint("uav", "afsmc.simlib.uav:SIMULATORS", uav.SIMULATORS),
        _FakeEntryPoint("rover", "rover_sims:SIMS", (_plugin("rover.drive", 4.0),)),
        _FakeEntryPoint("broken", "broken:SIMS", ImportError("no module named broken")),
        _FakeEntryPoint("clash", "clash:SIMS", (_plugin("uav.search", 1.0),)),
        _FakeEntryPoint("junk", "junk:SIMS", ("not a simulator",)),
    ]
    calls: list[str] = []

    def fake_entry_points(*, group: str) -> list[_FakeEntryPoint]:
        calls.append(group)
        return eps

    monkeypatch.setattr(registry, "entry_points", fake_entry_points)
    registry.reload()
    with pytest.warns(UserWarning) as record:
        refs = simlib.available()
    assert calls == ["afsmc.simulators"]
    messages = " ".join(str(w.message) for w in record)
    assert (
        "broken" in messages and "already registered" in messages and "not a Simulator" in messages
    )
    assert "rover.drive.duration" in refs
    x = simlib.sample("rover.drive.duration", 100, 0)
    assert x.shape == (100,) and np.all((x >= 4.0) & (x < 5.0))
    # A plugin neither shadows a built-in nor changes the built-ins' samples.
    assert simlib.lookup("uav.search.duration")[0] is next(
        s for s in uav.SIMULATORS if s.name == "uav.search"
    )
    np.testing.assert_array_equal(simlib.sample("uav.search.duration", 500, 3), before)


def test_builtin_fallback_without_metadata(
    monkeypatch: pytest.MonkeyPatch, fresh_registry: None
) -> None:
    monkeypatch.setattr(registry, "entry_points", lambda *, group: [])
    registry.reload()
    assert "uav.approach.duration" in simlib.available()


def test_registry_is_cached(monkeypatch: pytest.MonkeyPatch, fresh_registry: None) -> None:
    simlib.available()
    monkeypatch.setattr(registry, "entry_points", lambda *, group: pytest.fail("registry reloaded"))
    simlib.available()
    simlib.lookup("uav.land.duration")


def test_misbehaving_plugin_output_is_rejected(
    monkeypatch: pytest.MonkeyPatch, fresh_registry: None
) -> None:
    def run(runs: int, rng: np.random.Generator) -> dict[str, np.ndarray[Any, Any]]:
        return {"duration": np.ones(runs + 1)}

    bad = Simulator("bad.sim", "", {"duration": "duration"}, run)
    monkeypatch.setattr(
        registry, "entry_points", lambda *, group: [_FakeEntryPoint("bad", "bad:S", (bad,))]
    )
    registry.reload()
    with pytest.raises(ValueError, match="shape"):
        simlib.sample("bad.sim.duration", 10, 0)


# --- sampling -------------------------------------------------------------


def test_deterministic_for_a_seed() -> None:
    for ref in [
        "uav.approach.duration",
        "uav.grab.fail",
        "uav.transport.battery",
        "uav.recharge.duration",
    ]:
        a = simlib.sample(ref, 2000, 11)
        registry.reload()  # drop the sample cache: recomputed, not just remembered
        b = simlib.sample(ref, 2000, 11)
        np.testing.assert_array_equal(a, b)
        if simlib.kind(ref) != "probability":
            assert not np.array_equal(a, simlib.sample(ref, 2000, 12))


def test_samples_are_copies() -> None:
    a = simlib.sample("uav.search.duration", 100, 0)
    a[:] = -1.0
    assert np.all(simlib.sample("uav.search.duration", 100, 0) > 0)


@pytest.mark.parametrize("ref", simlib.available())
def test_shapes_and_dtypes(ref: str) -> None:
    x = simlib.sample(ref, 257, 5)
    assert x.shape == (257,)
    if simlib.kind(ref) == "probability":
        assert x.dtype == np.bool_
    else:
        assert x.dtype == np.float64
        assert np.all(np.isfinite(x))


def test_outputs_of_a_simulator_are_paired() -> None:
    out = simlib.simulate("uav.approach", 5000, 0)
    assert set(out) == {"duration", "battery"}
    np.testing.assert_array_equal(out["duration"], simlib.sample("uav.approach.duration", 5000, 0))
    # Longer approaches (objects further from the centre) drain more battery.
    assert np.corrcoef(out["duration"], out["battery"])[0, 1] > 0.8


@pytest.mark.slow
@pytest.mark.parametrize("sim", uav.SIMULATORS, ids=lambda s: s.name)
def test_100k_runs_in_one_call(sim: Simulator) -> None:
    # How fast is measured in benchmarks/simlib_speed.py, not here: a timed assertion
    # fails on a slow machine for no fault of the code.
    out = sim.run(100_000, np.random.default_rng(1))
    assert out and all(np.shape(v) == (100_000,) for v in out.values())


# --- physics --------------------------------------------------------------


def test_vehicle_endurance_and_units() -> None:
    v = quadrotor.Vehicle()
    assert 480.0 <= v.hover_endurance_s <= 600.0  # 8-10 min at hover
    assert math.isclose(100 * v.joules_per_unit, v.usable_energy_j)


@pytest.mark.parametrize("name", FLIGHTS)
def test_flights_take_time_and_battery(name: str) -> None:
    out = simlib.simulate(name, 4000, 0)
    d, b = out["duration"], out["battery"]
    assert np.all(d > 0) and np.all(d < 100)
    assert np.all(b > 0)
    # Average drain between idle avionics and full thrust, around hover (0.185 units/s).
    rate = b.sum() / d.sum()
    assert 0.12 < rate < 0.35, rate


def test_all_flights_complete() -> None:
    res = quadrotor.fly(
        5000, np.random.default_rng(0), np.zeros(3), np.array([6.0, 0.0, 10.0]), v_max=3, a_max=1.5
    )
    assert res.completed.all()
    assert np.all(np.abs(res.final_error) < 0.5)


def test_more_squares_cost_more() -> None:
    rng = np.random.default_rng(0)
    start = np.array([0.0, 0.0, uav.SEARCH_HEIGHT])
    means = []
    for squares in (1, 2, 3):
        goal = np.array([squares * uav.CELL, 0.0, uav.SEARCH_HEIGHT])
        res = quadrotor.fly(4000, rng, start, goal, v_max=3.0, a_max=1.5)
        means.append((res.duration.mean(), res.battery.mean()))
    assert means[0][0] < means[1][0] < means[2][0]
    assert means[0][1] < means[1][1] < means[2][1]
    # n single-square search moves cost more than one n-square flight (stops, camera dwell).
    search = simlib.simulate("uav.search", 4000, 0)
    assert 3 * search["duration"].mean() > means[2][0]
    assert 3 * search["battery"].mean() > means[2][1]


def test_payload_and_distance_cost_more() -> None:
    runs, seed = 20_000, 0
    loaded = simlib.simulate("uav.ascend", runs, seed)  # 9.4 m with the object
    empty = simlib.simulate("uav.ascend_empty", runs, seed)  # 8.5 m without
    assert loaded["duration"].mean() > empty["duration"].mean()
    assert loaded["battery"].mean() > empty["battery"].mean()
    # Per second, carrying the object drains more than searching without it.
    t = simlib.simulate("uav.transport", runs, seed)
    s = simlib.simulate("uav.search", runs, seed)
    assert t["battery"].sum() / t["duration"].sum() > s["battery"].sum() / s["duration"].sum()


def test_recharge_depends_on_level() -> None:
    rng = np.random.default_rng(0)
    levels = [0.0, uav.LOW_BATTERY, 60.0, 90.0, 100.0]
    times = [uav.recharge_time(b, 4000, rng).mean() for b in levels]
    assert times == sorted(times, reverse=True)
    assert times[-1] == pytest.approx(uav.DOCK_TIME, abs=0.05)
    # Low threshold to full takes minutes, not hours: a recharge fits a 900 s mission.
    assert 60.0 < simlib.sample("uav.recharge.duration", 4000, 0).mean() < 400.0


@pytest.mark.slow
def test_failure_probabilities_are_small_but_present(
    summary: dict[str, tuple[str, str, str, str]],
) -> None:
    for ref in ["uav.initialise.fail", "uav.grab.fail", "uav.transport.drop"]:
        p = float(summary[ref][1])
        assert 0.001 < p < 0.15, (ref, p)


def test_grab_failure_depends_on_position_error(monkeypatch: pytest.MonkeyPatch) -> None:
    base = uav.grab(20_000, np.random.default_rng(0))["fail"].mean()
    monkeypatch.setattr(uav, "CAPTURE_RADIUS", 0.10)
    tight = uav.grab(20_000, np.random.default_rng(0))["fail"].mean()
    monkeypatch.setattr(uav, "OBJECT_ESTIMATE_SD", 0.10)
    worse = uav.grab(20_000, np.random.default_rng(0))["fail"].mean()
    assert base < tight < worse


def test_drop_hazard_grows_with_gusts() -> None:
    start = np.array([0.0, 0.0, 10.0])
    goal = np.array([6.0, 0.0, 10.0])
    hazard = []
    for gust in (0.2, 0.6, 1.5):
        env = quadrotor.Environment(gust_sd=(gust, gust, gust / 2))
        res = quadrotor.fly(
            4000, np.random.default_rng(0), start, goal, v_max=2.5, a_max=1.2,
            payload_mass=uav.PAYLOAD, grip=uav.GRIP, env=env,
        )  # fmt: skip
        hazard.append(res.hazard.mean())
    assert hazard[0] < hazard[1] < hazard[2]


# --- the timing intervals used by the abstract model ----------------------


def _hull(h: str) -> tuple[int, int]:
    lo, hi = re.fullmatch(r"\[(-?\d+), (-?\d+)\]", h).groups()  # type: ignore[union-attr]
    return int(lo), int(hi)


@pytest.mark.slow
def test_duration_hulls_are_narrow(summary: dict[str, tuple[str, str, str, str]]) -> None:
    durations = [r for r in summary if summary[r][0] == "duration"]
    assert len(durations) == len(uav.SIMULATORS)
    for ref in durations:
        lo, hi = _hull(summary[ref][3])
        assert 0 <= lo < hi, ref
        assert hi - lo <= 3, (ref, lo, hi)
        assert lo <= float(summary[ref][1]) <= hi


@pytest.mark.slow
def test_docs_table_matches_the_library(summary: dict[str, tuple[str, str, str, str]]) -> None:
    text = DOCS.read_text(encoding="utf-8")
    rows = re.findall(r"^\| `([a-z_.]+)` \| (\w+) \| ([^|]+) \| ([^|]+) \| ([^|]+) \|$", text, re.M)
    documented = {r: (k, m.strip(), s.strip(), h.strip()) for r, k, m, s, h in rows}
    assert documented == summary
