"""`verify --scratch DIR`: afsmc's own exploration written layer by layer to a scratch
directory and read back by one backward pass (afsmc.verify.stream). Oracle: the in-memory
exploration and pass (afsmc.verify.explorer.explore_graph, acyclic), the reference route,
equal to 1e-12 on every query, the uniform DTMC's means included; and the scratch
directory left empty after a success, an error, a full disk and an interrupt."""

from __future__ import annotations

import errno
import json
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from afsmc.backends.prism import property_variants
from afsmc.compiler import load, lowered
from afsmc.diagnostics import CompileError
from afsmc.verify import run
from afsmc.verify import sweep as sweep_points
from afsmc.verify.arrays import acyclic
from afsmc.verify.engines import explicit
from afsmc.verify.explorer import explore, explore_graph
from afsmc.verify.stream import layers, scratch, sweep
from tests.conftest import EXAMPLES, run_cli
from tests.unit.backends.test_prism import SMALL
from tests.unit.verify.test_uniform_beside import LOOPS

pytestmark = pytest.mark.storm

UAV = str(EXAMPLES / "uav.afsm")


def _loops(tmp: Path) -> str:
    path = tmp / "loops.afsm"
    path.write_text(LOOPS, encoding="utf-8")
    return str(path)


def _plan(path: str, consts: dict[str, str]) -> tuple[explicit.Plan, explore.Compiled]:
    low = lowered(load(path, consts).model, "nondet")
    names = tuple(n for p in low.model.properties for n, _ in property_variants(low, p))
    p = explicit.plan(low, names)
    explicit.plan_uniform(low, tuple(pr.name for pr in low.model.properties), p)
    return p, explore.compile_model(low, p.targets, p.rewards)


CASES = {
    "uav": (UAV, SMALL["uav"]),  # many buckets, sinks, a window of several buckets
    "rover": (str(EXAMPLES / "rover.afsm"), {}),  # late states (a clock set back) and sinks
    "overtake": (str(EXAMPLES / "overtake.afsm"), {}),
}


@pytest.mark.parametrize("case", [*CASES, "loops"])
def test_streamed_values_equal_the_in_memory_pass(case: str, tmp_path: Path) -> None:
    path, consts = CASES[case] if case != "loops" else (_loops(tmp_path), {})
    p, c = _plan(path, consts)
    a = explore_graph.explore(c).arrays
    want = acyclic.solve_many(a, p.queries)
    with scratch.made(str(tmp_path)) as where:
        st = layers.explore(c, scratch.Scratch(where))
        got, pairs = sweep.run(st, p.queries, c.reward_names, len(p.targets))
        assert st.scratch.written > 0 and any(where.iterdir())
    assert st.states == len(a.states) - 1 and st.transitions == len(a.target)
    assert pairs == explicit._mean_transitions(a)
    assert any(q.opt == "mean" for q in p.queries)
    for q in p.queries:
        assert got[q.name] == pytest.approx(want[q.name], rel=1e-12, abs=1e-12), q.name
    # uav: a window of several buckets, smaller than the whole (the ring wraps round)
    shape = {"uav": lambda: len(st.start) > 10 and st.sinks > 0 and max(
                 r - i for i, r in enumerate(st.reach)) >= 1
                 and sweep.window_rows(st) < sum(st.size) / 2,
             "rover": lambda: st.late > 0,
             "loops": lambda: a.stay is not None,
             "overtake": lambda: st.sinks > 0}
    assert shape[case](), case  # the case covers what it is here for
    assert not list(tmp_path.glob(scratch.PREFIX + "*"))


def test_queries_in_sweeps_of_their_own_have_the_same_values(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    p, c = _plan(*CASES["uav"])
    with scratch.made(str(tmp_path)) as where:
        st = layers.explore(c, scratch.Scratch(where))
        together, pairs = sweep.run(st, p.queries, c.reward_names, len(p.targets))
        rows = sweep.live_rows(st)
        assert len(sweep.sweeps(p.queries, c.reward_names, rows)) == 1
        monkeypatch.setattr(sweep, "SWEEP_BYTES", 1)  # a sweep for each query
        monkeypatch.setattr(sweep, "SWEEP_SHARE", 0.0)
        assert len(sweep.sweeps(p.queries, c.reward_names, rows)) == len(p.queries)
        apart, pairs_apart = sweep.run(st, p.queries, c.reward_names, len(p.targets))
    assert apart == together and pairs_apart == pairs > 0


def test_the_pass_keeps_only_the_live_states_a_brute_force_count_says(tmp_path: Path) -> None:
    # live while solving bucket i: its own states, and those of later buckets that bucket
    # i or an earlier one points at (counted here from every file's successors)
    p, c = _plan(*CASES["uav"])
    with scratch.made(str(tmp_path)) as where:
        st = layers.explore(c, scratch.Scratch(where))
        lowest: dict[int, int] = {}  # regular state -> its lowest predecessor bucket
        for i in range(len(st.start)):
            stored = st.scratch.load(f"b{i}")["target"]
            for g in layers.widen(stored, st.start[i]).tolist():
                if g >= 0:
                    lowest[g] = min(lowest.get(g, i), i)
        got, _ = sweep.run(st, p.queries, c.reward_names, len(p.targets))
    bucket = {g: i for i, (s, n) in enumerate(zip(st.start, st.size, strict=True))
              for g in range(s, s + n)}
    live = [st.size[i] + sum(1 for g, low in lowest.items() if bucket[g] > i and low <= i)
            for i in range(len(st.start))]
    assert sweep.live_rows(st) == max(live)
    # finer than the window of buckets it replaces, on a case where that matters
    assert sweep.live_rows(st) < sweep.window_rows(st) / 2
    want = acyclic.solve_many(explore_graph.explore(c).arrays, p.queries)
    for q in p.queries:
        assert got[q.name] == pytest.approx(want[q.name], rel=1e-12, abs=1e-12), q.name


def test_successors_are_stored_as_int32_offsets_where_they_fit() -> None:
    late = np.iinfo(np.int64).min  # a branch into a late state, numbered later
    small = np.array([5, 7, -1, -3, late, 6], np.int64)
    stored = layers.narrow(small, 5)
    assert stored.dtype == np.int32 and stored.tolist()[:4] == [0, 2, -1, -3]
    assert layers.widen(stored, 5).tolist() == small.tolist()
    big = np.array([5, 5 + 2 ** 31, -1, late], np.int64)  # too far for int32: int64 kept
    assert layers.narrow(big, 5).dtype == np.int64
    assert layers.widen(layers.narrow(big, 5), 5).tolist() == big.tolist()


def test_a_model_the_explorer_gives_up_on_is_given_up_with_the_scratch_too(
        tmp_path: Path) -> None:
    path = str(EXAMPLES / "auv.afsm")
    _, c = _plan(path, {})
    with pytest.raises(explore.GiveUp, match="clock went back"):
        explore_graph.explore(c)
    with scratch.made(str(tmp_path)) as where, pytest.raises(explore.GiveUp,
                                                             match="clock went back"):
        layers.explore(c, scratch.Scratch(where))
    low = lowered(load(path, {}).model, "nondet")
    names = tuple(n for q in low.model.properties for n, _ in property_variants(low, q))
    work = tmp_path / "job"
    work.mkdir()
    assert explicit.answer(low, names, "MDP", lambda _e, _d: None, scratch=str(work)) is None
    assert list(work.iterdir()) == []


def test_verify_with_a_scratch_gives_the_same_answer_and_leaves_nothing(tmp_path: Path) -> None:
    plain = run(UAV, consts=SMALL["uav"], isolate=False)
    streamed = run(UAV, consts=SMALL["uav"], isolate=False, scratch=str(tmp_path))
    assert streamed.model.engine == "explicit" and "MB of scratch disk" in str(
        streamed.model.engine_reason)
    for a, b in zip(plain.properties, streamed.properties, strict=True):
        for x, y in ((a.min, b.min), (a.max, b.max), (a.uniform, b.uniform)):
            assert x is not None and y == pytest.approx(x, rel=1e-12, abs=1e-12), a.name
    assert (plain.model.states, plain.model.transitions, plain.model.choices) == (
        streamed.model.states, streamed.model.transitions, streamed.model.choices)
    assert list(tmp_path.iterdir()) == []


def test_the_scratch_of_a_watched_child_is_removed_too(tmp_path: Path) -> None:
    said: list[str] = []
    res = run(UAV, consts=SMALL["uav"], isolate=True, scratch=str(tmp_path),
              properties=["success"], progress=said.append)
    assert res.model.processes == 1 and "scratch disk" in str(res.model.engine_reason)
    assert any("into the scratch directory" in s for s in said), said
    assert list(tmp_path.iterdir()) == []


def test_a_scratch_that_is_no_writable_directory_is_refused_up_front(tmp_path: Path) -> None:
    afile = tmp_path / "file"
    afile.write_text("x", encoding="utf-8")
    for bad, words in ((tmp_path / "missing", "does not exist"), (afile, "not a directory")):
        with pytest.raises(CompileError) as exc:
            run(UAV, consts=SMALL["uav"], scratch=str(bad))
        d = exc.value.diagnostics[0]
        assert d.code == "E419" and words in d.message and d.hint
    r = run_cli("verify", UAV, "--scratch", str(tmp_path / "missing"))
    assert r.code == 1 and "E419" in r.err and "Traceback" not in r.err, r.err


def _fail_after(k: int, exc: BaseException) -> Any:
    seen: list[Path] = []

    def hook(path: Path) -> None:
        seen.append(path)
        if len(seen) > k:
            raise exc

    return hook


def test_a_full_disk_is_a_clear_error_and_leaves_nothing(tmp_path: Path,
                                                         monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(scratch, "FAULT", _fail_after(40, OSError(errno.ENOSPC, "No space")))
    with pytest.raises(CompileError) as exc:
        run(UAV, consts=SMALL["uav"], isolate=False, scratch=str(tmp_path))
    d = exc.value.diagnostics[0]
    assert d.code == "E419" and "scratch disk is full" in d.message and d.hint, d
    assert list(tmp_path.iterdir()) == []


def test_an_interrupt_leaves_nothing(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(scratch, "FAULT", _fail_after(40, KeyboardInterrupt()))
    with pytest.raises(KeyboardInterrupt):
        run(UAV, consts=SMALL["uav"], isolate=False, scratch=str(tmp_path))
    assert list(tmp_path.iterdir()) == []


def test_a_bucket_is_one_file_read_back_with_its_appended_records(tmp_path: Path) -> None:
    # every dtype and shape the layers use, empty ones too, in one file; an appended
    # record's array replaces the earlier one of its name; written counts the bytes on disk
    s = scratch.Scratch(tmp_path)
    first = {"keys": np.array([3, 1, 2], np.int64), "nchoice": np.array([1, 2], np.int32),
             "label0": np.array([True, False, True]), "none": np.zeros(0, np.int64),
             "layers": np.array(7, np.int64), "prob": np.arange(6, dtype=np.uint16)}
    s.save("b0", **first)
    s.save("b0", append=True, target=np.array([-5, 2 ** 31 - 1], np.int32),
           prob=np.array([1.5, 2.5]))
    got = s.load("b0")
    assert [p.name for p in tmp_path.iterdir()] == ["b0"]
    assert set(got) == {*first, "target"}
    for k, a in first.items():
        if k != "prob":
            assert got[k].dtype == a.dtype and got[k].shape == a.shape
            assert got[k].tolist() == a.tolist(), k
    assert got["prob"].tolist() == [1.5, 2.5] and got["target"].tolist() == [-5, 2 ** 31 - 1]
    got["keys"][0] = 9  # writable, as np.load's arrays are
    assert s.written == (tmp_path / "b0").stat().st_size
    s.save("b0", keys=np.zeros(2, np.int64))  # replaced, not appended
    assert list(s.load("b0")) == ["keys"] and s.written == (tmp_path / "b0").stat().st_size
    s.remove("b0")
    assert s.written == 0 and not list(tmp_path.iterdir())


def test_a_sweep_with_a_scratch_gives_the_in_memory_sweeps_values_and_leaves_nothing(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    # two points of the SMALL UAV (T_LIMIT 100 and 120): each streamed through a directory
    # of its own (the files written there, seen by the fault hook), the values those of
    # the sweep in memory; the same through `afsmc sweep --scratch`
    consts = {"WIDTH": "2", "HEIGHT": "2"}
    names = ["success", "timeout"]
    plain = sweep_points(UAV, "T_LIMIT", [100, 120], consts=consts, properties=names,
                  isolate=False, no_scratch=True, jobs=1)
    written: list[Path] = []
    monkeypatch.setattr(scratch, "FAULT", written.append)
    streamed = sweep_points(UAV, "T_LIMIT", [100, 120], consts=consts, properties=names,
                     isolate=False, scratch=str(tmp_path), jobs=1)
    # a directory per point (and per model of a point: the MDP's uniform DTMC comes from it)
    assert len({p.parent for p in written}) == 2 and all(
        p.parent.parent == tmp_path for p in written)
    args = ["sweep", UAV, "--const", "WIDTH=2", "--const", "HEIGHT=2", "--const",
            "T_LIMIT=100,120", "-p", "success", "-p", "timeout", "--json"]
    cli = run_cli(*args, "--scratch", str(tmp_path))
    assert cli.code == 0, cli.err
    want = [[(q.min, q.max, q.uniform) for q in p.properties] for p in plain.points]
    for got in ([[(q.min, q.max, q.uniform) for q in p.properties] for p in streamed.points],
                [[(q["min"], q["max"], q["uniform"]) for q in p["properties"]]
                 for p in json.loads(cli.out)["points"]]):
        assert np.allclose(np.array(got, float), np.array(want, float), rtol=1e-12,
                           atol=1e-12), (got, want)
    assert [(p.states, p.transitions) for p in streamed.points] == [
        (p.states, p.transitions) for p in plain.points]
    assert list(tmp_path.iterdir()) == []
