"""The keys of afsmc's own exploration (afsmc.verify.explorer.explore_graph): the keys a
bucket has found, those waiting in later buckets, and the codes of the branches'
distinct probabilities, each with its numpy reference and, on large models, its compiled
kernel (afsmc.verify.kernels.hashing)."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

import numpy as np
import numpy.typing as npt

from afsmc.verify.arrays.acyclic import F64, I64, Bools

if TYPE_CHECKING:
    from afsmc.verify.kernels.hashing import KeySet

Codes = npt.NDArray[np.uint32]


class ProbTable:
    """The distinct probabilities of the explored branches: each branch keeps its
    probability's code (4 bytes instead of 8; 2 once assembled, if few)."""

    def __init__(self) -> None:
        self.index: dict[float, int] = {}
        self.known = np.zeros(0)  # the values met so far, sorted ...
        self.code = np.zeros(0, np.uint32)  # ... and their codes

    def encode(self, prob: F64, fast: bool = False) -> Codes:
        """The codes of `prob`: looked up among the known values (a model's are few),
        the new ones added first; `fast`: by the compiled kernel while every value is
        known already."""
        if fast and len(self.known):
            from afsmc.verify.kernels import hashing

            codes = hashing.encode(self.known, self.code, prob)
            if codes is not None:
                return codes
        pos = np.searchsorted(self.known, prob)
        hit = self.known[np.minimum(pos, len(self.known) - 1)] == prob \
            if len(self.known) else np.zeros(len(prob), bool)
        if not hit.all():
            for v in np.unique(prob[~hit]).tolist():
                self.index.setdefault(float(v), len(self.index))
            self.known = np.array(sorted(self.index))
            self.code = np.array([self.index[v] for v in self.known.tolist()], np.uint32)
            pos = np.searchsorted(self.known, prob)
        out: Codes = self.code[pos]
        return out

    def table(self) -> F64:
        out = np.empty(len(self.index))
        for v, k in self.index.items():
            out[k] = v
        return out

    def dtype(self) -> Any:
        return np.uint16 if len(self.index) <= 1 << 16 else np.uint32


def unique(a: I64) -> I64:
    """The sorted distinct values (numpy 2's np.unique hashes int64 keys ~30 times slower
    than it sorts them)."""
    s = np.sort(a)
    if s.size < 2:
        return s
    out: I64 = s[np.concatenate(([True], s[1:] != s[:-1]))]
    return out


def found_in(sorted_keys: I64, keys: I64) -> Bools:
    pos = np.searchsorted(sorted_keys, keys)
    pos[pos == len(sorted_keys)] = 0
    out: Bools = sorted_keys[pos] == keys if len(sorted_keys) else np.zeros(len(keys), bool)
    return out


class Keys:
    """The keys a bucket has found so far, as a few sorted runs whose sizes at least halve
    from one to the next (merged like the digits of a binary counter): adding a round's
    keys costs about their number times the log of the total, not a sort of everything
    found so far, which made a long chain (a round or two of new states per step)
    quadratic."""

    def __init__(self, first: I64) -> None:
        self.runs: list[I64] = [first]
        self.size = len(first)

    def add(self, keys: I64) -> None:
        """Add sorted keys, none of them present already."""
        self.runs.append(keys)
        self.size += len(keys)
        while len(self.runs) > 1 and len(self.runs[-2]) <= 2 * len(self.runs[-1]):
            last = self.runs.pop()
            # two sorted runs: the stable sort (timsort) merges them in linear time
            self.runs[-1] = np.sort(np.concatenate([self.runs[-1], last]), kind="stable")

    def found(self, keys: I64) -> Bools:
        out = np.zeros(len(keys), bool)
        for run in self.runs:
            if len(run):
                out |= found_in(run, keys)
        return out

    def sorted(self) -> I64:
        """Every key, sorted."""
        while len(self.runs) > 1:
            last = self.runs.pop()
            self.runs[-1] = np.sort(np.concatenate([self.runs[-1], last]), kind="stable")
        return self.runs[0]


@dataclass
class Frontiers:
    """What waits to be explored: keys by bucket (the union of each bucket's arrays), and
    the late ones. The compiled path keeps a bucket's keys in a hash set instead (`sets`),
    its list in `pending` then holding them once, as one array."""

    pending: dict[int, list[I64]] = field(default_factory=dict)
    late: list[I64] = field(default_factory=list)
    sets: dict[int, KeySet] = field(default_factory=dict)

    def add(self, buckets: I64, keys: I64, fast: bool = False) -> None:
        """Add `keys`, each of bucket `buckets[i]`; `fast`: into hash sets (a bucket's
        keys once, not sorted round after round)."""
        if fast or self.sets:
            self._add_hashed(buckets, keys)
            return
        order = np.argsort(buckets, kind="stable")
        buckets, keys = buckets[order], keys[order]
        cuts = np.flatnonzero(np.diff(buckets)) + 1
        for part, b in zip(np.split(keys, cuts), buckets[np.r_[0, cuts]].tolist(), strict=True):
            self.pending.setdefault(int(b), []).append(unique(part))

    def _add_hashed(self, buckets: I64, keys: I64) -> None:
        from afsmc.verify.kernels.hashing import KeySet, grouped

        for gone in [b for b in self.sets if b not in self.pending]:
            del self.sets[gone]  # taken by a caller that pops `pending` itself
        for b, part in grouped(buckets, keys):
            hashed = self.sets.get(b)
            if hashed is None:
                hashed = self.sets[b] = KeySet(len(part))
                for earlier in self.pending.get(b, []):  # added by the numpy path
                    hashed.add(earlier)
            hashed.add(part)
            self.pending[b] = [hashed.keys()]

    def take(self, b: int) -> I64:
        """The sorted distinct keys waiting in bucket `b`, no longer waiting."""
        parts = self.pending.pop(b)
        if self.sets.pop(b, None) is not None:
            return np.sort(parts[0])  # distinct already
        return unique(np.concatenate(parts))


class Sorted:
    """The keys a bucket has found (the numpy reference): sorted runs (Keys), each
    round's candidates sorted and searched there and among the keys to skip."""

    def __init__(self, start: I64, skip: I64 | None) -> None:
        self.skip = np.zeros(0, np.int64) if skip is None else skip
        first = unique(start)
        self.first: I64 = first[~found_in(self.skip, first)]
        self.keys = Keys(self.first)

    @property
    def size(self) -> int:
        return self.keys.size

    def add(self, targets: I64) -> I64:
        """The keys of `targets` not found (nor skipped) before, sorted; now found."""
        cand = unique(targets)
        frontier = cand[~self.keys.found(cand) & ~found_in(self.skip, cand)]
        self.keys.add(frontier)  # disjoint from what it has
        return frontier

    def sorted(self) -> I64:
        return self.keys.sorted()

    def inside(self, expanded: I64, target: I64) -> tuple[Bools, I64]:
        """Which of `target` were found, and the position of each of those in `expanded`
        (the found keys in the order they were expanded)."""
        known = self.sorted()
        sorter = np.argsort(expanded)
        inside = found_in(known, target)
        return inside, sorter[np.searchsorted(known, target[inside])]
