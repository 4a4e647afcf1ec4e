"""Numbering a streamed bucket's successors (afsmc.verify.stream.layers): each successor
key looked up among the regular states of the buckets from it to its reach (the
window) and among the sinks, and the bucket's "dies" (the regular states it is the
lowest predecessor bucket of).

Two forms, the same numbers: the numpy reference keeps each bucket's keys sorted beside
their numbers and every sink in sorted runs (binary searches); on large models a bucket's
states and its own sinks are numbered in hash sets (afsmc.verify.kernels.streamed.Bucket),
a key looked up in its own bucket's only and the dies marked in the same lookup, and the
sinks of every bucket are hashed only when a key into an earlier bucket (a clock set
back) or a late state asks for them.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Union

import numpy as np

from afsmc.verify.arrays import acyclic
from afsmc.verify.arrays.acyclic import I64
from afsmc.verify.explorer.explore import Compiled
from afsmc.verify.explorer.keysets import found_in, unique

if TYPE_CHECKING:
    from afsmc.verify.kernels.streamed import Bucket, Numbered

# bucket -> its first number, and which of its states some resolved bucket points at
Seen = dict[int, tuple[int, acyclic.Bools]]


class Index:
    """Sorted keys with a number each, as a few sorted runs merged like a binary
    counter (see keysets.Keys): the sinks' numbers, the numpy reference."""

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


class HashedSinks:
    """The sinks' keys numbered in a hash set (afsmc.verify.kernels.streamed): Index's
    compiled counterpart, taken on large models. Filled only when asked: each bucket's
    own sinks are looked up in its window entry (afsmc.verify.kernels.streamed.Bucket),
    so this is only asked for a key into an earlier bucket (a clock set back) and for
    the late states."""

    def __init__(self, keys: I64) -> None:
        self.waiting: list[I64] = [keys]  # added, not in the set yet
        self.count = len(keys)
        self.set: Numbered | None = None

    @classmethod
    def of(cls, index: Index) -> HashedSinks:
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
Sinks = Union["Index", "HashedSinks"]


def hashed(window: dict[int, Entry], sinks: Index, buckets: list[int], sink_start: list[int],
           total: int) -> None:
    """The window's buckets moved to hash sets (the exploration has grown past the
    kernels' threshold), each with its own sinks (bucket i's numbered from
    sink_start[i]; `total` sinks in all)."""
    from afsmc.verify.kernels.streamed import Bucket

    every = sinks.by_number()
    for b, e in window.items():
        if isinstance(e, tuple):
            keys, numbers = e
            order = np.argsort(numbers)
            i = buckets.index(b)
            lo = sink_start[i]
            hi = sink_start[i + 1] if i + 1 < len(sink_start) else total
            window[b] = Bucket(keys[order], int(numbers[order[0]]) if len(numbers) else 0,
                               every[lo:hi], lo)


def resolve_span(span: list[tuple[int, Entry]], sinks: Sinks, keys: I64,
                 c: Compiled) -> tuple[I64, acyclic.Bools]:
    """resolve_sorted against the keys of several consecutive buckets (their window
    entries), or resolve_hashed where they are hash sets."""
    if span and not isinstance(span[0][1], tuple):
        target, late, _ = resolve_hashed(span, sinks, keys, c, None)
        return target, late
    # a bucket's keys are those whose high bits are the bucket: the window's runs, end to
    # end in bucket order, are sorted
    pairs = [e for _, e in span if isinstance(e, tuple)]
    joined = (np.concatenate([k for k, _ in pairs]), np.concatenate([n for _, n in pairs]))
    return resolve_sorted(joined, sinks, keys)


def resolve_hashed(span: list[tuple[int, Entry]], sinks: Sinks, keys: I64,
                   c: Compiled, seen: Seen | None
                   ) -> tuple[I64, acyclic.Bools, I64]:
    """resolve_span and dies_sorted by the compiled path: each key looked up in its own
    bucket's states and sinks (a bucket of the span: `span[0]` is the bucket resolved),
    the others among every sink; and with `seen`, the dies (as dies_sorted gives them),
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
        first, mark = seen[t] if seen is not None else (0, np.zeros(0, bool))
        # the bucket resolved: no later bucket points at its states, all of them go now
        own = t == lo
        new = e.resolve(keys, at, out, np.zeros(0, bool) if own else mark)
        if seen is not None:
            if own:
                new = np.flatnonzero(~mark).astype(np.int64) + first
                mark[:] = True
            dies.append(new)
    # the rest: sinks of earlier buckets (a clock set back), or late states
    todo = np.flatnonzero(out == np.iinfo(np.int64).min)
    late = np.zeros(len(keys), bool)
    if todo.size:
        assert isinstance(sinks, HashedSinks)
        got = sinks.lookup(keys[todo])
        hit = got >= 0
        out[todo[hit]] = -1 - got[hit]
        miss = todo[~hit]
        out[miss] = keys[miss]
        late[miss] = True
    return out, late, np.concatenate(dies) if dies else np.zeros(0, np.int64)


def resolve_sorted(window: tuple[I64, I64], sinks: Sinks, keys: I64
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
    return sinks_of(sinks, keys, out, todo)


def sinks_of(sinks: Sinks, keys: I64, out: I64, todo: acyclic.Bools
             ) -> tuple[I64, acyclic.Bools]:
    """The keys still `todo` that are sinks numbered in `out` (-1 - o); and which keys
    are neither regular nor sinks."""
    other = np.zeros(len(keys), np.int64)
    left = todo.copy()
    sinks.find(keys, other, left)  # clears `left` where a sink's
    is_sink = todo & ~left
    out[is_sink] = -1 - other[is_sink]
    return out, left


def dies_sorted(target: I64, bucket: int, reach: int, seen: Seen) -> I64:
    """The regular states (sorted numbers) that the bucket points at and no earlier bucket
    did, and those of its own that nothing points at but the initial state; marked seen
    (the compiled path marks them while resolving: resolve_hashed)."""
    points = unique(target[target >= 0])
    out = []
    for t in sorted(seen):
        if not bucket <= t <= reach:
            continue
        first, mark = seen[t]
        lo, hi = np.searchsorted(points, [first, first + len(mark)])
        at = points[lo:hi] - first
        if t == bucket:  # no later bucket points at its states: all of them go now
            at = np.arange(len(mark), dtype=np.int64)
        new = at[~mark[at]]
        mark[new] = True
        out.append(new + first)
    return np.concatenate(out) if out else np.zeros(0, np.int64)
