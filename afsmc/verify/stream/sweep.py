"""The backward pass over the streamed layers (afsmc.verify.stream.layers): the files read
back in reverse (the sinks, the late states, then the buckets from the last explored to
the first), every query of the run in one sweep, each layer by the same step as the
in-memory pass (:func:`afsmc.verify.arrays.acyclic.settle`).

Values kept: those of the sinks and late states ("other"), and of the regular states that
are live: solved, and pointed at by a bucket not yet solved (each bucket's "dies", recorded
while exploring, are the states it is the lowest predecessor bucket of; they are dropped
once it is solved). Their values live in rows handed out and taken back through a stack
of free rows, as many rows as the most states live at once (live_rows), not a whole
window of buckets. Which row holds regular state g is kept for a window of buckets (from
the bucket being solved to the last one a bucket not yet solved reaches; window_rows), one
integer per state, in a ring: state g at entry g mod its size.
"""

from __future__ import annotations

import contextlib
import itertools
import os
from collections.abc import Callable, Generator
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass
from typing import Any, Protocol

import numpy as np
import numpy.typing as npt

from afsmc.verify import kernels
from afsmc.verify.arrays import acyclic
from afsmc.verify.arrays.acyclic import F64, I64, Query, Sense
from afsmc.verify.explorer import keysets
from afsmc.verify.stream.layers import Streamed, opened, widen
from afsmc.verify.stream.scratch import Arrays

LATE = np.iinfo(np.int64).min  # a branch into a late state, before it is numbered
Rows = npt.NDArray[np.signedinteger[Any]]  # rows of the live values (int32 or int64)


@dataclass
class Part:
    """One file's states as the pass reads them: offsets, each branch's successor as a
    column of the regular window (`reg`, -1 if none) or of the other values (`oth`, -1
    if none), probabilities, self-loops, rewards per choice and labels per state."""

    states: I64
    choices: I64
    reg: I64
    oth: I64
    prob: F64
    stay: acyclic.Vec | None
    layers: I64
    rewards: list[F64]
    labels: list[acyclic.Bools]
    dies: npt.NDArray[np.signedinteger[Any]] | None  # a bucket's, as offsets; else None


def _offsets(counts: npt.NDArray[np.integer[Any]]) -> I64:
    out = np.zeros(len(counts) + 1, np.int64)
    np.cumsum(counts, dtype=np.int64, out=out[1:])
    return out


def late_index(st: Streamed) -> tuple[I64, I64]:
    """The late states' keys sorted, and each one's number among the late states: how a
    branch into a late state, kept by its key, is numbered (late_numbers)."""
    order = np.argsort(st.late_keys)
    return st.late_keys[order], order


def late_numbers(st: Streamed, late_sorted: I64, late_order: I64, keys: I64) -> I64:
    """The other numbers (the sinks first, then the late states) of late states' `keys`."""
    out: I64 = st.sinks + late_order[np.searchsorted(late_sorted, keys)]
    return out


def load(st: Streamed, name: str, first: int, own_other: int | None, late_sorted: I64,
         late_order: I64, rewards: int, labels: int, slot: Rows | None = None) -> Part:
    """The file `name`; its regular successors as the rows `slot[g mod len(slot)]` of
    the live values (its own states from `first`, its own first number), or, for the
    sinks and the late states (`own_other`: their first other number), its own states as
    rows of the other values from there."""
    a = opened(st.scratch.load(name))
    states = _offsets(a["nchoice"])
    choices = _offsets(a["nbranch"])
    target = widen(a["target"], first)
    if "late_at" in a:
        target[a["late_at"]] = -1 - late_numbers(st, late_sorted, late_order, a["late_key"])
    assert not (target == LATE).any()
    prob = st.table[a["prob"]]
    regular = target >= 0
    # the sinks' and late states' successors are all "other"
    reg = np.full(len(target), -1, np.int64) if slot is None else \
        np.where(regular, slot[target % len(slot)], -1)
    oth = np.where(regular, -1, -1 - target)
    own = np.where(regular, target - first, -1) if own_other is None else \
        np.where(regular, -1, oth - own_other)
    stay = acyclic.self_loops(states, choices, own.astype(np.int64), prob)
    return _part(a, states, choices, reg, oth, prob, stay, rewards, labels)


def _part(a: Arrays, states: I64, choices: I64, reg: I64, oth: I64, prob: F64,
          stay: acyclic.Vec | None, rewards: int, labels: int) -> Part:
    """The part of a file's arrays `a`, its successors and self-loops given: its rewards
    per choice, its layers' offsets, its labels and dies as the file has them."""
    per_choice = []
    for i in range(rewards):
        r = np.zeros(len(choices) - 1)
        r[a[f"reward{i}_at"]] = a[f"reward{i}_v"]
        per_choice.append(r)
    layers = np.concatenate([[0], np.cumsum(a["layers"])]).astype(np.int64)
    return Part(states, choices, reg, oth, prob, stay, layers, per_choice,
                [a[f"label{i}"] for i in range(labels)], a.get("dies"))


def load_compiled(st: Streamed, name: str, first: int, own_other: int | None,
                  late_sorted: I64, late_order: I64, rewards: int, labels: int,
                  slot: Rows | None = None, arrays: Arrays | None = None) -> Part:
    """`load` by a compiled kernel (afsmc.verify.kernels.streamed.prepare): the same
    part, its self-loops dense; from `arrays` if the file was read already."""
    from afsmc.verify.kernels import streamed

    a = opened(st.scratch.load(name) if arrays is None else arrays)
    states = _offsets(a["nchoice"])
    choices = _offsets(a["nbranch"])
    prob = st.table[a["prob"]]
    stored = a["target"]
    reg = np.empty(len(stored), np.int64)
    oth = np.empty(len(stored), np.int64)
    stay = np.empty(len(choices) - 1)
    loops = streamed.prepare(states, choices, stored, int(np.iinfo(stored.dtype).min), first,
                             np.zeros(0, np.int64) if slot is None else slot,
                             -1 if own_other is None else own_other, prob, reg, oth, stay)
    if "late_at" in a:
        oth[a["late_at"]] = late_numbers(st, late_sorted, late_order, a["late_key"])
    return _part(a, states, choices, reg, oth, prob, stay if loops else None, rewards, labels)


def _steps(part: Part, lo: int, hi: int, reg: int, other: int) -> list[tuple[bool, Any]]:
    """The span's choices as sparse rows over the regular window (of `reg` rows; True)
    and over the other values (`other` rows; False), those that have branches there."""
    from scipy.sparse import csr_matrix

    c0, c1 = int(part.states[lo]), int(part.states[hi])
    b0, b1 = int(part.choices[c0]), int(part.choices[c1])
    sizes = np.diff(part.choices[c0:c1 + 1])
    out = []
    for regular, cols, width in ((True, part.reg[b0:b1], reg), (False, part.oth[b0:b1], other)):
        m = cols >= 0
        if not m.any():
            continue
        if m.all():
            rows = part.choices[c0:c1 + 1] - b0
        else:
            rows = np.zeros(c1 - c0 + 1, np.int64)
            owner = np.repeat(np.arange(c1 - c0), sizes)
            np.cumsum(np.bincount(owner[m], minlength=c1 - c0), out=rows[1:])
        out.append((regular, csr_matrix((part.prob[b0:b1][m], cols[m], rows),
                                        shape=(c1 - c0, width))))
    return out


def _product(steps: list[tuple[bool, Any]], choices: int, reg: F64 | None, other: F64) -> F64:
    """Each choice of a span: its branches' probabilities times their successors'
    values (regular window and others)."""
    out = np.zeros((choices, other.shape[1]))
    for regular, step in steps:
        out += np.asarray(step @ (reg if regular else other))
    return out


@dataclass
class Group:
    """The queries of one kind solved side by side, and where their reward models and
    targets are among the files' (`reward`: index per query, or None for P)."""

    queries: list[Query]
    sense: Sense
    reward: list[int] | None
    target: list[int]


def put(out: npt.NDArray[Any], at: int, values: npt.NDArray[Any]) -> None:
    """`values` into the rows from `at` of `out`, as a ring (past its end, from row 0)."""
    size = len(out)
    lo = at % size
    hi = lo + len(values)
    if hi <= size:
        out[lo:hi] = values
    else:
        out[lo:] = values[:size - lo]
        out[:hi - size] = values[size - lo:]


@dataclass
class Fast:
    """A sweep by the compiled kernels (afsmc.verify.kernels.streamed): every group's
    values side by side, group g's in columns cut[g] to cut[g + 1] of one matrix of live
    values and one of the others (solve_part's lists are views of these); and the count
    of the uniform DTMC's transitions: per successor row (live, other) the last state
    that had it, and the next state's stamp."""

    live: F64
    other: F64
    cut: I64
    seen_reg: I64
    seen_oth: I64
    # the groups' distinct reward models and targets (indices among the files'), each
    # query pointing at its column (rcol -1: no reward); per group its stuck and reached
    # values and whether it is a mean; per query 1 for a min, -1 for a max
    rewards: list[int]
    rcol: I64
    targets: list[int]
    ocol: I64
    stuck: F64
    reached: F64
    mean: acyclic.Bools
    sign: F64
    stamp: int = 0
    # threads that solve the parts of a large layer side by side (None: one)
    pool: ThreadPoolExecutor | None = None
    workers: int = 1

    @classmethod
    def of(cls, groups: list[Group], rows: int, others: int) -> Fast:
        cut = np.cumsum([0] + [len(g.queries) for g in groups]).astype(np.int64)
        rewards = sorted({r for g in groups for r in g.reward or []})
        targets = sorted({t for g in groups for t in g.target})
        senses = [g.sense for g in groups]
        return cls(np.zeros((rows, int(cut[-1]))), np.zeros((others, int(cut[-1]))), cut,
                   np.full(rows, -1, np.int64), np.full(others, -1, np.int64), rewards,
                   np.array([rewards.index(r) if g.reward is not None else -1 for g in groups
                             for r in (g.reward or [-1] * len(g.queries))], np.int64),
                   targets,
                   np.array([targets.index(t) for g in groups for t in g.target], np.int64),
                   np.array([x.stuck for x in senses]), np.array([x.reached for x in senses]),
                   np.array([x.mean for x in senses]),
                   np.concatenate([np.where(x.low, 1.0, -1.0) for x in senses]))

    def close(self) -> None:
        if self.pool is not None:
            self.pool.shutdown()

    def views(self, values: F64) -> list[F64]:
        """Each group's columns of `values`."""
        return [values[:, a:b] for a, b in itertools.pairwise(self.cut.tolist())]


class Keep(Protocol):
    """What a sweep keeps of each file besides the values (a strategy's choices, a
    witness's bounds: afsmc.verify.stream.extract): told of each file before it is
    solved (its part, the live and the other values, where its states' rows are), of
    each span of a group once its values are in place (each state's first optimal
    choice per query of the group, within the state), and of the file's end."""

    def begin(self, name: str, part: Part, reg: list[F64] | None, other: list[F64],
              at: int | Rows) -> None: ...

    def span(self, g: int, lo: int, hi: int, best: I64) -> None: ...

    def end(self) -> None: ...


def solve_part(part: Part, groups: list[Group], reg: list[F64] | None, other: list[F64],
               out: list[F64], at: int | Rows, count: bool = False,
               fast: Fast | None = None, keep: Keep | None = None) -> int:
    """Solve the part's layers into `out[g]`, its state s at row `at + s` (as a ring),
    or at row `at[s]` where `at` is an array of rows;
    with `count`, the distinct (state, successor) pairs of its states (the uniform
    DTMC's transitions), else 0. With `fast`, by the compiled kernels (the lists of
    values are views of its matrices); with `keep`, each span's optimal choices handed
    to it once its values are in place."""
    if fast is not None:
        return _solve_compiled(part, reg is not None, at, count, fast, keep)
    pairs = 0
    spans = [(k, min(k + acyclic.SPAN, hi)) for lo, hi in
             itertools.pairwise(part.layers.tolist()) for k in range(lo, hi, acyclic.SPAN)]
    for i, (lo, hi) in enumerate(spans):
        if i % acyclic.TRIM_EVERY == acyclic.TRIM_EVERY - 1:
            acyclic.trim_heap()
        c0, c1 = int(part.states[lo]), int(part.states[hi])
        offsets = part.states[lo:hi + 1] - c0
        steps = _steps(part, lo, hi, 0 if reg is None else len(reg[0]), len(other[0]))
        for g, grp in enumerate(groups):
            per_choice = _product(steps, c1 - c0, None if reg is None else reg[g], other[g])
            if grp.reward is not None:
                per_choice += np.stack([part.rewards[r][c0:c1] for r in grp.reward], axis=1)
            on = np.stack([part.labels[t][lo:hi] for t in grp.target], axis=1)
            stay = None if part.stay is None else part.stay[c0:c1]
            best = None if keep is None else np.zeros((hi - lo, len(grp.queries)), np.int64)
            values = acyclic.settle(per_choice, stay, offsets, on, grp.sense, best)
            if isinstance(at, int):
                put(out[g], at + lo, values)
            else:
                out[g][at[lo:hi]] = values
            if keep is not None:
                assert best is not None
                keep.span(g, lo, hi, best)
        if count:
            pairs += _pairs(part, lo, hi)
    return pairs


# The fewest states of a layer each thread solves: below, the layer is solved in one.
SPLIT = 1024


def threads() -> int:
    """The threads of a compiled sweep: the cores this process may run on, at most 4
    (the pass is bound by memory, not arithmetic, past a few)."""
    cores = len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else \
        os.cpu_count() or 1
    return max(1, min(4, cores))


def _solve_compiled(part: Part, regular: bool, at: int | Rows, count: bool, fast: Fast,
                    keep: Keep | None = None) -> int:
    """solve_part by afsmc.verify.kernels.streamed: the whole file's layers and every
    group of `fast` in one call, no matrix built; the same values to the bit. `regular`: a
    bucket's file (its values go to the live ones, else to the others). With `keep`, the
    optimal choices too, handed to it layer by layer once the file is solved."""
    from afsmc.verify.kernels import streamed

    n = len(part.states) - 1
    out = fast.live if regular else fast.other
    rows = (np.arange(at, at + n, dtype=np.int64) % len(out) if isinstance(at, int)
            else np.asarray(at, np.int64))
    stay = np.zeros(0) if part.stay is None else \
        np.asarray(part.stay[0:len(part.choices) - 1], np.float64)
    reward = np.stack([part.rewards[r] for r in fast.rewards], axis=1) if fast.rewards \
        else np.zeros((0, 0))
    on = np.stack([part.labels[t] for t in fast.targets], axis=1) if n else \
        np.zeros((0, len(fast.targets)), bool)
    best = np.zeros((n if keep is not None else 0, len(fast.sign)), np.int32)
    args = (part.states, part.choices, part.reg, part.oth, part.prob, fast.live, fast.other,
            reward, fast.rcol, stay, on, fast.ocol, fast.cut, fast.stuck, fast.reached,
            fast.mean, fast.sign, rows, out, best)
    pool = fast.pool
    threads = 1 if pool is None else fast.workers
    if pool is None or n < threads * SPLIT:
        streamed.solve(part.layers, *args, regular)
    else:
        # the states of a layer do not depend on each other: its parts side by side
        if regular:
            streamed.clear(out, rows)
        for lo, hi in itertools.pairwise(part.layers.tolist()):
            cuts = np.linspace(lo, hi, threads + 1).astype(np.int64) if hi - lo >= \
                threads * SPLIT else np.array([lo, hi], np.int64)
            done = [pool.submit(streamed.solve, cuts[j:j + 2], *args, False)
                    for j in range(len(cuts) - 1)]
            for f in done:
                f.result()
    if keep is not None:  # a layer's states depend on the earlier layers' (a witness's h)
        for lo, hi in itertools.pairwise(part.layers.tolist()):
            for g, (a, b) in enumerate(itertools.pairwise(fast.cut.tolist())):
                keep.span(g, lo, hi, best[lo:hi, a:b].astype(np.int64))
    if not count:
        return 0
    got = int(streamed.pairs(part.states, part.choices, part.reg, part.oth, fast.seen_reg,
                             fast.seen_oth, fast.stamp))
    fast.stamp += n
    return got


def _pairs(part: Part, lo: int, hi: int) -> int:
    """The distinct (state, successor) pairs of the span's states."""
    c0, c1 = int(part.states[lo]), int(part.states[hi])
    b0, b1 = int(part.choices[c0]), int(part.choices[c1])
    per_choice = np.repeat(np.arange(hi - lo, dtype=np.int64), np.diff(part.states[lo:hi + 1]))
    owner = np.repeat(per_choice, np.diff(part.choices[c0:c1 + 1]))
    reg, oth = part.reg[b0:b1], part.oth[b0:b1]
    succ = np.where(reg >= 0, 2 * reg, 2 * oth + 1)  # the two spaces apart
    # distinct by a sort (np.unique hashes int64 keys far slower)
    return len(keysets.unique(succ * acyclic.SPAN + owner))


def groups_of(queries: list[Query], reward_names: list[str], most: int | None = None
              ) -> list[Group]:
    """The queries by kind (and means apart), as acyclic.solve_many groups them, at
    most `most` in a group."""
    by: dict[tuple[str, bool], list[Query]] = {}
    for q in queries:
        by.setdefault((q.kind, q.opt == "mean"), []).append(q)
    step = most or max(1, len(queries))
    return [Group(qs, Sense.of(qs),
                  [reward_names.index(q.reward) for q in qs] if qs[0].kind == "R" else None,
                  [q.target for q in qs])
            for every in by.values() for qs in (every[i:i + step]
                                                for i in range(0, len(every), step))]


Progress = Callable[[int, int, int], None]  # buckets solved, of how many; sweeps to go


def window_rows(st: Streamed) -> int:
    """The most regular states whose values the pass keeps at once: for each bucket,
    from its first state to the last one that it or an earlier bucket reaches."""
    ends = [s + n for s, n in zip(st.start, st.size, strict=True)]
    keep = itertools.accumulate((ends[r] for r in st.reach), max)
    return max(1, max((k - s for k, s in zip(keep, st.start, strict=True)), default=1))


def live_rows(st: Streamed) -> int:
    """The most regular states live at once in the pass: solving bucket i, its own and
    those of later buckets that bucket i or an earlier one points at (less the dies of
    the buckets solved before it)."""
    alive = most = 0
    for size, dies in zip(reversed(st.size), reversed(st.dies), strict=True):
        alive += size
        most = max(most, alive)
        alive -= dies
    return max(1, most)


# The most bytes the live values of one sweep take: above it, the queries (P, R, the
# uniform DTMC's means) are solved in several sweeps, each reading the files again,
# rather than all side by side. At least SWEEP_BYTES, and SWEEP_SHARE of the memory
# available when the pass begins (the exploration's window is freed by then).
SWEEP_BYTES = 1 << 28
SWEEP_SHARE = 0.05


def sweep_bytes() -> int:
    """The bytes one sweep's live values may take (see SWEEP_BYTES)."""
    from afsmc.verify.engines.guard import mem_available

    free = mem_available()
    return SWEEP_BYTES if free is None else max(SWEEP_BYTES, int(SWEEP_SHARE * free))


def sweeps(queries: list[Query], reward_names: list[str], rows: int,
           most: int | None = None) -> list[list[Group]]:
    """The queries' groups, cut to fit, packed into sweeps whose window of values fits
    `most` bytes (SWEEP_BYTES if None; one query at a time where one does not)."""
    most = SWEEP_BYTES if most is None else most
    groups = groups_of(queries, reward_names, max(1, most // (8 * rows)))
    out: list[list[Group]] = []
    cols = 0
    for g in groups:
        k = len(g.queries)
        if out and (cols + k) * rows * 8 <= most:
            out[-1].append(g)
            cols += k
        else:
            out.append([g])
            cols = k
    return out


def run(st: Streamed, queries: list[Query], reward_names: list[str], targets: int,
        progress: Progress | None = None, keep: Keep | None = None
        ) -> tuple[dict[str, float], int]:
    """Each query's value in the initial state, and the uniform DTMC's transitions (0
    unless a query is a mean): as few sweeps over the files as sweep_bytes() allows;
    with `keep`, one sweep that hands it every file's optimal choices."""
    rows = live_rows(st)
    plan = sweeps(queries, reward_names, rows, sweep_bytes()) if keep is None else \
        [groups_of(queries, reward_names)]
    out: dict[str, float] = {}
    pairs = 0
    # the uniform DTMC's transitions counted in the first sweep of means
    counted = next((k for k, part in enumerate(plan) if any(g.sense.mean for g in part)), -1)
    for k, part in enumerate(plan):
        values, got = _sweep(st, part, len(reward_names), targets, rows, progress,
                             len(plan) - k, k == counted, keep)
        out |= values
        pairs += got
    return {q.name: out[q.name] for q in queries}, pairs


def _sweep(st: Streamed, groups: list[Group], nr: int, targets: int, rows: int,
           progress: Progress | None, left: int, count: bool, keep: Keep | None = None
           ) -> tuple[dict[str, float], int]:
    """One sweep over the files for `groups`: their values in the initial state, and
    with `count` the uniform DTMC's transitions; each file's optimal choices to `keep`."""
    fast = Fast.of(groups, rows, st.sinks + st.late) if kernels.enabled(st.states) else None
    if fast is not None:
        fast.workers = threads()
        if fast.workers > 1:
            fast.pool = ThreadPoolExecutor(fast.workers, thread_name_prefix="afsmc-sweep")
    try:
        return _sweep_with(st, groups, nr, targets, rows, progress, left, count, fast, keep)
    finally:
        if fast is not None:
            fast.close()


def _ahead(st: Streamed, names: list[str]) -> Generator[Arrays, None, None]:
    """Each file's arrays in turn, the next one read by a thread of its own meanwhile."""
    with ThreadPoolExecutor(1, thread_name_prefix="afsmc-read") as reader:
        coming = reader.submit(st.scratch.load, names[0]) if names else None
        for k in range(len(names)):
            assert coming is not None
            got = coming.result()
            coming = reader.submit(st.scratch.load, names[k + 1]) if k + 1 < len(names) \
                else None
            yield got


def _sweep_with(st: Streamed, groups: list[Group], nr: int, targets: int, rows: int,
                progress: Progress | None, left: int, count: bool, fast: Fast | None,
                keep: Keep | None = None) -> tuple[dict[str, float], int]:
    other = fast.views(fast.other) if fast is not None else \
        [np.zeros((st.sinks + st.late, len(g.queries))) for g in groups]
    late = late_index(st)
    pairs = 0
    read = load if fast is None else load_compiled

    def solve(name: str, part: Part, reg: list[F64] | None, out: list[F64],
              at: int | Rows) -> int:
        if keep is not None:
            keep.begin(name, part, reg, other, at)
        got = solve_part(part, groups, reg, other, out, at, count, fast, keep)
        if keep is not None:
            keep.end()
        return got

    for i, first in enumerate(st.sink_start):
        part = read(st, f"s{i}", 0, first, *late, nr, targets)
        pairs += solve(f"s{i}", part, None, other, first)
    if st.late:
        part = read(st, "late", 0, st.sinks, *late, nr, targets)
        pairs += solve("late", part, None, other, st.sinks)
    live = fast.views(fast.live) if fast is not None else \
        [np.zeros((rows, len(g.queries))) for g in groups]
    wide = rows >= 2 ** 31
    slot: Rows = np.zeros(window_rows(st), np.int64 if wide else np.int32)
    free = np.arange(rows, dtype=slot.dtype)  # a stack of the free rows, top at the end
    top = rows
    buckets = len(st.start)
    # the compiled path reads the next file while it solves one (its reader closed at
    # the end or on an error, before the scratch is removed)
    files = _ahead(st, [f"b{i}" for i in reversed(range(buckets))]) if fast is not None \
        else None
    with contextlib.closing(files) if files is not None else contextlib.nullcontext():
        for i in reversed(range(buckets)):
            first, size = st.start[i], st.size[i]
            mine = free[top - size:top].copy()
            top -= size
            put(slot, first, mine)
            if fast is None:  # its rows start at 0, as the in-memory pass's values do
                for r in live:  # (the kernel clears them itself)
                    r[mine] = 0.0
            part = read(st, f"b{i}", first, None, *late, nr, targets, slot) if files is None \
                else load_compiled(st, f"b{i}", first, None, *late, nr, targets, slot, next(files))
            pairs += solve(f"b{i}", part, live, live, mine)
            assert part.dies is not None
            dead = slot[(part.dies.astype(np.int64) + first) % len(slot)]
            del part
            free[top:top + len(dead)] = dead
            top += len(dead)
            if progress is not None:
                progress(buckets - i, buckets, left)
    out: dict[str, float] = {}
    for g, grp in enumerate(groups):
        row = live[g][slot[st.initial % len(slot)]] if st.initial >= 0 else \
            other[g][-1 - st.initial]
        out |= {q.name: float(x) for q, x in zip(grp.queries, row, strict=True)}
    return out, pairs
