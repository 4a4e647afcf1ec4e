"""Streaming by default above a size (issue 48): without --scratch, afsmc's exploration
goes through the system temp directory once the in-memory route would not fit
comfortably; `--scratch DIR` forces DIR, `--no-scratch` forbids it. The decision
(afsmc.verify.stream.route.where, surely_fits, too_big) at its edges, and the route taken
end to end: the values equal the in-memory route's (the oracle) to 1e-12, the engine's
reason and the progress lines say which route and why, and the temp directory is left as
it was."""

from __future__ import annotations

import math
import tempfile
from pathlib import Path
from typing import Any

import pytest

from afsmc.backends.prism import property_variants
from afsmc.compiler import load, lowered
from afsmc.diagnostics import CompileError
from afsmc.verify import run
from afsmc.verify.engines import explicit
from afsmc.verify.explorer import explore_graph
from afsmc.verify.stream import layers, route
from tests.conftest import EXAMPLES, run_cli
from tests.unit.backends.test_prism import SMALL
from tests.unit.verify.test_streaming import CASES

UAV = str(EXAMPLES / "uav.afsm")
GB = 10**9


def _room(bound: int) -> int:
    """The memory in which `bound` states just fit comfortably."""
    return math.ceil(bound * route.BLOCK_BYTES_PER_STATE * explore_graph.PEAK_FACTOR
                     / route.COMFORT)


def test_a_bound_that_surely_fits_stays_in_memory_and_one_byte_less_room_does_not() -> None:
    room = _room(1_000_000)
    assert route.surely_fits(1_000_000, room)
    assert not route.surely_fits(1_000_000, room - 1)
    assert route.surely_fits(10**12, None)  # memory unknown: in memory, as before


def test_the_exploration_is_too_big_past_its_share_of_the_memory() -> None:
    available = 10 * GB
    edge = int(route.COMFORT * available / explore_graph.PEAK_FACTOR)
    assert not route.too_big(edge, available)
    assert route.too_big(edge + 1, available)
    assert not route.too_big(10**15, None)


def test_where_the_scratch_goes(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(tempfile, "tempdir", str(tmp_path))
    big, room = 10**9, 20 * GB  # a bound far past what fits
    # --scratch DIR: DIR, at once, whatever the size
    assert route.where("/data", False, 10, room) == route.Scratching("/data")
    # --no-scratch: in memory, whatever the size
    assert route.where(None, True, big, room) == route.Scratching(None)
    # default: the temp directory, once the exploration says so; not for a small bound
    assert route.where(None, False, big, room) == route.Scratching(str(tmp_path), auto=True)
    assert route.where(None, False, 1000, _room(1000)) == route.Scratching(None)
    assert route.where(None, False, 1001, _room(1000)).auto
    # a temp directory that cannot be written: in memory, as before
    monkeypatch.setattr(tempfile, "tempdir", str(tmp_path / "missing"))
    assert route.where(None, False, big, room) == route.Scratching(None)


def _tight(monkeypatch: pytest.MonkeyPatch, tmp: Path) -> None:
    """A machine whose memory the SMALL UAV's exploration outgrows: the comfortable share
    a few bytes, the memory growing by 1 MB at each look (the watch looks after every
    bucket), the temp directory `tmp`."""
    grown = iter(range(0, 10**12, 1 << 20))
    monkeypatch.setattr(route, "COMFORT", 1e-9)
    monkeypatch.setattr(route, "resident", lambda: next(grown))
    monkeypatch.setattr(explore_graph, "PROGRESS_EVERY", 0.0)
    monkeypatch.setattr(tempfile, "tempdir", str(tmp))


@pytest.mark.storm
def test_a_model_that_would_not_fit_in_memory_is_streamed_by_default(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    plain = run(UAV, consts=SMALL["uav"], isolate=False)
    assert "scratch" not in str(plain.model.engine_reason)
    _tight(monkeypatch, tmp_path)
    streamed = run(UAV, consts=SMALL["uav"], isolate=False)
    reason = str(streamed.model.engine_reason)
    assert "MB of scratch disk (by default: in memory it would peak at about" in reason, reason
    for a, b in zip(plain.properties, streamed.properties, strict=True):
        for x, y in ((a.min, b.min), (a.max, b.max), (a.uniform, b.uniform)):
            assert x is not None and y == pytest.approx(x, rel=1e-12, abs=1e-12), a.name
    assert streamed.model.states == plain.model.states
    assert list(tmp_path.iterdir()) == []
    # --no-scratch on the same tight machine: in memory, the same values
    kept = run(UAV, consts=SMALL["uav"], isolate=False, no_scratch=True)
    assert "scratch" not in str(kept.model.engine_reason)
    assert [p.max for p in kept.properties] == [p.max for p in plain.properties]
    # --scratch DIR: through DIR at once, and the reason says so
    forced = run(UAV, consts=SMALL["uav"], isolate=False, scratch=str(tmp_path),
                 properties=["success"])
    assert "MB of scratch disk (--scratch)" in str(forced.model.engine_reason)
    assert list(tmp_path.iterdir()) == []


@pytest.mark.storm
def test_the_progress_lines_say_why_the_model_is_streamed(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    # (the lines a watched child sends; in this process, as explicit.answer notifies them)
    _tight(monkeypatch, tmp_path)
    low = lowered(load(UAV, SMALL["uav"]).model, "nondet")
    names = tuple(n for q in low.model.properties for n, _ in property_variants(low, q))
    said: list[str] = []
    work = tmp_path / "afsmc-scratch-job"
    work.mkdir()
    ans = explicit.answer(low, names, "MDP", lambda e, d: said.append(str(d)),
                          scratch=str(work), scratch_auto=True)
    assert ans is not None and ans.scratch and ans.scratch_why.startswith("by default")
    assert any("states explored in memory are written to the scratch directory in "
               f"{tmp_path} and the exploration goes on layer by layer (--no-scratch keeps "
               "it in memory" in s for s in said), said
    assert any("into the scratch directory" in s for s in said), said
    assert list(work.iterdir()) == []


@pytest.mark.storm
def test_a_strategy_is_streamed_by_default_too(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    plain = run(UAV, consts=SMALL["uav"], isolate=False, properties=["success"],
                strategy=True, witness=("success", 3))
    _tight(monkeypatch, tmp_path)
    res = run(UAV, consts=SMALL["uav"], isolate=False, properties=["success"],
              strategy=True, witness=("success", 3))
    # streamed, the strategy and the paths with it (no second exploration in memory)
    assert "MB of scratch disk (by default" in str(res.model.engine_reason)
    a, b = plain.properties[0], res.properties[0]
    assert a.strategy is not None and b.strategy == a.strategy
    assert a.witnesses and b.witnesses == a.witnesses
    assert list(tmp_path.iterdir()) == []


def _count_buckets(monkeypatch: pytest.MonkeyPatch) -> list[int]:
    """Count every bucket's exploration, in memory or through the disk."""
    calls: list[int] = []
    search = explore_graph.search_bucket

    def counted(*args: Any, **kwargs: Any) -> Any:
        calls.append(1)
        return search(*args, **kwargs)

    monkeypatch.setattr(explore_graph, "search_bucket", counted)
    monkeypatch.setattr(layers.explore_graph, "search_bucket", counted)
    return calls


@pytest.mark.storm
@pytest.mark.parametrize("case", ["uav", "rover"])
@pytest.mark.parametrize("edge", ["first", "middle", "last"])
def test_past_stream_from_the_exploration_goes_on_through_the_disk_without_a_restart(
        case: str, edge: str, tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    # the buckets explored in memory are written out and the rest explored on the disk:
    # every bucket explored once (a restart would explore the first ones twice), after
    # the first bucket, in the middle and after the last one; the values equal the
    # in-memory route's to 1e-12
    path, consts = CASES[case]
    low = lowered(load(path, consts).model, "nondet")
    names = tuple(n for q in low.model.properties for n, _ in property_variants(low, q))
    calls = _count_buckets(monkeypatch)
    monkeypatch.setattr(tempfile, "tempdir", str(tmp_path))
    work = tmp_path / "afsmc-scratch-job"
    work.mkdir()
    # in memory first (never past STREAM_FROM): the states explored after each bucket
    seen: list[int] = []
    asked = route.Watch.handover
    monkeypatch.setattr(route, "STREAM_FROM", 10**12)
    monkeypatch.setattr(route.Watch, "handover",
                        lambda self, states: seen.append(states) or asked(self, states))
    plain = explicit.answer(low, names, "MDP", lambda *_: None, scratch=str(work),
                            scratch_auto=True)
    assert plain is not None and not plain.scratch and len(seen) > 2
    once = len(calls)
    monkeypatch.setattr(route, "STREAM_FROM", {"first": seen[0], "middle": seen[len(seen) // 2],
                                               "last": seen[-1]}[edge])
    calls.clear()
    said: list[str] = []
    got = explicit.answer(low, names, "MDP", lambda e, d: said.append(str(d)),
                          scratch=str(work), scratch_auto=True)
    assert got is not None and got.scratch and got.scratch_why.startswith("by default: passed")
    assert len(calls) == once, (len(calls), once)
    assert any("states explored in memory are written to the scratch directory" in s
               for s in said), said
    assert got.states == plain.states and got.transitions == plain.transitions
    for q, v in plain.values.items():
        assert got.values[q] == pytest.approx(v, rel=1e-12, abs=1e-12), q
    assert list(work.iterdir()) == []


def test_scratch_and_no_scratch_together_are_refused(tmp_path: Path) -> None:
    with pytest.raises(CompileError) as exc:
        run(UAV, consts=SMALL["uav"], scratch=str(tmp_path), no_scratch=True)
    d = exc.value.diagnostics[0]
    assert d.code == "E419" and "--no-scratch" in d.message and d.hint
    r = run_cli("verify", UAV, "--scratch", str(tmp_path), "--no-scratch")
    assert r.code == 1 and "E419" in r.err and "Traceback" not in r.err, r.err
    r = run_cli("sweep", UAV, "--const", "WIDTH=2,3", "--const", "HEIGHT=2", "--scratch",
                str(tmp_path), "--no-scratch")
    assert r.code == 1 and "E419" in r.err and "Traceback" not in r.err, r.err
    assert list(tmp_path.iterdir()) == []
