"""The compiled bookkeeping of afsmc's explorer (afsmc.verify.kernels.hashing, taken by
afsmc.verify.explorer.explore_graph when `kernels.enabled` says so) against its oracles:
the hash tables against Python sets and dicts, the coded probabilities against the numpy
ProbTable, and whole explorations with AFSMC_KERNELS=numba against AFSMC_KERNELS=numpy,
bit for bit (the order of the states is part of the output: strategies, witnesses)."""

from __future__ import annotations

import dataclasses
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from afsmc.verify import kernels, run
from afsmc.verify.arrays import acyclic
from afsmc.verify.explorer import explore_graph, keysets
from afsmc.verify.explorer.explore import GiveUp
from afsmc.verify.kernels import blocks, hashing
from afsmc.verify.stream import layers, scratch, sweep
from tests.unit.verify.test_streaming import CASES, _loops, _plan

KEYS = st.lists(st.integers(0, (1 << 62) - 1) | st.integers(0, 40), max_size=200)


def _differences(x: Any, y: Any, where: str = "") -> list[str]:
    """Where `x` and `y` differ: arrays by dtype, shape and bytes; dataclasses, dicts and
    lists field by field; anything else by ==."""
    if type(x) is not type(y):
        return [f"{where}: {type(x).__name__} vs {type(y).__name__}"]
    if isinstance(x, np.ndarray):
        same = x.dtype == y.dtype and x.shape == y.shape and x.tobytes() == y.tobytes()
        return [] if same else [where]
    if dataclasses.is_dataclass(x):
        return [d for f in dataclasses.fields(x)
                for d in _differences(getattr(x, f.name), getattr(y, f.name), f"{where}.{f.name}")]
    if isinstance(x, dict):
        if x.keys() != y.keys():
            return [f"{where}: keys"]
        return [d for k in x for d in _differences(x[k], y[k], f"{where}[{k}]")]
    if isinstance(x, (list, tuple)):
        if len(x) != len(y):
            return [f"{where}: length"]
        return [d for i, (u, v) in enumerate(zip(x, y, strict=True))
                for d in _differences(u, v, f"{where}[{i}]")]
    return [] if x == y else [where]


def _home(key: int, mask: int) -> int:
    """The kernel's home slot of `key`, in Python integers."""
    return ((key * 0x9E3779B97F4A7C15) % (1 << 64) >> 29) & mask


# --- the hash tables against Python's sets and dicts ------------------------------------


@settings(max_examples=60, deadline=None)
@given(st.lists(KEYS, max_size=6))
def test_a_key_set_adds_the_absent_keys_in_first_seen_order(rounds: list[list[int]]) -> None:
    s = hashing.KeySet()
    order: dict[int, int] = {}  # the oracle: key -> its rank, in insertion order
    for keys in rounds:
        new = s.add(np.array(keys, np.int64))
        want = [k for k in dict.fromkeys(keys) if k not in order]
        assert new.tolist() == want
        base = len(order)
        order.update((k, base + i) for i, k in enumerate(want))
        assert s.keys().tolist() == list(order)
    probe = [k for keys in rounds for k in keys] + [1 << 61, 7, 0, -5]
    assert s.find(np.array(probe, np.int64)).tolist() == [order.get(k, -1) for k in probe]
    # mapped through values, only keys in [lo, hi) looked for
    values = np.arange(s.size, dtype=np.int64) * 3 + 1
    lo, hi = 5, 1 << 61
    assert s.find(np.array(probe, np.int64), lo, hi, values).tolist() == [
        3 * order[k] + 1 if k in order and lo <= k < hi else -1 for k in probe]


def test_a_key_set_resolves_collisions_and_grows() -> None:
    s = hashing.KeySet()
    assert len(s.slots) <= 4
    rng = np.random.default_rng(48)
    keys = rng.choice(1 << 40, size=3000, replace=False).astype(np.int64)
    for part in np.array_split(keys, 7):
        assert s.add(np.concatenate([part, part[::-1]])).tolist() == part.tolist()
    assert len(s.slots) >= 2 * len(keys) and s.size == len(keys)
    # the table holds keys whose home slots coincide: found by linear probing
    homes = [_home(k, len(s.slots) - 1) for k in keys.tolist()]
    assert len(set(homes)) < len(homes)
    assert s.find(keys).tolist() == list(range(len(keys)))
    assert (s.find(keys + 1) == -1).all()
    assert s.add(keys).size == 0


@settings(max_examples=60, deadline=None)
@given(st.lists(st.tuples(st.integers(0, 6), st.integers(0, 1 << 40)), max_size=100))
def test_keys_grouped_by_bucket_keep_their_order(pairs: list[tuple[int, int]]) -> None:
    want: dict[int, list[int]] = {}
    for b, k in pairs:
        want.setdefault(b + 40, []).append(k)
    got = hashing.grouped(np.array([b + 40 for b, _ in pairs], np.int64),
                          np.array([k for _, k in pairs], np.int64))
    assert [(b, part.tolist()) for b, part in got] == sorted(want.items())


@settings(max_examples=60, deadline=None)
@given(st.sets(st.tuples(st.integers(0, 5), st.integers(0, (1 << 20) - 1)), max_size=300),
       st.lists(st.tuples(st.integers(0, 9), st.integers(0, (1 << 20) - 1)), max_size=50))
def test_regions_number_the_keys_by_position(entries: set[tuple[int, int]],
                                             probes: list[tuple[int, int]]) -> None:
    shift = 20  # a key's region: its bucket, key >> 20
    keys = [b << shift | low for b, low in entries]
    index = hashing.Regions(np.array(keys, np.int64), shift)
    where = {k: i for i, k in enumerate(keys)}
    asked = keys + [b << shift | low for b, low in probes] + [-1, 1 << 40]
    assert index.find(np.array(asked, np.int64)).tolist() == [where.get(k, -1) for k in asked]


@settings(max_examples=60, deadline=None)
@given(st.lists(st.sampled_from([0.1, 0.25, 1 / 3, 0.5, 0.9, 1.0, 2 / 3]), max_size=100),
       st.lists(st.sampled_from([0.1, 0.25, 1 / 3, 0.5, 0.9, 1.0, 2 / 3, 0.7]), max_size=50))
def test_probabilities_coded_by_the_kernel_are_the_tables_codes(
        first: list[float], then: list[float]) -> None:
    reference, compiled = keysets.ProbTable(), keysets.ProbTable()
    for values in (first, then, first + then):
        prob = np.array(values)
        want = reference.encode(prob)
        got = compiled.encode(prob, fast=True)
        assert got.dtype == want.dtype and got.tolist() == want.tolist()
        known = compiled.known
        direct = hashing.encode(known, compiled.code, prob) if len(known) else None
        assert direct is None or direct.tolist() == want.tolist()
    assert reference.table().tolist() == compiled.table().tolist()
    assert hashing.encode(np.array([0.5]), np.zeros(1, np.uint32), np.array([0.5, 0.7])) is None


@settings(max_examples=40, deadline=None)
@given(st.lists(st.tuples(st.lists(st.integers(0, 3), min_size=1, max_size=30),
                          st.booleans()), max_size=8))
def test_frontiers_in_hash_sets_wait_with_the_same_keys(rounds: list[tuple[list[int], bool]]
                                                        ) -> None:
    # bucket = key >> 8; each round's keys spread over buckets 0..3, some added by the
    # numpy path first (a model whose kernels start part way)
    sorted_, hashed = keysets.Frontiers(), keysets.Frontiers()
    for i, (buckets, fast) in enumerate(rounds):
        b = np.array(buckets, np.int64)
        keys = b << 8 | (np.arange(len(b)) * 7 + i) % 5
        sorted_.add(b, keys)
        hashed.add(b, keys, fast)
    assert sorted(sorted_.pending) == sorted(hashed.pending)
    for b in sorted(sorted_.pending):
        assert hashed.take(b).tolist() == sorted_.take(b).tolist()


@settings(max_examples=60, deadline=None)
@given(st.lists(st.lists(st.lists(st.integers(0, 4), min_size=1, max_size=3), min_size=1,
                         max_size=3), max_size=12), st.randoms(use_true_random=False))
def test_a_block_reordered_by_the_kernel_is_numpys_gather(
        graph: list[list[list[int]]], rnd: Any) -> None:
    # states -> choices -> branches (successor keys 0..4; state s has key s)
    n = len(graph)
    nchoice = np.array([len(ch) for ch in graph], np.int32)
    nbranch = np.array([len(br) for ch in graph for br in ch], np.int32)
    target = np.array([t for ch in graph for br in ch for t in br], np.int64)
    prob = np.arange(len(target)) / 7.0
    states, choices = explore_graph._offsets(nchoice), explore_graph._offsets(nbranch)
    keys = np.arange(n, dtype=np.int64)
    perm = np.array(rnd.sample(range(n), n), np.int64)
    want = explore_graph._permuted(perm, states, choices, nbranch, target, prob, False)
    got = blocks.permuted(perm, states, choices, nbranch, target, prob)
    assert _differences(list(want), list(got)) == []
    owner = np.repeat(np.repeat(np.arange(n), nchoice), nbranch)
    sink = [all(t == s for br in ch for t in br) for s, ch in enumerate(graph)]
    assert (np.bincount(owner[target != owner], minlength=n) == 0).tolist() == sink
    assert blocks.absorbing(states, choices, target, keys).tolist() == sink


@settings(max_examples=60, deadline=None)
@given(st.lists(st.tuples(st.integers(0, 5), st.integers(0, 3)), max_size=40))
def test_choices_sorted_by_state_by_the_kernel_are_numpys_stable_sort(
        choices: list[tuple[int, int]]) -> None:
    # each choice: (its state, its number of branches)
    state = np.array([s for s, _ in choices], np.int64)
    first = explore_graph._offsets(np.array([k for _, k in choices], np.int32))
    order, branch = blocks.by_state(state, np.bincount(state, minlength=6), first)
    want = np.argsort(state, kind="stable")
    assert order.tolist() == want.tolist()
    assert branch.tolist() == acyclic._ranges(first[want], first[want + 1]).tolist()


def _blocks_with(targets: list[int]) -> list[explore_graph.Block]:
    z = np.zeros(0, np.int32)
    target = np.array(targets, np.int64)
    return [explore_graph.Block(np.zeros(0, np.int64), z, z, target, np.zeros(len(target),
                                np.uint32), [], [], [], z)]


def test_a_successor_that_was_not_explored_gives_up_on_both_paths(tmp_path: Path) -> None:
    _, c = _plan(_loops(tmp_path), {})
    keys = np.array([c.initial, c.initial + 1, c.initial + 5], np.int64)
    order = np.argsort(keys)
    numbered, initial = explore_graph._targets_hashed(_blocks_with([c.initial + 5, c.initial]),
                                                      keys, c)
    assert numbered.tolist() == [2, 0] and initial == 0
    for missing in (c.initial + 2, c.initial + 6, c.initial + (1 << 40)):
        with pytest.raises(GiveUp, match="not explored"):
            explore_graph._targets_hashed(_blocks_with([c.initial, missing]), keys, c)
        with pytest.raises(GiveUp, match="not explored"):
            explore_graph._targets(_blocks_with([c.initial, missing]), order, keys[order],
                                   c.initial)


# --- whole explorations: compiled and numpy, bit for bit --------------------------------


def _explored(path: str, consts: dict[str, str], mode: str, monkeypatch: pytest.MonkeyPatch
              ) -> explore_graph.Explored:
    monkeypatch.setenv("AFSMC_KERNELS", mode)
    _, c = _plan(path, consts)
    return explore_graph.explore(c)


def _case(case: str, tmp: Path) -> tuple[str, dict[str, str]]:
    return CASES[case] if case != "loops" else (_loops(tmp), {})


@pytest.mark.parametrize("case", ["uav", "rover", "loops"])
def test_the_compiled_exploration_equals_numpys_bit_for_bit(
        case: str, tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    path, consts = _case(case, tmp_path)
    numpy_ = _explored(path, consts, "numpy", monkeypatch)
    cut: list[int] = []  # the absorbing states of each bucket put first, then cut off
    real = explore_graph._cut
    monkeypatch.setattr(explore_graph, "_cut", lambda blk, k: (cut.append(k), real(blk, k))[1])
    compiled = _explored(path, consts, "numba", monkeypatch)
    assert _differences(numpy_, compiled) == []
    # the case covers what it is here for: many buckets with sinks, late states, self-loops
    a = compiled.arrays
    shape = {"uav": len(a.layers) > 100 and sum(k > 0 for k in cut) > 10,
             "rover": compiled.states > 500, "loops": a.stay is not None}
    assert shape[case], case


def test_kernels_taken_part_way_through_give_the_same_exploration(
        monkeypatch: pytest.MonkeyPatch) -> None:
    # auto: numpy for the first buckets, the kernels once past the threshold
    path, consts = CASES["uav"]
    want = _explored(path, consts, "numpy", monkeypatch)
    monkeypatch.delenv("AFSMC_KERNELS")
    monkeypatch.setattr(kernels, "THRESHOLD", want.states // 3)
    taken = {keysets.Sorted: 0, hashing.Found: 0}  # buckets explored by each
    for cls in list(taken):

        def counting(self: Any, *args: Any, real: Any = cls.__init__, cls: Any = cls
                     ) -> None:
            taken[cls] += 1
            real(self, *args)

        monkeypatch.setattr(cls, "__init__", counting)
    _, c = _plan(path, consts)
    got = explore_graph.explore(c)
    assert _differences(want, got) == []
    assert all(taken.values()), taken  # some buckets each way


def test_the_streamed_exploration_is_the_same_under_the_kernels(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    path, consts = CASES["rover"]  # late states: Frontiers and the excluded sinks
    got = []
    for mode in ("numpy", "numba"):
        monkeypatch.setenv("AFSMC_KERNELS", mode)
        p, c = _plan(path, consts)
        with scratch.made(str(tmp_path)) as where:
            st_ = layers.explore(c, scratch.Scratch(where))
            values, pairs = sweep.run(st_, p.queries, c.reward_names, len(p.targets))
            files = {f"b{i}": st_.scratch.load(f"b{i}")["target"] for i in range(len(st_.start))}
        got.append((dataclasses.replace(st_, scratch=None), values, pairs, files))
    assert _differences(got[0], got[1]) == []


@pytest.mark.storm
def test_verify_answers_the_same_under_the_kernels(monkeypatch: pytest.MonkeyPatch) -> None:
    path, consts = CASES["uav"]
    answers = []
    for mode in ("numpy", "numba"):
        monkeypatch.setenv("AFSMC_KERNELS", mode)  # the engine's child process inherits it
        r = run(path, consts=consts)
        sizes = [(m.type, m.states, m.choices, m.transitions, m.engine, m.solver)
                 for m in (r.model, r.uniform_model) if m is not None]
        answers.append(([(p.name, p.min, p.max, p.verdict) for p in r.properties], sizes))
    assert answers[0] == answers[1]
    assert answers[0][1][0][4] == "explicit" and len(answers[0][1]) == 2
