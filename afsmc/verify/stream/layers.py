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

import queue
import threading
import time
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import numpy.typing as npt

from afsmc.verify import kernels
from afsmc.verify.arrays import acyclic
from afsmc.verify.arrays.acyclic import I64
from afsmc.verify.explorer import explore_graph
from afsmc.verify.explorer.explore import Compiled, GiveUp, Notify, TooManyStates
from afsmc.verify.explorer.explore_graph import Block
from afsmc.verify.explorer.keysets import Frontiers, ProbTable, found_in
from afsmc.verify.stream import resolve
from afsmc.verify.stream.scratch import Scratch


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


def _save_block(s: Scratch, name: str, blk: Block, target: I64 | None) -> None:
    """The block as one file, what the backward pass reads (`opened` gives it back): its
    successors (`target`) too unless None (a bucket's are appended once they are
    numbered); not its keys (a bucket's are a file of their own, read only to check the
    late states). Counts and probability codes in the narrowest unsigned type that holds
    them (a model's are small: a byte each, mostly), each label's bits packed."""
    arrays: dict[str, Any] = {
        "nchoice": smallest(blk.nchoice), "nbranch": smallest(blk.nbranch),
        "prob": smallest(blk.prob), "layers": np.asarray(blk.layers, np.int64),
        **({} if target is None else {"target": target})}
    for i, (at, values) in enumerate(blk.reward):
        arrays[f"reward{i}_at"], arrays[f"reward{i}_v"] = at, values
    for i, lab in enumerate(blk.labels):
        arrays[f"label{i}"] = np.packbits(lab)
    if len(blk.command):  # kept for a strategy or a witness (Compiled.keep)
        arrays["command"] = smallest(blk.command)
    s.save(name, **arrays)


def smallest(x: npt.NDArray[np.integer[Any]]) -> npt.NDArray[np.unsignedinteger[Any]]:
    """Non-negative integers in the narrowest unsigned type that holds them all."""
    top = int(x.max()) if len(x) else 0
    kind = np.uint8 if top < 1 << 8 else np.uint16 if top < 1 << 16 else np.uint32 \
        if top < 1 << 32 else np.uint64
    out: npt.NDArray[np.unsignedinteger[Any]] = x.astype(kind)
    return out


def opened(a: dict[str, npt.NDArray[Any]]) -> dict[str, npt.NDArray[Any]]:
    """A block's file as _save_block wrote it, its labels unpacked (one per state)."""
    n = len(a["nchoice"])
    return {k: np.unpackbits(v, count=n).astype(bool) if k.startswith("label") else v
            for k, v in a.items()}


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
            max_states: int | None = None, resume: explore_graph.Partial | None = None
            ) -> Streamed:
    """Every state reachable from the initial one, bucket by bucket, written to `s`;
    raises GiveUp as explore_graph.explore does, TooManyStates past `max_states`. With
    `resume`, the buckets an in-memory exploration explored are written first (each
    block let go once handed over), and the exploration goes on from where it stopped.

    Two threads: this one finds each bucket's states in order
    (explore_graph.search_bucket) and hands each bucket's states found to a worker
    (_Writer) that assembles their block, splits off its sinks, writes it and numbers
    the successors of the buckets whose reach is explored, in the same order; most of
    either's work is in numpy or compiled kernels, which let the other run. The
    probabilities' table is the writer's until it is done."""
    if resume is None:
        waiting, table = Frontiers(), ProbTable()
        waiting.pending[int(c.layout.bucket_of(np.array([c.initial]))[0])] = [
            np.array([c.initial], np.int64)]
        count = rounds = 0
    else:
        waiting, table = resume.waiting, resume.table
        count, rounds = resume.counts[-1], resume.rounds
    writer = _Writer(c, s, table)
    shown = time.monotonic()
    try:
        if resume is not None:
            _replay(writer, resume)
        while waiting.pending:
            writer.check()
            b = min(waiting.pending)
            begin = waiting.take(b)
            found = explore_graph.search_bucket(c, begin, b, waiting, counted=count,
                                                max_states=max_states, rounds=rounds)
            rounds += len(found.parts)
            count += found.found.size
            if max_states is not None and count > max_states:
                raise TooManyStates(count)
            explore_graph.narrow(count, rounds)
            writer.put((b, found, min(waiting.pending) if waiting.pending else None, count))
            del found
            if notify is not None and time.monotonic() - shown > explore_graph.PROGRESS_EVERY:
                shown = time.monotonic()
                notify("explored", (b, count, s.written))
        writer.close()
    finally:
        writer.stop()
    out = writer.out
    acyclic.trim_heap()
    _late(c, s, out, table, waiting, writer.sinks, writer.buckets, count, max_states)
    out.table = table.table()
    s.save("table", prob=out.table)
    return out


def _replay(writer: _Writer, resume: explore_graph.Partial) -> None:
    """Hand the writer the buckets an in-memory exploration explored, in order, each as
    it would have been handed over had it been explored here (its successor bucket the
    next explored, after the last the first still waiting)."""
    nxt_after = min(resume.waiting.pending) if resume.waiting.pending else None
    for i, b in enumerate(resume.buckets):
        sink, block = resume.sinks[i], resume.blocks[i]
        assert sink is not None and block is not None
        resume.sinks[i] = resume.blocks[i] = None  # the writer's alone: freed once written
        nxt = resume.buckets[i + 1] if i + 1 < len(resume.buckets) else nxt_after
        writer.put((b, (sink, block), nxt, resume.counts[i]))
        del sink, block


# An explored bucket handed to the writer: the bucket, its states found (the block is
# assembled by the writer) or, from an in-memory exploration, its sinks and block; the
# next bucket to explore (None: none left) and the states explored so far.
Item = tuple[int, "explore_graph.Search | tuple[Block, Block]", "int | None", int]


class _Writer:
    """The buckets' blocks, written and numbered in a thread of its own in the order
    explored (at most two wait while one is written, so that memory holds a few
    buckets' states, and the explorer rarely waits for a slow bucket's writing); an
    error there is raised in the exploring thread at its next put or close."""

    def __init__(self, c: Compiled, s: Scratch, table: ProbTable) -> None:
        self.c, self.s, self.table = c, s, table
        self.out = Streamed(s)
        self.sinks: resolve.Sinks = resolve.Index()
        self.window: dict[int, resolve.Entry] = {}  # bucket -> its keys and numbers
        self.seen: resolve.Seen = {}
        self.unresolved: list[_Waiting] = []
        self.held: dict[int, I64] = {}  # bucket index -> its successors' keys, in memory
        self.buckets: list[int] = []
        self.fast = False
        self.items: queue.Queue[Item | None] = queue.Queue(maxsize=2)
        self.error: BaseException | None = None
        self.halt = threading.Event()
        self.thread = threading.Thread(target=self._run, name="afsmc-layers", daemon=True)
        self.thread.start()

    def check(self) -> None:
        """Raise the writer's error, if it had one."""
        if self.error is not None:
            raise self.error

    def put(self, item: Item | None) -> None:
        while True:
            self.check()
            try:
                self.items.put(item, timeout=0.1)
                return
            except queue.Full:
                continue

    def close(self) -> None:
        """Wait for every block to be written and numbered."""
        self.put(None)
        while self.thread.is_alive():
            self.thread.join(0.1)
        self.check()
        assert not self.unresolved

    def stop(self) -> None:
        """Stop the writer (after close, or on an error here) and wait for it."""
        self.halt.set()
        while self.thread.is_alive():
            self.thread.join(0.1)

    def _run(self) -> None:
        try:
            while not self.halt.is_set():
                try:
                    item = self.items.get(timeout=0.1)
                except queue.Empty:
                    continue
                if item is None:
                    return
                self._write(*item)
        except BaseException as exc:  # handed to the exploring thread
            self.error = exc

    def _write(self, b: int, found: explore_graph.Search | tuple[Block, Block],
               nxt: int | None, count: int) -> None:
        """Bucket `b`'s block assembled (unless given, with its sinks split off) and
        written, and the successors of every bucket whose reach is explored (all up to
        `nxt`) numbered."""
        s, out, c = self.s, self.out, self.c
        if isinstance(found, tuple):
            sink, block = found
        else:
            sink, block = explore_graph.split_sinks(found.block(c, self.table))
        del found
        if not self.fast and kernels.enabled(count):
            self.fast = True
            assert isinstance(self.sinks, resolve.Index)
            resolve.hashed(self.window, self.sinks, self.buckets, out.sink_start, out.sinks)
            self.sinks = resolve.HashedSinks.of(self.sinks)
        index = len(self.buckets)
        self.buckets.append(b)
        first = sum(out.size)
        out.start.append(first)
        out.size.append(len(block.keys))
        out.sink_start.append(out.sinks)
        sink_numbers = np.arange(out.sinks, out.sinks + len(sink.keys), dtype=np.int64)
        self.sinks.add(sink.keys, sink_numbers)
        out.sinks += len(sink.keys)
        if c.keep:  # a strategy's or a witness's: the sinks' variables, from their keys
            s.save(f"sk{index}", keys=sink.keys)
        _save_block(s, f"s{index}", sink, -1 - sink_numbers[
            acyclic._state_of_branches(explore_graph._offsets(sink.nchoice),
                                       explore_graph._offsets(sink.nbranch))])
        if self.fast:
            from afsmc.verify.kernels.streamed import Bucket

            self.window[b] = Bucket(block.keys, first, sink.keys, int(sink_numbers[0]) if len(
                sink_numbers) else out.sinks)
            s.save(f"keys{index}", keys=block.keys)  # for _check_late and a strategy
        else:
            numbers = np.arange(first, first + len(block.keys), dtype=np.int64)
            order = np.argsort(block.keys)
            self.window[b] = (block.keys[order], numbers[order])
            s.save(f"keys{index}", keys=block.keys)  # for _check_late and a strategy
            del order, numbers
        self.seen[b] = (first, np.zeros(len(block.keys), bool))
        if index == 0:
            initial = np.array([c.initial], np.int64)
            out.initial = int(resolve.resolve_span([(b, self.window[b])], self.sinks, initial,
                                                   c)[0][0])
            if out.initial >= 0:  # its value is read once the pass is over: never dropped
                self.seen[b][1][out.initial - first] = True
        reach = int(c.layout.bucket_of(block.target).max()) if len(block.target) else b
        self.unresolved.append(_Waiting(index, b, max(reach, b)))
        out.choices += len(block.nbranch) + len(sink.nbranch)
        out.transitions += len(block.target) + len(sink.target)
        _save_block(s, f"b{index}", block, None)
        # its successors' keys, until numbered: in memory while the held ones are few
        if sum(k.nbytes for k in self.held.values()) + block.target.nbytes <= HOLD_BYTES:
            self.held[index] = block.target
        else:
            s.save(f"k{index}", target=block.target)
        del block, sink, sink_numbers
        while self.unresolved and (nxt is None or self.unresolved[0].reach < nxt):
            self._finish(self.unresolved.pop(0))
            low = self.unresolved[0].bucket if self.unresolved else nxt
            for t in [t for t in self.window if low is None or t < low]:
                del self.window[t], self.seen[t]
        if index % explore_graph.TRIM_BUCKETS == explore_graph.TRIM_BUCKETS - 1:
            acyclic.trim_heap()

    def _finish(self, w: _Waiting) -> None:
        """Resolve the successors of a bucket whose every successor bucket is explored:
        its successors' keys, written over by their numbers; and its dies. Buckets are
        resolved in order, so the first to point at a state is its lowest predecessor."""
        s, out, c, seen = self.s, self.out, self.c, self.seen
        span = [(t, self.window[t]) for t in sorted(self.window) if w.bucket <= t <= w.reach]
        on_disk = w.index not in self.held
        keys = s.load(f"k{w.index}")["target"] if on_disk else self.held.pop(w.index)
        if isinstance(span[0][1], tuple):
            target, late = resolve.resolve_span(span, self.sinks, keys, c)
            dies = None
        else:
            target, late, dies = resolve.resolve_hashed(span, self.sinks, keys, c, seen)
        at = np.flatnonzero(late)
        if at.size and (c.layout.bucket_of(keys[at]) >= w.bucket).any():
            raise GiveUp("a successor that was not explored")
        target[at] = np.iinfo(np.int64).min
        out.reach.append(int(np.searchsorted(self.buckets, w.reach, side="right")) - 1)
        if dies is None:
            dies = resolve.dies_sorted(target, w.bucket, w.reach, seen)
        out.dies.append(len(dies))
        first = out.start[w.index]
        # offsets from the bucket's first number: int32 while its reach spans fewer states
        wide = bool(len(dies)) and int(dies[-1]) - first >= 2 ** 31
        s.save(f"b{w.index}", append=True, target=narrow(target, first), dies=(
            dies - first).astype(np.int64 if wide else np.int32),
               **({"late_at": at, "late_key": keys[at]} if at.size else {}))
        if on_disk:
            s.remove(f"k{w.index}")


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


def _late(c: Compiled, s: Scratch, out: Streamed, table: ProbTable, waiting: Frontiers,
          sinks: resolve.Sinks, buckets: list[int], count: int, max_states: int | None
          ) -> None:
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
    target, missing = resolve.resolve_sorted((block.keys[order], numbers[order]), sinks,
                                             block.target)
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
