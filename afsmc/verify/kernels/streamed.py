"""Compiled kernels of the streamed route (afsmc.verify.stream): resolving a bucket's
successor keys into state numbers by hash lookups (its dies marked in the same lookup),
and a file's backward pass without a sparse matrix.

Each has a numpy reference in afsmc.verify.stream.resolve or .sweep, and gives the same
numbers and, for the pass, the same values to the bit: a choice's value is, as the
numpy code's CSR products add them, 0 plus the sum (in the branches' order, from 0) of
its branches into regular states, plus the sum of those into the other states, plus its
reward; the state's value then as :func:`afsmc.verify.kernels.passes._states` settles it.
"""

from __future__ import annotations

from typing import Any

import numpy as np
import numpy.typing as npt

from afsmc.verify.kernels import jit
from afsmc.verify.kernels.hashing import KeySet, _home
from afsmc.verify.kernels.passes import CHUNK, _reduceat, _states

I64 = npt.NDArray[np.int64]
F64 = npt.NDArray[np.float64]
Bools = npt.NDArray[np.bool_]
Ints = npt.NDArray[np.integer[Any]]


@jit
def _probe(slots: Ints, dense: I64, k: int) -> int:
    """The entry of key k in the one-region table, -1 if absent."""
    m = len(slots) - 1
    s = _home(k, m)
    while True:
        e = slots[s]
        if e < 0 or dense[e] == k:
            return int(e)
        s = (s + 1) & m


@jit
def _lookup(slots: Ints, dense: I64, keys: I64, at: I64, base: int, out: I64) -> None:
    """For each key keys[i], i in `at`: if the one-region table (`slots` over `dense`)
    holds it at entry e, out[i] = base + e."""
    for i in at:
        e = _probe(slots, dense, keys[i])
        if e >= 0:
            out[i] = base + e


@jit
def _group(j: I64, n: int, order: I64, first: I64) -> None:
    """The positions i with 0 <= j[i] < n grouped by j[i] (a counting sort, stable):
    group g's are order[first[g]:first[g + 1]]."""
    for i in range(len(j)):
        if 0 <= j[i] < n:
            first[j[i] + 1] += 1
    for g in range(n):
        first[g + 1] += first[g]
    at = first[:-1].copy()
    for i in range(len(j)):
        g = j[i]
        if 0 <= g < n:
            order[at[g]] = i
            at[g] += 1


def groups(j: I64, n: int) -> tuple[I64, I64]:
    """:func:`_group`'s order and group offsets (positions outside 0 <= j < n left out)."""
    order = np.empty(len(j), np.int64)
    first = np.zeros(n + 1, np.int64)
    _group(np.ascontiguousarray(j), n, order, first)
    return order, first


class Numbered:
    """Distinct keys numbered from `first` in the order given (a bucket's states, or
    the sinks as they come): a hash set whose entry is the number less `first`."""

    def __init__(self, keys: I64, first: int) -> None:
        self.set = KeySet(len(keys))
        self.set.add(keys)
        self.first = first

    def add(self, keys: I64) -> None:
        """More keys, numbered on from the last (they must be new)."""
        added = self.set.add(keys)
        assert len(added) == len(keys), "a key numbered twice"

    def find(self, keys: I64, at: I64, out: I64) -> None:
        """The number of each key keys[i], i in `at`, that is here into out[i]."""
        _lookup(self.set.slots, self.set.dense, keys, at, self.first, out)

    def keys(self) -> I64:
        return self.set.keys()


@jit
def _resolve_bucket(slots: Ints, dense: I64, base: int, sslots: Ints, sdense: I64, sbase: int,
                    keys: I64, at: I64, out: I64, mark: Bools, new: I64) -> int:
    """For each key keys[i], i in `at` (of one bucket): a regular state of the bucket
    (entry e of `slots` over `dense`) gets out[i] = base + e, and if `mark` is not empty
    and mark[e] not set yet, it is set and base + e written to `new`; else a sink of the
    bucket (entry e of the second table) gets out[i] = -1 - (sbase + e); else out[i] is
    left. How many were written to `new`."""
    n = 0
    marking = len(mark) > 0
    for i in at:
        k = keys[i]
        e = _probe(slots, dense, k)
        if e >= 0:
            out[i] = base + e
            if marking and not mark[e]:
                mark[e] = True
                new[n] = base + e
                n += 1
            continue
        e = _probe(sslots, sdense, k)
        if e >= 0:
            out[i] = -1 - (sbase + e)
    return n


class Bucket:
    """A bucket of the streamed route's window, compiled: its regular states numbered
    from `first` and its sinks (afsmc.verify.explorer.explore_graph.split_sinks) from
    `sink_first`, each in a hash set."""

    def __init__(self, keys: I64, first: int, sink_keys: I64, sink_first: int) -> None:
        self.regular = Numbered(keys, first)
        self.sinks = Numbered(sink_keys, sink_first)

    def resolve(self, keys: I64, at: I64, out: I64, mark: Bools) -> I64:
        """Each key keys[i], i in `at`, that is one of the bucket's states numbered in
        `out` (a sink o as -1 - o); the regular ones not marked in `mark` yet (if not
        empty), sorted, now marked."""
        new = np.empty(min(len(at), len(mark)), np.int64)
        n = _resolve_bucket(self.regular.set.slots, self.regular.set.dense, self.regular.first,
                            self.sinks.set.slots, self.sinks.set.dense, self.sinks.first,
                            keys, at, out, mark, new)
        return np.sort(new[:n])


@jit
def prepare(states: I64, choices: I64, stored: Ints, late: int, first: int, slot: Ints,
            own_other: int, prob: F64, reg: I64, oth: I64, stay: F64) -> bool:
    """A file's successors as the pass reads them (afsmc.verify.stream.sweep.load's
    numpy reference): `stored` (afsmc.verify.stream.layers.narrow's form: a regular
    one as its offset from `first`, another as -1 - its other number, a late one as
    `late`) into reg[b] (the row slot[g mod len(slot)] of regular state g, else -1) and
    oth[b] (its other number, else -1; a late branch gets both -1, for its caller to
    number); and each choice's self-loop probability into stay[c] (its branches to its
    own state, summed as numpy's add.reduceat sums them): its own states are regular
    from `first` (own_other < 0) or other from own_other. Whether any choice loops."""
    size = len(slot)
    most = 1
    for c in range(len(choices) - 1):
        most = max(most, choices[c + 1] - choices[c])
    buf = np.empty(most)
    loops = False
    for s in range(len(states) - 1):
        for c in range(states[s], states[s + 1]):
            here = 0
            for b in range(choices[c], choices[c + 1]):
                v = stored[b]
                reg[b] = -1
                oth[b] = -1
                if v == late:
                    continue
                own = -1
                if v >= 0:
                    if size:
                        reg[b] = slot[(v + first) % size]
                    if own_other < 0:
                        own = v
                else:
                    oth[b] = -1 - v
                    if own_other >= 0:
                        own = oth[b] - own_other
                if own == s:
                    buf[here] = prob[b]
                    here += 1
            stay[c] = _reduceat(buf, 0, here) if here else 0.0
            loops = loops or here > 0
    return loops


@jit
def solve(layers: I64, states: I64, choices: I64, reg: I64, oth: I64, prob: F64, live: F64,
          other: F64, reward: F64, rcol: I64, stay: F64, on: Bools, ocol: I64, cut: I64,
          stuck: F64, reached: F64, mean: Bools, sign: F64, rows: I64, out: F64,
          best: Ints, clear: bool) -> None:
    """One file's states solved layer by layer (from the first; the states of a layer
    depend only on earlier layers' and on other files'): state s's values (one per
    query) into out[rows[s]]. The queries are in groups side by side, group g's in
    columns cut[g] to cut[g + 1] with its `stuck`, `reached` and `mean` (a branch's
    successor's values in one row for all of them: one visit of the row per branch). A
    branch b goes to row reg[b] of `live` or, where that is -1, to row oth[b] of `other`;
    `reward` (choices x reward models) gives query q its column rcol[q] (-1: none), `on`
    (states x targets) its column ocol[q]; `stay` is the choices' self-loops (empty: none
    loops). CHUNK states of a layer at a time: their choices' values, then settled.
    `best` (states x queries, or no rows): each state's first optimal choice, within the
    state, written there (not for a mean).
    `clear`: the states' rows start at 0 (a branch to its own state reads its row)."""
    k = len(sign)
    if clear:
        for s in range(layers[0], layers[-1]):
            for q in range(k):
                out[rows[s], q] = 0.0
    most = 1
    for j in range(len(layers) - 1):
        for s0 in range(layers[j], layers[j + 1], CHUNK):
            most = max(most, states[min(s0 + CHUNK, layers[j + 1])] - states[s0])
    pc = np.empty((most, k))
    here = np.empty((CHUNK, k))
    r = np.empty(k)
    o = np.empty(k)
    cols = np.arange(k)
    none = np.zeros((0, k), np.int32)
    loops = len(stay) > 0
    for j in range(len(layers) - 1):
        lo, hi = layers[j], layers[j + 1]
        for s0 in range(lo, hi, CHUNK):
            s1 = min(s0 + CHUNK, hi)
            row0 = states[s0]
            for c in range(row0, states[s1]):
                for q in range(k):
                    r[q] = 0.0
                    o[q] = 0.0
                for b in range(choices[c], choices[c + 1]):
                    p = prob[b]
                    t = reg[b]
                    if t >= 0:
                        for q in range(k):
                            r[q] += p * live[t, q]
                    else:
                        t = oth[b]
                        for q in range(k):
                            o[q] += p * other[t, q]
                for q in range(k):
                    pc[c - row0, q] = (0.0 + r[q]) + o[q]
                for q in range(k):
                    if rcol[q] >= 0:
                        pc[c - row0, q] += reward[c, rcol[q]]
            for g in range(len(cut) - 1):
                a, b = cut[g], cut[g + 1]
                kept = best[s0:s1, a:b] if len(best) else none[:, a:b]
                _states(pc[:, a:b], states[s0:s1 + 1], 0, s1 - s0, row0,
                        stay[row0:states[s1]] if loops else stay, on, -s0, ocol[a:b],
                        stuck[g], reached[g], mean[g], sign[a:b], here[:, a:b],
                        kept, none[:, a:b], cols[a:b])
            for s in range(s1 - s0):
                for q in range(k):
                    out[rows[s0 + s], q] = here[s, q]


@jit
def clear(out: F64, rows: I64) -> None:
    """The rows `rows` of `out` set to 0."""
    for s in range(len(rows)):
        for q in range(out.shape[1]):
            out[rows[s], q] = 0.0


@jit
def pairs(states: I64, choices: I64, reg: I64, oth: I64, seen_reg: I64, seen_oth: I64,
          stamp: int) -> int:
    """The distinct (state, successor) pairs of the file's states (the uniform DTMC's
    transitions): seen_reg[t] / seen_oth[t] hold the last state stamp (`stamp` + s, unique
    across calls) that had t as a successor, so each pair counts once."""
    total = 0
    for s in range(len(states) - 1):
        mine = stamp + s
        for b in range(choices[states[s]], choices[states[s + 1]]):
            t = reg[b]
            if t >= 0:
                if seen_reg[t] != mine:
                    seen_reg[t] = mine
                    total += 1
            else:
                t = oth[b]
                if seen_oth[t] != mine:
                    seen_oth[t] = mine
                    total += 1
    return total


@jit
def differ(states: I64, choices: I64, reg: I64, oth: I64, prob: F64, live: F64, other: F64,
           reward: F64, lo: int, hi: int, same: float, out: Bools) -> None:
    """Whether the choices of a file's states lo..hi differ in value, into out[s - lo]
    (afsmc.verify.stream.extract.Kept._matters, its numpy reference): each choice's
    branches' probabilities times their successors' values (row reg[b] of `live`, else
    row oth[b] of `other`; an infinite one as 1e300), summed as numpy's add.reduceat
    sums them, plus its reward (`reward` per choice, empty: none); the state's largest
    and smallest of those more than `same` apart, relative to 1 or their size."""
    most = 1
    for c in range(states[lo], states[hi]):
        most = max(most, choices[c + 1] - choices[c])
    buf = np.empty(most)
    rewarded = len(reward) > 0
    for s in range(lo, hi):
        c0, c1 = states[s], states[s + 1]
        out[s - lo] = False
        low = high = 0.0
        for c in range(c0, c1):
            b0, b1 = choices[c], choices[c + 1]
            for b in range(b0, b1):
                t = reg[b]
                v = live[t] if t >= 0 else other[oth[b]]
                buf[b - b0] = prob[b] * (v if np.isfinite(v) else 1e300)
            x = _reduceat(buf, 0, b1 - b0) if b1 > b0 else 0.0
            if rewarded:
                x += reward[c]
            if c == c0 or x < low:
                low = x
            if c == c0 or x > high:
                high = x
        if c1 > c0:
            out[s - lo] = abs(high - low) > same * max(1.0, max(abs(high), abs(low)))


@jit
def follow(states: I64, choices: I64, succ: I64, best: I64, layers: I64, own: I64,
           reached: Bools) -> None:
    """A strategy followed through one file (afsmc.verify.stream.extract.forward, its
    numpy reference): from its last layer to its first, each reached state's chosen
    choice (states[s] + best[s]) marks its successors (global numbers) reached."""
    for j in range(len(layers) - 2, -1, -1):
        for s in range(layers[j], layers[j + 1]):
            if reached[own[s]]:
                c = states[s] + best[s]
                for b in range(choices[c], choices[c + 1]):
                    reached[succ[b]] = True


@jit
def relax(states: I64, choices: I64, succ: I64, prob: F64, best: I64, layers: I64,
          own: I64, dist: F64, alive: Bools, on: Bools) -> None:
    """A witness's dist through one file (extract._relax, its numpy reference): from its
    last layer to its first, each state that reaches the target, is no target and is
    reached (dist > 0) raises its chosen choice's successors' dist to its own times the
    branch's probability; a self-loop never does."""
    for j in range(len(layers) - 2, -1, -1):
        for s in range(layers[j], layers[j + 1]):
            g = own[s]
            d = dist[g]
            if d > 0.0 and alive[s] and not on[s]:
                c = states[s] + best[s]
                for b in range(choices[c], choices[c + 1]):
                    t = succ[b]
                    if t != g:
                        x = d * prob[b]
                        if x > dist[t]:
                            dist[t] = x
