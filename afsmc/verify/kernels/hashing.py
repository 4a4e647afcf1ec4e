"""Open-addressing hash tables of int64 state keys (numba): the compiled bookkeeping of
afsmc.verify.explorer.explore_graph, whose numpy counterparts sort and binary-search.

A table is a slot array of entry numbers (-1: empty) over a dense array of keys (entry e
holds key `dense[e]`), probed linearly from a multiplicative hash of the key. It may be
cut into **regions**, one per value of `key >> shift` (a bucket of the mission clock),
each a power of two of slots: a lookup then probes only its bucket's region, which stays
in cache while a block's successors are resolved, instead of the whole table.

Keys are non-negative (afsmc.verify.explorer.explore packs them into 62 bits); -1 marks an
empty slot and, in a lookup's answer, a key that is absent.

Built on them: `KeySet` (insertion-ordered, growing: a bucket's waiting keys), `Found` (a
bucket's found keys and their positions in the order expanded), `Regions` (every state's
number, static); besides, `grouped` (keys by bucket, a counting sort) and `encode` (a
branch probability's code among the few known values).
"""

from __future__ import annotations

from typing import Any

import numpy as np
import numpy.typing as npt

from afsmc.verify.kernels import ANY_KEY, jit

I64 = npt.NDArray[np.int64]
F64 = npt.NDArray[np.float64]
Bools = npt.NDArray[np.bool_]
Slots = npt.NDArray[Any]  # int32 or int64 entry numbers

# 2**64 / golden ratio: Knuth's multiplicative hash spreads keys that differ in a few
# (bit-packed) fields over the whole table
_GOLDEN = np.uint64(0x9E3779B97F4A7C15)
_HIGH = np.uint64(29)  # the product's bits from here on pick the slot (good to 2**35 slots)
LOAD = 0.5  # a table holds at most this many keys per slot (linear probing stays short)


@jit
def _home(key: int, mask: int) -> int:
    return int((np.uint64(key) * _GOLDEN) >> _HIGH) & mask


@jit
def _find(slots: Slots, dense: I64, start: I64, mask: I64, shift: int, keys: I64,
          out: I64, lo: int, hi: int, values: I64) -> None:
    """out[i] = the entry holding keys[i] (its value, if `values` is not empty), or -1
    (at once if outside [lo, hi))."""
    mapped = len(values) > 0
    for i in range(len(keys)):
        k = keys[i]
        r = k >> shift
        out[i] = -1
        if k < lo or k >= hi or r < 0 or r >= len(start):
            continue
        base, m = start[r], mask[r]
        s = _home(k, m)
        while True:
            e = slots[base + s]
            if e < 0:
                break
            if dense[e] == k:
                out[i] = values[e] if mapped else e
                break
            s = (s + 1) & m


@jit
def _insert_new(slots: Slots, dense: I64, n: int, keys: I64, new: I64) -> int:
    """Insert the keys absent from the one-region table holding `n` entries, each as the
    next entry, writing them (first-seen order) to `new`; the number of entries after."""
    m = len(slots) - 1
    count = 0
    for i in range(len(keys)):
        k = keys[i]
        s = _home(k, m)
        while True:
            e = slots[s]
            if e < 0:
                slots[s] = n
                dense[n] = k
                new[count] = k
                n += 1
                count += 1
                break
            if dense[e] == k:
                break
            s = (s + 1) & m
    return n


@jit
def _place(slots: Slots, dense: I64, start: I64, mask: I64, shift: int, first: int) -> None:
    """Enter dense[first:] (distinct keys, none entered yet) into their regions' slots."""
    for e in range(first, len(dense)):
        k = dense[e]
        r = k >> shift
        base, m = start[r], mask[r]
        s = _home(k, m)
        while slots[base + s] >= 0:
            s = (s + 1) & m
        slots[base + s] = e


def _capacity(count: int) -> int:
    """The power of two of slots that holds `count` keys at most at LOAD."""
    return 1 << max(int(np.ceil(count / LOAD)), 1).bit_length()


class KeySet:
    """The distinct keys added so far, numbered in the order first seen (one region,
    grown by doubling; int32 entries, half the slots' bytes: a set holds the keys of one
    bucket)."""

    def __init__(self, expect: int = 0) -> None:
        self.slots = np.full(_capacity(expect), -1, np.int32)
        self.dense = np.empty(max(expect, 16), np.int64)
        self.size = 0

    def keys(self) -> I64:
        """Every key, in the order first added (a view)."""
        out: I64 = self.dense[:self.size]
        return out

    def add(self, keys: I64) -> I64:
        """Add `keys`: those that were absent, each once, in the order first met (entries
        size, size + 1, ... before the call)."""
        keys = np.ascontiguousarray(keys)
        new = np.empty(len(keys), np.int64)
        done, before = 0, self.size
        while done < len(keys):
            # at most as many keys as the table has room for: each may be new
            room = int(LOAD * len(self.slots)) - self.size
            if room <= 0 or room < min(len(keys) - done, len(self.slots) // 4):
                self._grow()
                continue
            part = keys[done:done + room]
            if self.size + len(part) > len(self.dense):
                dense = np.empty(max(self.size + len(part), 2 * len(self.dense)), np.int64)
                dense[:self.size] = self.dense[:self.size]
                self.dense = dense
            self.size = _insert_new(self.slots, self.dense, self.size, part,
                                    new[self.size - before:])
            done += len(part)
        out: I64 = new[:self.size - before]
        return out

    def _grow(self) -> None:
        self.slots = np.full(2 * len(self.slots), -1, np.int32)
        _place(self.slots, self.dense[:self.size], _ZERO, np.array([len(self.slots) - 1]),
               63, 0)

    def find(self, keys: I64, lo: int = 0, hi: int = ANY_KEY, values: I64 | None = None
             ) -> I64:
        """The entry of each key (its rank among the keys added), or `values[entry]`; -1
        where absent. Every key added lies in [lo, hi): the others are not looked for."""
        out = np.empty(len(keys), np.int64)
        _find(self.slots, self.dense, _ZERO, np.array([len(self.slots) - 1]), 63,
              np.ascontiguousarray(keys), out, lo, hi, _NONE if values is None else values)
        return out


_ZERO = np.zeros(1, np.int64)
_NONE = np.zeros(0, np.int64)


@jit
def _group(buckets: I64, keys: I64, lo: int, out: I64, first: I64) -> None:
    """`keys` grouped by bucket (a counting sort, stable): bucket lo + j's are
    out[first[j]:first[j + 1]]."""
    for i in range(len(buckets)):
        first[buckets[i] - lo + 1] += 1
    for j in range(1, len(first)):
        first[j] += first[j - 1]
    at = first[:-1].copy()
    for i in range(len(buckets)):
        j = buckets[i] - lo
        out[at[j]] = keys[i]
        at[j] += 1


def grouped(buckets: I64, keys: I64) -> list[tuple[int, I64]]:
    """(bucket, its keys in their order) for each bucket present in `buckets`."""
    if not len(buckets):
        return []
    lo = int(buckets.min())
    out = np.empty(len(keys), np.int64)
    first = np.zeros(int(buckets.max()) - lo + 2, np.int64)
    _group(np.ascontiguousarray(buckets), np.ascontiguousarray(keys), lo, out, first)
    return [(lo + j, out[first[j]:first[j + 1]]) for j in np.flatnonzero(np.diff(first)).tolist()]


class Regions:
    """Distinct keys -> their positions in `keys`, a region per value of `key >> shift`
    (static: built once)."""

    def __init__(self, keys: I64, shift: int) -> None:
        keys = np.ascontiguousarray(keys)
        per = np.bincount(keys >> shift) if len(keys) else np.zeros(1, np.int64)
        size = np.array([_capacity(int(k)) for k in per.tolist()], np.int64)
        self.start = np.zeros(len(size), np.int64)
        np.cumsum(size[:-1], out=self.start[1:])
        self.mask = size - 1
        self.shift = shift
        self.dense = keys
        dtype = np.int32 if len(keys) < np.iinfo(np.int32).max else np.int64
        self.slots = np.full(int(size.sum()), -1, dtype)
        _place(self.slots, keys, self.start, self.mask, shift, 0)

    def find(self, keys: I64) -> I64:
        """The position of each key in the keys indexed, -1 where absent."""
        out = np.empty(len(keys), np.int64)
        _find(self.slots, self.dense, self.start, self.mask, self.shift,
              np.ascontiguousarray(keys), out, 0, ANY_KEY, _NONE)
        return out


@jit
def _encode(known: F64, code: npt.NDArray[np.uint32], prob: F64,
            out: npt.NDArray[np.uint32]) -> bool:
    """out[i] = the code of prob[i] among the sorted `known` values (a binary search in a
    table that stays in L1); False as soon as one is not there."""
    n = len(known)
    for i in range(len(prob)):
        p = prob[i]
        lo, hi = 0, n
        while lo < hi:
            mid = (lo + hi) >> 1
            if known[mid] < p:
                lo = mid + 1
            else:
                hi = mid
        if lo == n or known[lo] != p:
            return False
        out[i] = code[lo]
    return True


def encode(known: F64, code: npt.NDArray[np.uint32], prob: F64
           ) -> npt.NDArray[np.uint32] | None:
    """The codes of `prob` (afsmc.verify.explorer.keysets.ProbTable's), or None if
    some value is not known yet."""
    out = np.empty(len(prob), np.uint32)
    if not _encode(known, code, np.ascontiguousarray(prob), out):
        return None
    return out


class Found:
    """The keys a bucket has found, for afsmc.verify.explorer.explore_graph.explore_bucket's
    compiled path (its numpy reference: keysets.Sorted): a KeySet of them and of
    the keys to skip; each round's new keys sorted alone, as _Sorted gives them. `span`:
    the bucket's keys lie in [lo, hi) (a successor outside is in another bucket)."""

    def __init__(self, start: I64, skip: I64 | None, span: tuple[int, int] = (0, ANY_KEY)
                 ) -> None:
        self.span = span
        self.set = KeySet(len(start) + (0 if skip is None else len(skip)))
        # per entry of the set: its position in the order expanded (-1: skipped)
        self.position: list[I64] = []
        if skip is not None and len(skip):
            self.position.append(np.full(len(self.set.add(skip)), -1, np.int64))
        self.size = 0
        self.runs: list[I64] = []
        self.first = self.add(start)

    def add(self, targets: I64) -> I64:
        """The keys of `targets` not found (nor skipped) before, sorted; now found."""
        new = self.set.add(targets)
        order = np.argsort(new)
        frontier: I64 = new[order]
        at = np.empty(len(new), np.int64)
        at[order] = np.arange(self.size, self.size + len(new))
        self.position.append(at)
        self.size += len(new)
        self.runs.append(frontier)
        return frontier

    def sorted(self) -> I64:
        """Every key found, sorted."""
        if len(self.runs) > 1:  # sorted runs: timsort merges them
            self.runs = [np.sort(np.concatenate(self.runs), kind="stable")]
        return self.runs[0] if self.runs else np.zeros(0, np.int64)

    def inside(self, expanded: I64, target: I64) -> tuple[Bools, I64]:
        """Which of `target` were found, and the position of each of those in the order
        expanded (`expanded`, which _Sorted.inside needs), by one lookup of each."""
        if not self.position:
            return np.zeros(len(target), bool), np.zeros(0, np.int64)
        at = self.set.find(target, *self.span, np.concatenate(self.position))
        inside = at >= 0
        out: I64 = at[inside]
        return inside, out
