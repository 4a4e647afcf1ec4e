"""afsmc's exploration (afsmc.verify.explorer.explore_graph) with each bucket's layers
written to the scratch directory as soon as its successors are known.

The clock only grows: a transition from bucket b lands in a bucket from b to the largest
bucket b's states reach (its "reach", recorded while exploring), in the absorbing states
split off every bucket (the sinks), or in the late states (the clock set back). So a
bucket's successors are resolved into state numbers once every bucket up to its reach is
explored: each bucket is written at once, its successors' keys held in memory (or, past
HOLD_BYTES of them, in a file of their own, read back then and removed) until its
numbers are appended to the bucket's file, so that only the keys of the buckets not yet
resolved (and of those they reach) stay in memory: sorted, or in hash sets on large
models (afsmc.verify.kernels.streamed). Numbers: the regular
states in exploration order, a bucket's states in its layered order (global, from 0); the
sinks and then the late states in a space of their own ("other", stored as -1 - o). A
branch into a late state keeps its key (the late states are numbered at the end) and is
resolved when its bucket is read back.

While resolving, each bucket also records the regular states whose lowest predecessor
bucket it is (its "dies", as offsets from its first number): once the backward pass has
solved that bucket, no bucket still to be solved needs their values
(afsmc.verify.stream.sweep keeps a value only that long). The initial state is never in
one; a state no other bucket points at is in its own bucket's.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any, Union

import numpy as np
import numpy.typing as npt

from afsmc.verify import kernels
from afsmc.verify.arrays import acyclic
from afsmc.verify.arrays.acyclic import I64
from afsmc.verify.explorer import explore_graph
from afsmc.verify.explorer.explore import Compiled, GiveUp, Notify, TooManyStates
from afsmc.verify.explorer.explore_graph import Block
from afsmc.verify.explorer.keysets import Frontiers, ProbTable, found_in, unique
from afsmc.verify.stream.scratch import Scratch

if TYPE_CHECKING:
    from afsmc.verify.kernels.streamed import Bucket, Numbered


@dataclass
class Streamed:
    """What the backward pass needs besides the files: per explored bucket (in order) its
    first global number, its size, the index of the last bucket it reaches and how many
    states it is the lowest predecessor bucket of (`dies`); the sinks' files and counts; the late states' count; the initial state (>= 0 regular, else
    -1 - o); the probabilities' table."""

    scratch: Scratch
    start: list[int] = field(default_factory=list)
    size: list[int] = field(default_factory=list)
    reach: list[int] = field(default_factory=list)
    dies: list[int] = field(default_factory=list)
    sink_start: list[int] = field(default_factory=list)  # per bucket: its first sink
    sinks: int = 0
    late: int = 0
    initial: int = 0
    table: Any = None
    choices: int = 0
    transitions: int = 0
    late_keys: I64 = field(default_factory=lambda: np.zeros(0, np.int64))

    @property
    def states(self) -> int:
        return sum(self.size) + self.sinks + self.late


class _Index:
    """Sorted keys with a number each, as a few sorted runs merged like a binary
    counter (see keysets.Keys)."""

    def __init__(self) -> None:
        self.runs: list[tuple[I64, I64]] = []

    def add(self, keys: I64, numbers: I64) -> None:
        order = np.argsort(keys, kind="stable")
        self.runs.append((keys[order], numbers[order]))
        while len(self.runs) > 1 and len(self.runs[-2][0]) <= 2 * len(self.runs[-1][0]):
            k1, n1 = self.runs.pop()
            k0, n0 = self.runs[-1]
            keys_, nums = np.concatenate([k0, k1]), np.concatenate([n0, n1])
            o = np.argsort(keys_, kind="stable")
            self.runs[-1] = (keys_[o], nums[o])

    def sorted_keys(self) -> I64:
        return np.sort(np.concatenate([k for k, _ in self.runs])) if self.runs else \
            np.zeros(0, np.int64)

    def by_number(self) -> I64:
        """Every key, in the order of their numbers (0, 1, ...)."""
        if not self.runs:
            return np.zeros(0, np.int64)
        keys = np.concatenate([k for k, _ in self.runs])
        numbers = np.concatenate([n for _, n in self.runs])
        order = np.argsort(numbers)
        assert (numbers[order] == np.arange(len(numbers))).all()
        out: I64 = keys[order]
        return out

    def find(self, keys: I64, out: I64, todo: acyclic.Bools) -> None:
        """Write the number of each key of `keys[todo]` found into `out`, clearing `todo`."""
        for sk, nums in self.runs:
            idx = np.flatnonzero(todo)
            if not idx.size or not len(sk):
                continue
            hit = found_in(sk, keys[idx])
            out[idx[hit]] = nums[np.searchsorted(sk, keys[idx[hit]])]
            todo[idx[hit]] = False


class _Hashed:
    """The sinks' keys numbered in a hash set (afsmc.verify.kernels.streamed): _Index's
    compiled counterpart, taken on large models. Filled only when asked: each bucket's
    own sinks are looked up in its window entry (afsmc.verify.kernels.streamed.Bucket),
    so this is only asked for a key into an earlier bucket (a clock set back) and for
    the late states."""

    def __init__(self, keys: I64) -> None:
        self.waiting: list[I64] = [keys]  # added, not in the set yet
        self.count = len(keys)
        self.set: Numbered | None = None

    @classmethod
    def of(cls, index: _Index) -> _Hashed:
        """The keys of `index` (numbered 0, 1, ... in the order added)."""
        return cls(index.by_number())

    def add(self, keys: I64, numbers: I64) -> None:
        assert not len(numbers) or int(numbers[0]) == self.count
        self.waiting.append(keys)
        self.count += len(keys)

    def _filled(self) -> Numbered:
        from afsmc.verify.kernels.streamed import Numbered

        if self.set is None:
            self.set = Numbered(np.zeros(0, np.int64), 0)
        for keys in self.waiting:
            self.set.add(keys)
        self.waiting = []
        return self.set

    def find(self, keys: I64, out: I64, todo: acyclic.Bools) -> None:
        """Write the number of each key of `keys[todo]` found into `out`, clearing `todo`."""
        at = np.flatnonzero(todo)
        got = self.lookup(keys[at])
        hit = got >= 0
        out[at[hit]] = got[hit]
        todo[at[hit]] = False

    def lookup(self, keys: I64) -> I64:
        """The number of each key, -1 where it is no sink."""
        got = np.full(len(keys), -1, np.int64)
        if len(keys):
            self._filled().find(np.ascontiguousarray(keys), np.arange(len(keys)), got)
        return got

    def sorted_keys(self) -> I64:
        return np.sort(self._filled().keys())


# a bucket's keys in the window: sorted with their numbers (the numpy reference), or its
# states and sinks numbered in hash sets (the compiled path)
Entry = Union[tuple[I64, I64], "Bucket"]


def _hashed(window: dict[int, Entry], sinks: _Index, buckets: list[int], out: Streamed
            ) -> None:
    """The window's buckets moved to hash sets (the exploration has grown past the
    kernels' threshold), each with its own sinks."""
    from afsmc.verify.kernels.streamed import Bucket

    every = sinks.by_number()
    for b, e in window.items():
        if isinstance(e, tuple):
            keys, numbers = e
            order = np.argsort(numbers)
            i = buckets.index(b)
            lo = out.sink_start[i]
            hi = out.sink_start[i + 1] if i + 1 < len(out.sink_start) else out.sinks
            window[b] = Bucket(keys[order], int(numbers[order[0]]) if len(numbers) else 0,
                               every[lo:hi], lo)


def _save_block(s: Scratch, name: str, blk: Block, target: I64 | None) -> None:
    """The block as one file, what the backward pass reads: its successors (`target`) too
    unless None (a bucket's are appended once they are numbered); not its keys (a
    bucket's are a file of their own, read only to check the late states)."""
    arrays: dict[str, Any] = {
        "nchoice": blk.nchoice, "nbranch": blk.nbranch,
        "prob": blk.prob, "layers": np.asarray(blk.layers, np.int64),
        **({} if target is None else {"target": target})}
    for i, (at, values) in enumerate(blk.reward):
        arrays[f"reward{i}_at"], arrays[f"reward{i}_v"] = at, values
    for i, lab in enumerate(blk.labels):
        arrays[f"label{i}"] = lab
    s.save(name, **arrays)


# The most bytes of successors' keys that wait in memory for their buckets to be
# numbered; the keys of a bucket past it wait in a file of its own (`k{i}`). Each
# bucket's would take two more opens and a removal.
HOLD_BYTES = 1 << 28


@dataclass
class _Waiting:
    """An explored bucket, written with its successors' keys, some of whose successor
    buckets are not explored yet."""

    index: int
    bucket: int
    reach: int  # the largest bucket its branches reach


def explore(c: Compiled, s: Scratch, notify: Notify | None = None,
            max_states: int | None = None) -> Streamed:
    """Every state reachable from the initial one, bucket by bucket, written to `s`;
    raises GiveUp as explore_graph.explore does, TooManyStates past `max_states`."""
    waiting, table = Frontiers(), ProbTable()
    waiting.pending[int(c.layout.bucket_of(np.array([c.initial]))[0])] = [
        np.array([c.initial], np.int64)]
    out = Streamed(s)
    sinks: _Index | _Hashed = _Index()
    unresolved: list[_Waiting] = []
    window: dict[int, Entry] = {}  # bucket -> its keys and their numbers
    fast = False
    held: dict[int, I64] = {}  # bucket index -> its successors' keys, kept in memory
    # bucket -> its first number, and which of its states some resolved bucket points at
    seen: dict[int, tuple[int, acyclic.Bools]] = {}
    buckets: list[int] = []
    count = rounds = 0
    shown = time.monotonic()
    initial = np.array([c.initial], np.int64)
    while waiting.pending:
        b = min(waiting.pending)
        if not fast and kernels.enabled(count):
            fast = True
            assert isinstance(sinks, _Index)
            _hashed(window, sinks, buckets, out)
            sinks = _Hashed.of(sinks)
        begin = waiting.take(b)
        block, known, took = explore_graph.explore_bucket(
            c, table, begin, b, waiting, counted=count, max_states=max_states, rounds=rounds)
        rounds += took
        sink, block = explore_graph.split_sinks(block)
        index = len(buckets)
        buckets.append(b)
        first = sum(out.size)
        out.start.append(first)
        out.size.append(len(block.keys))
        out.sink_start.append(out.sinks)
        sink_numbers = np.arange(out.sinks, out.sinks + len(sink.keys), dtype=np.int64)
        sinks.add(sink.keys, sink_numbers)
        out.sinks += len(sink.keys)
        _save_block(s, f"s{index}", sink, -1 - sink_numbers[
            acyclic._state_of_branches(explore_graph._offsets(sink.nchoice),
                                       explore_graph._offsets(sink.nbranch))])
        if fast:
            from afsmc.verify.kernels.streamed import Bucket

            window[b] = Bucket(block.keys, first, sink.keys, int(sink_numbers[0]) if len(
                sink_numbers) else out.sinks)
            s.save(f"keys{index}", keys=block.keys)  # for _check_late
        else:
            numbers = np.arange(first, first + len(block.keys), dtype=np.int64)
            order = np.argsort(block.keys)
            window[b] = entry = (block.keys[order], numbers[order])
            s.save(f"keys{index}", keys=entry[0])  # for _check_late
            del order, numbers, entry
        seen[b] = (first, np.zeros(len(block.keys), bool))
        if index == 0:
            out.initial = _resolve_span([(b, window[b])], sinks, initial, c)[0][0]
            if out.initial >= 0:  # its value is read once the pass is over: never dropped
                seen[b][1][out.initial - first] = True
        reach = int(c.layout.bucket_of(block.target).max()) if len(block.target) else b
        unresolved.append(_Waiting(index, b, max(reach, b)))
        out.choices += len(block.nbranch) + len(sink.nbranch)
        out.transitions += len(block.target) + len(sink.target)
        _save_block(s, f"b{index}", block, None)
        # its successors' keys, until numbered: in memory while the held ones are few
        if sum(k.nbytes for k in held.values()) + block.target.nbytes <= HOLD_BYTES:
            held[index] = block.target
        else:
            s.save(f"k{index}", target=block.target)
        count += len(known)
        del block, sink, known, sink_numbers
        if max_states is not None and count > max_states:
            raise TooManyStates(count)
        explore_graph.narrow(count, rounds)
        nxt = min(waiting.pending) if waiting.pending else None
        while unresolved and (nxt is None or unresolved[0].reach < nxt):
            _finish(s, out, unresolved.pop(0), window, seen, sinks, buckets, c, held)
            low = unresolved[0].bucket if unresolved else nxt
            for t in [t for t in window if low is None or t < low]:
                del window[t], seen[t]
        if index % explore_graph.TRIM_BUCKETS == explore_graph.TRIM_BUCKETS - 1:
            acyclic.trim_heap()
        if notify is not None and time.monotonic() - shown > explore_graph.PROGRESS_EVERY:
            shown = time.monotonic()
            notify("explored", (b, count, s.written))
    assert not unresolved
    acyclic.trim_heap()
    _late(c, s, out, table, waiting, sinks, buckets, count, max_states)
    out.table = table.table()
    s.save("table", prob=out.table)
    return out


def _resolve_span(span: list[tuple[int, Entry]], sinks: _Index | _Hashed, keys: I64,
                  c: Compiled) -> tuple[I64, acyclic.Bools]:
    """_resolve against the keys of several consecutive buckets (their window entries)."""
    if span and not isinstance(span[0][1], tuple):
        target, late, _ = _resolve_hashed(span, sinks, keys, c, None)
        return target, late
    # a bucket's keys are those whose high bits are the bucket: the window's runs, end to
    # end in bucket order, are sorted
    pairs = [e for _, e in span if isinstance(e, tuple)]
    joined = (np.concatenate([k for k, _ in pairs]), np.concatenate([n for _, n in pairs]))
    return _resolve(joined, sinks, keys)


def _resolve_hashed(span: list[tuple[int, Entry]], sinks: _Index | _Hashed, keys: I64,
                    c: Compiled, seen: dict[int, tuple[int, acyclic.Bools]] | None
                    ) -> tuple[I64, acyclic.Bools, I64]:
    """_resolve_span and _dies by the compiled path: each key looked up in its own
    bucket's states and sinks (a bucket of the span: `span[0]` is the bucket resolved),
    the others among every sink; and with `seen`, the dies (as _dies gives them),
    marked while looking up."""
    from afsmc.verify.kernels.streamed import groups

    keys = np.ascontiguousarray(keys)
    out = np.full(len(keys), np.iinfo(np.int64).min, np.int64)
    lo = span[0][0]
    order, cut = groups(c.layout.bucket_of(keys) - lo, span[-1][0] - lo + 1)
    dies = []
    for t, e in span:
        assert not isinstance(e, tuple)
        at = order[cut[t - lo]:cut[t - lo + 1]]
        if seen is None:
            e.resolve(keys, at, out, np.zeros(0, bool))
            continue
        first, mark = seen[t]
        if t == lo:  # no later bucket points at its states: all of them go now
            e.resolve(keys, at, out, np.zeros(0, bool))
            dies.append(np.flatnonzero(~mark).astype(np.int64) + first)
            mark[:] = True
        else:
            dies.append(e.resolve(keys, at, out, mark))
    # the rest: sinks of earlier buckets (a clock set back), or late states
    todo = np.flatnonzero(out == np.iinfo(np.int64).min)
    late = np.zeros(len(keys), bool)
    if todo.size:
        assert isinstance(sinks, _Hashed)
        got = sinks.lookup(keys[todo])
        hit = got >= 0
        out[todo[hit]] = -1 - got[hit]
        miss = todo[~hit]
        out[miss] = keys[miss]
        late[miss] = True
    return out, late, np.concatenate(dies) if dies else np.zeros(0, np.int64)


def _resolve(window: tuple[I64, I64], sinks: _Index | _Hashed, keys: I64
             ) -> tuple[I64, acyclic.Bools]:
    """The numbers of `keys` among the window's regular states (>= 0) or the sinks
    (-1 - o); and which keys are neither (left as they are)."""
    sk, nums = window
    out = keys.copy()
    todo = np.ones(len(keys), bool)
    if len(sk):
        hit = found_in(sk, keys)
        out[hit] = nums[np.searchsorted(sk, keys[hit])]
        todo[hit] = False
    return _sinks(sinks, keys, out, todo)


def _sinks(sinks: _Index | _Hashed, keys: I64, out: I64, todo: acyclic.Bools
           ) -> tuple[I64, acyclic.Bools]:
    """The keys still `todo` that are sinks numbered in `out` (-1 - o); and which keys
    are neither regular nor sinks."""
    other = np.zeros(len(keys), np.int64)
    left = todo.copy()
    sinks.find(keys, other, left)  # clears `left` where a sink's
    is_sink = todo & ~left
    out[is_sink] = -1 - other[is_sink]
    return out, left


def _finish(s: Scratch, out: Streamed, w: _Waiting, window: dict[int, Entry],
            seen: dict[int, tuple[int, acyclic.Bools]], sinks: _Index | _Hashed,
            buckets: list[int], c: Compiled, held: dict[int, I64]) -> None:
    """Resolve the successors of a bucket whose every successor bucket is explored: its
    successors' keys read back, written over by their numbers; and its dies. Buckets
    are resolved in order, so the first to point at a state is its lowest predecessor."""
    span = [(t, window[t]) for t in sorted(window) if w.bucket <= t <= w.reach]
    keys = held.pop(w.index) if w.index in held else s.load(f"k{w.index}")["target"]
    if isinstance(span[0][1], tuple):
        target, late = _resolve_span(span, sinks, keys, c)
        dies = None
    else:
        target, late, dies = _resolve_hashed(span, sinks, keys, c, seen)
    at = np.flatnonzero(late)
    if at.size and (c.layout.bucket_of(keys[at]) >= w.bucket).any():
        raise GiveUp("a successor that was not explored")
    target[at] = np.iinfo(np.int64).min
    out.reach.append(int(np.searchsorted(buckets, w.reach, side="right")) - 1)
    if dies is None:
        dies = _dies(target, w, seen)
    out.dies.append(len(dies))
    first = out.start[w.index]
    # offsets from the bucket's first number: int32 while its reach spans fewer states
    wide = bool(len(dies)) and int(dies[-1]) - first >= 2 ** 31
    s.save(f"b{w.index}", append=True, target=narrow(target, first), dies=(
        dies - first).astype(np.int64 if wide else np.int32),
           **({"late_at": at, "late_key": keys[at]} if at.size else {}))
    s.remove(f"k{w.index}")  # (if it was written)


def narrow(target: I64, first: int) -> npt.NDArray[np.signedinteger[Any]]:
    """A bucket's resolved successors as stored: a regular one as its offset from the
    bucket's `first` number (successors lie in the bucket or a few later), the others
    as they are; int32 where every one fits, a branch into a late state as the type's
    least value (see widen)."""
    late = target == np.iinfo(np.int64).min
    out = np.where(target >= 0, target - first, target)
    kept = out[~late]
    small = not kept.size or (int(kept.min()) > -2 ** 31 and int(kept.max()) < 2 ** 31)
    out = out.astype(np.int32 if small else np.int64)
    out[late] = np.iinfo(out.dtype).min
    return out


def widen(stored: npt.NDArray[np.signedinteger[Any]], first: int) -> I64:
    """The successors `narrow` stored, as numbers again (a late one as int64's least)."""
    out = stored.astype(np.int64)
    out[stored == np.iinfo(stored.dtype).min] = np.iinfo(np.int64).min
    regular = out >= 0
    out[regular] += first
    return out


def _dies(target: I64, w: _Waiting, seen: dict[int, tuple[int, acyclic.Bools]]) -> I64:
    """The regular states (sorted numbers) that bucket `w` points at and no earlier bucket
    did, and those of its own that nothing points at but the initial state; marked seen
    (the compiled path marks them while resolving: _resolve_hashed)."""
    points = unique(target[target >= 0])
    out = []
    for t in sorted(seen):
        if not w.bucket <= t <= w.reach:
            continue
        first, mark = seen[t]
        lo, hi = np.searchsorted(points, [first, first + len(mark)])
        at = points[lo:hi] - first
        if t == w.bucket:  # no later bucket points at its states: all of them go now
            at = np.arange(len(mark), dtype=np.int64)
        new = at[~mark[at]]
        mark[new] = True
        out.append(new + first)
    return np.concatenate(out) if out else np.zeros(0, np.int64)


def _late(c: Compiled, s: Scratch, out: Streamed, table: ProbTable, waiting: Frontiers,
          sinks: _Index | _Hashed, buckets: list[int], count: int, max_states: int | None) -> None:
    """The late states (their successors are late or sinks), as one block in a file."""
    if not waiting.late:
        return
    absorbing = sinks.sorted_keys()
    block, known, _ = explore_graph.explore_bucket(c, table, np.concatenate(waiting.late), None,
                                                   Frontiers(), absorbing, counted=count,
                                                   max_states=max_states)
    _check_late(c, s, known, buckets)
    out.late = len(block.keys)
    numbers = -1 - (out.sinks + np.arange(len(block.keys), dtype=np.int64))
    order = np.argsort(block.keys)
    target, missing = _resolve((block.keys[order], numbers[order]), sinks, block.target)
    if missing.any():
        raise GiveUp("a successor that was not explored")
    out.late_keys = block.keys
    out.choices += len(block.nbranch)
    out.transitions += len(block.target)
    _save_block(s, "late", block, target)


def _check_late(c: Compiled, s: Scratch, late: I64, buckets: list[int]) -> None:
    """GiveUp if a late state is also a regular one (reached both before and after its
    clock went back): each bucket's sorted keys read back from their file."""
    tb = c.layout.bucket_of(late)
    for b in np.unique(tb).tolist():
        i = int(np.searchsorted(buckets, b))
        if i < len(buckets) and buckets[i] == b and \
                found_in(np.sort(s.load(f"keys{i}")["keys"]), late[tb == b]).any():
            raise GiveUp("a state reached both before and after its clock went back")
