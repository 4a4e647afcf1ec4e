"""The states of afsmc's own exploration (afsmc.verify.explorer.explore) bucket by bucket, each
bucket's in topological order, and the whole as the arrays of the backward pass.

Buckets are explored in increasing order of the clock, each to a fixpoint; then the late
states (reached by a transition that sets the clock back); a state whose every branch
loops is taken out of its bucket into one first layer of absorbing states, so that the
late states may reach it. Within a block, Kahn's algorithm (backwards, self-loops
ignored) orders the states; a cycle of more than one state gives up.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np
import numpy.typing as npt

from afsmc.verify import kernels
from afsmc.verify.arrays import acyclic
from afsmc.verify.arrays.acyclic import F64, I64, Arrays, Bools
from afsmc.verify.explorer.explore import (
    Compiled,
    Expansion,
    GiveUp,
    Notify,
    TooManyStates,
    expand,
    full,
)
from afsmc.verify.explorer.explore_eval import frame
from afsmc.verify.explorer.keysets import Codes, Frontiers, ProbTable, Sorted, found_in, unique
from afsmc.verify.kernels import ANY_KEY

if TYPE_CHECKING:
    from afsmc.verify.kernels.hashing import Found

Counts = npt.NDArray[np.int32]  # choices of a state, branches of a choice
Commands = npt.NDArray[np.int32]
Pairs = tuple[npt.NDArray[np.int32], F64]  # a sparse vector: (positions, values)


def _no_pairs() -> Pairs:
    return np.zeros(0, np.int32), np.zeros(0)


@dataclass
class Block:
    """The states of one bucket (or the late ones) in backward order: every successor in
    the block lies in an earlier layer of it."""

    keys: I64
    nchoice: Counts  # per state
    nbranch: Counts  # per choice
    target: I64  # per branch: the successor's key
    prob: Codes  # per branch: its probability's code in the exploration's ProbTable
    reward: list[Pairs]  # per reward structure asked: per choice, state reward included
    labels: list[Bools]  # per target: per state
    layers: list[int]  # the layers' sizes
    command: Commands  # per choice: its lowered command (empty unless Compiled.keep)
    # the absorbing states (see split_sinks) are the first `sinks` ones; -1: not known
    sinks: int = -1


def explore_bucket(c: Compiled, table: ProbTable, start: I64, b: int | None,
                   waiting: Frontiers, exclude: I64 | None = None, *, counted: int = 0,
                   max_states: int | None = None, rounds: int | None = None
                   ) -> tuple[Block, I64, int]:
    """The states of bucket `b` reachable from `start` (None: the late states, whose
    successors all stay late, but for those in `exclude`, explored already); successors
    in other buckets go to `waiting`. The block, its sorted keys and the rounds taken.
    Raises TooManyStates as soon as `counted` (the states of earlier buckets) and this
    bucket's pass `max_states`: a bucket may be deep (a long chain, round after round);
    with `rounds` (those of earlier buckets), GiveUp as soon as the states come too few
    per round (see NARROW_ROUNDS), rather than at the end of the chain."""
    x = search_bucket(c, start, b, waiting, exclude, counted=counted, max_states=max_states,
                      rounds=rounds)
    return x.block(c, table), x.found.sorted(), len(x.parts)


@dataclass
class Search:
    """A bucket's states found (explore_bucket's first step) and each round's expansion,
    and whether the compiled kernels took them; `block` assembles them."""

    found: Sorted | Found
    parts: list[tuple[I64, Expansion]]
    fast: bool
    sinks_first: bool

    def block(self, c: Compiled, table: ProbTable) -> Block:
        """The block of the states found (explore_bucket's second step)."""
        return _block(c, table, self.found, self.parts, self.fast, self.sinks_first)


def search_bucket(c: Compiled, start: I64, b: int | None, waiting: Frontiers,
                  exclude: I64 | None = None, *, counted: int = 0,
                  max_states: int | None = None, rounds: int | None = None) -> Search:
    """explore_bucket's states found and expansions, the block not yet assembled (the
    streamed route assembles it in another thread)."""
    fast = kernels.enabled(counted + len(start))
    found: Sorted | Found
    if fast:
        from afsmc.verify.kernels.hashing import Found

        found = Found(start, exclude, _span(c, b))
    else:
        found = Sorted(start, exclude)
    frontier = found.first
    parts: list[tuple[I64, Expansion]] = []
    while frontier.size:
        x = expand(c, frontier, fast)
        parts.append((frontier, x))
        same = np.ones(len(x.target), bool)
        if b is not None:
            tb = c.layout.bucket_of(x.target)
            same = tb == b
            later = tb > b
            if later.any():
                waiting.add(tb[later], x.target[later], fast)
            earlier = tb < b
            if earlier.any():
                waiting.late.append(unique(x.target[earlier]))
        frontier = found.add(x.target[same])
        if max_states is not None and counted + found.size > max_states:
            raise TooManyStates(counted + found.size, partial=True)
        if rounds is not None:
            narrow(counted + found.size, rounds + len(parts))
    return Search(found, parts, fast, fast and b is not None)


def _span(c: Compiled, b: int | None) -> tuple[int, int]:
    """The keys of bucket `b`: [lo, hi) (None: any key)."""
    f = c.layout.bucket
    return (0, ANY_KEY) if f is None or b is None else (b << f.shift, (b + 1) << f.shift)


def _offsets(counts: Counts) -> I64:
    out = np.zeros(len(counts) + 1, np.int64)
    np.cumsum(counts, out=out[1:])
    return out


def _subset(blk: Block, idx: I64, layers: list[int]) -> Block:
    states, choices = _offsets(blk.nchoice), _offsets(blk.nbranch)
    ch = acyclic._ranges(states[idx], states[idx + 1])
    br = acyclic._ranges(choices[ch], choices[ch + 1])
    return Block(blk.keys[idx], blk.nchoice[idx], blk.nbranch[ch], blk.target[br],
                 blk.prob[br], [_pairs_at(r, ch) for r in blk.reward], [x[idx] for x in blk.labels],
                 [k for k in layers if k], blk.command[ch] if len(blk.command) else blk.command)


def _pairs_at(r: Pairs, idx: I64) -> Pairs:
    """The entries of `r` at the positions `idx` (sorted), renumbered 0, 1, ... along it."""
    at, values = r
    keep = found_in(idx, at.astype(np.int64))
    return np.searchsorted(idx, at[keep]).astype(np.int32), values[keep]


def _cat_pairs(blocks: list[Block], i: int) -> tuple[I64, F64]:
    """The blocks' rewards of structure `i` end to end, positions numbered across the
    blocks' choices (read before those are freed); each block's freed."""
    at: list[I64] = []
    values: list[F64] = []
    first = 0
    for b in blocks:
        at.append(b.reward[i][0].astype(np.int64) + first)
        values.append(b.reward[i][1])
        first += len(b.nbranch)
        b.reward[i] = _no_pairs()
    if not at:
        return np.zeros(0, np.int64), np.zeros(0)
    return np.concatenate(at), np.concatenate(values)


def split_sinks(blk: Block) -> tuple[Block, Block]:
    """(the block's absorbing states, whose every branch loops, and the others). The
    absorbing ones are in its first layer: they may come first of all, before the
    states that reach them by a transition that sets the clock back."""
    if blk.sinks >= 0:
        return _cut(blk, blk.sinks)
    n = len(blk.keys)
    owner = acyclic._state_of_branches(_offsets(blk.nchoice), _offsets(blk.nbranch))
    moving = blk.target != blk.keys[owner]
    sink = np.bincount(owner[moving], minlength=n) == 0
    del owner, moving
    idx = np.flatnonzero(sink)
    if idx.size and idx[-1] >= blk.layers[0]:
        raise GiveUp("an absorbing state past the first layer")
    rest = np.flatnonzero(~sink)
    return (_subset(blk, idx, [len(idx)]),
            _subset(blk, rest, [blk.layers[0] - len(idx), *blk.layers[1:]]))


def _cut(blk: Block, k: int) -> tuple[Block, Block]:
    """split_sinks of a block whose absorbing states are its first `k`: its arrays cut
    (views) where split_sinks would gather them."""
    ch = int(blk.nchoice[:k].sum())
    br = int(blk.nbranch[:ch].sum())
    cuts = [int(np.searchsorted(at, ch)) for at, _ in blk.reward]
    cmd = blk.command
    head = Block(blk.keys[:k], blk.nchoice[:k], blk.nbranch[:ch], blk.target[:br],
                 blk.prob[:br], [(at[:j], v[:j]) for (at, v), j in zip(blk.reward, cuts, strict=True)],
                 [x[:k] for x in blk.labels], [k] if k else [], cmd[:ch] if len(cmd) else cmd)
    tail = Block(blk.keys[k:], blk.nchoice[k:], blk.nbranch[ch:], blk.target[br:],
                 blk.prob[br:],
                 [(at[j:] - ch, v[j:]) for (at, v), j in zip(blk.reward, cuts, strict=True)],
                 [x[k:] for x in blk.labels],
                 [s for s in [blk.layers[0] - k, *blk.layers[1:]] if s],
                 cmd[ch:] if len(cmd) else cmd)
    return head, tail


def _block(c: Compiled, table: ProbTable, found: Sorted | Found,
           parts: list[tuple[I64, Expansion]], fast: bool, sinks_first: bool = False
           ) -> Block:
    """The block of the explored `parts` (states in the order they were expanded, those
    `found`), its states sorted topologically (Kahn, backwards) by the edges within it;
    `fast`: reordered and coded by compiled kernels; `sinks_first`: the absorbing
    states first in the first layer, so that split_sinks cuts the block rather than
    gathering both parts."""
    if not parts:
        z, w = np.zeros(0, np.int64), np.zeros(0, np.int32)
        return Block(z, w, w, z, np.zeros(0, np.uint32), [_no_pairs() for _ in c.state_rewards],
                     [np.zeros(0, bool) for _ in c.targets], [], w)
    keys = np.concatenate([k for k, _ in parts])
    n = len(keys)
    nchoice = np.concatenate([np.bincount(x.state, minlength=len(k)).astype(np.int32)
                              for k, x in parts])
    nbranch = np.concatenate([np.diff(x.first).astype(np.int32) for _, x in parts])
    target = np.concatenate([x.target for _, x in parts])
    prob = np.concatenate([x.prob for _, x in parts])
    command = np.concatenate([x.command for _, x in parts]) if c.keep else np.zeros(0, np.int32)
    rewards = [np.concatenate([x.reward[i] for _, x in parts])
               for i in range(len(c.state_rewards))]
    del parts
    states = np.zeros(n + 1, np.int64)
    np.cumsum(nchoice, out=states[1:])
    choices = np.zeros(len(nbranch) + 1, np.int64)
    np.cumsum(nbranch, out=choices[1:])
    inside, at = found.inside(keys, target)
    local = acyclic._state_of_branches(states, choices)  # out of the block: as a self-loop
    sink = None
    if sinks_first:
        from afsmc.verify.kernels.blocks import absorbing

        sink = absorbing(states, choices, target, keys)
    local[inside] = at
    layers = acyclic.layers_of(states, choices, local)
    del local, inside, at
    if layers is None:
        raise GiveUp("a cycle of more than one state")
    lead = -1 if sink is None else _sinks_first(layers, sink)
    perm = np.concatenate(layers)
    old_choice, nbranch, target, prob = _permuted(perm, states, choices, nbranch, target, prob,
                                                  fast)
    keys, nchoice = keys[perm], nchoice[perm]
    fr = frame(c.layout.decode(keys))
    labels = [full(t(fr), n, bool) for t in c.targets]
    out_rewards = []
    for r, items in zip(rewards, c.state_rewards, strict=True):
        per_state = np.zeros(n)
        for guard, value in items:
            per_state += np.where(full(guard(fr), n, bool), full(value(fr), n, float), 0.0)
        full_reward = r[old_choice] + np.repeat(per_state, nchoice)
        nz = np.flatnonzero(full_reward)
        out_rewards.append((nz.astype(np.int32), full_reward[nz]))
    return Block(keys, nchoice, nbranch, target, table.encode(prob, fast),
                 out_rewards, labels, [len(x) for x in layers],
                 command[old_choice] if c.keep else command, lead)


def _permuted(perm: I64, states: I64, choices: I64, nbranch: Counts, target: I64, prob: F64,
              fast: bool) -> tuple[I64, Counts, I64, F64]:
    """The states in the order `perm`: each choice's old index, its branch count, each
    branch's target and probability; `fast`: in one pass of a compiled kernel."""
    if fast:
        from afsmc.verify.kernels.blocks import permuted

        return permuted(perm, states, choices, nbranch, target, prob)
    old_choice = acyclic._ranges(states[perm], states[perm + 1])
    branch = acyclic._ranges(choices[old_choice], choices[old_choice + 1])
    return old_choice, nbranch[old_choice], target[branch], prob[branch]


def _sinks_first(layers: list[I64], sink: Bools) -> int:
    """The absorbing states (`sink`) of the first layer moved to its front, the order of
    both kinds kept, so that the block's order after split_sinks is the one it gives
    otherwise; their number, or -1 if one lies past the first layer."""
    if not layers or sink[layers[0]].sum() != sink.sum():
        return -1
    first = layers[0]
    absorbing = sink[first]
    layers[0] = np.concatenate([first[absorbing], first[~absorbing]])
    return int(absorbing.sum())


@dataclass
class Explored:
    arrays: Arrays
    states: int
    choices: int
    transitions: int


# A model explored in more rounds than this, with fewer states per round on average than
# NARROW_STATES, comes a few states at a time (a long chain): each round costs numpy's
# fixed overheads, and Storm's builder, a state at a time, is far quicker at it.
NARROW_ROUNDS = 5000
NARROW_STATES = 50
PROGRESS_EVERY = 2.0  # seconds between two progress lines


def narrow(count: int, rounds: int) -> None:
    """GiveUp if `count` states in `rounds` rounds is a long chain (Storm is quicker)."""
    if rounds > NARROW_ROUNDS and count < NARROW_STATES * rounds:
        raise GiveUp(f"its states come a few at a time ({count:,} in {rounds:,} rounds)")
TRIM_BUCKETS = 32  # buckets explored between two trim_heap()

# The explored blocks times this is about the peak of the whole (the arrays assembled and
# the pass's values besides them): 1.19 GB for scenario 2's 0.72 GB of blocks.
PEAK_FACTOR = 1.8


def _nbytes(b: Block) -> int:
    arrays: list[npt.NDArray[Any]] = [b.keys, b.nchoice, b.nbranch, b.target, b.prob,
                                      b.command, *b.labels, *[x for r in b.reward for x in r]]
    return sum(int(a.nbytes) for a in arrays)


@dataclass
class Partial:
    """An exploration stopped after a bucket, to go on elsewhere (Handover): the buckets
    explored, in order, with their blocks (the absorbing states split off into `sinks`)
    and the states explored after each; the states waiting, the probabilities' table the
    blocks' codes point into, and the rounds taken."""

    buckets: list[int]
    blocks: list[Block | None]
    sinks: list[Block | None]
    counts: list[int]
    waiting: Frontiers
    table: ProbTable
    rounds: int


class Handover(Exception):
    """The in-memory exploration stopped, as its `handover` asked after a bucket, `why`
    (afsmc.verify.stream.layers.explore goes on from `partial` through the disk)."""

    def __init__(self, partial: Partial, why: str) -> None:
        super().__init__(why)
        self.partial, self.why = partial, why


def explore(c: Compiled, notify: Notify | None = None, max_states: int | None = None,
            max_bytes: int | None = None, handover: Callable[[int], str | None] | None = None
            ) -> Explored:
    """Every state reachable from the initial one, bucket by bucket; raises GiveUp (also
    once the blocks, times PEAK_FACTOR, pass `max_bytes`), or TooManyStates past
    `max_states`; and Handover once `handover`, asked after each bucket with the states
    explored so far, gives a reason."""
    waiting, table = Frontiers(), ProbTable()
    waiting.pending[int(c.layout.bucket_of(np.array([c.initial]))[0])] = [
        np.array([c.initial], np.int64)]
    blocks: list[Block] = []
    sinks: list[Block] = []
    regular: list[I64] = []
    buckets: list[int] = []
    counts: list[int] = []
    count = held = rounds = 0
    shown = time.monotonic()
    while waiting.pending:
        b = min(waiting.pending)
        start = waiting.take(b)
        block, known, took = explore_bucket(c, table, start, b, waiting, counted=count,
                                            max_states=max_states, rounds=rounds)
        rounds += took
        sink, block = split_sinks(block)
        blocks.append(block)
        sinks.append(sink)
        regular.append(known)
        count += len(known)
        buckets.append(b)
        counts.append(count)
        held += _nbytes(block) + _nbytes(sink) + known.nbytes
        if max_states is not None and count > max_states:
            raise TooManyStates(count)
        narrow(count, rounds)
        if max_bytes is not None and held * PEAK_FACTOR > max_bytes:
            raise GiveUp(f"{count:,} states explored so far would need more than the "
                         f"{max_bytes / 1e9:.1f} GB available")
        if len(blocks) % TRIM_BUCKETS == 0:
            acyclic.trim_heap()
        if notify is not None and time.monotonic() - shown > PROGRESS_EVERY:
            shown = time.monotonic()
            notify("explored", (b, count))
        if handover is not None and (why := handover(count)) is not None:
            raise Handover(Partial(buckets, list(blocks), list(sinks), counts, waiting,
                                   table, rounds), why)
    if waiting.late:
        absorbing = np.sort(np.concatenate([s.keys for s in sinks]))
        block, known, _ = explore_bucket(c, table, np.concatenate(waiting.late), None,
                                         Frontiers(), absorbing, counted=count,
                                         max_states=max_states)
        if found_in(np.concatenate(regular), known).any():
            raise GiveUp("a state reached both before and after its clock went back")
        blocks.append(block)
    del regular
    blocks.append(_joined(sinks, c))
    return assemble(blocks, c, table)


def _joined(sinks: list[Block], c: Compiled) -> Block:
    """The absorbing states of every bucket as one block of one layer."""
    total = sum(len(s.keys) for s in sinks)
    rewards = []
    for i in range(len(c.state_rewards)):
        at, values = _cat_pairs(sinks, i)
        rewards.append((at.astype(np.int32), values))
    labels = [np.concatenate([s.labels[i] for s in sinks]) for i in range(len(c.targets))]
    return Block(_cat_free(sinks, "keys", np.int64), _cat_free(sinks, "nchoice", np.int32),
                 _cat_free(sinks, "nbranch", np.int32), _cat_free(sinks, "target", np.int64),
                 _cat_free(sinks, "prob", np.uint32), rewards, labels,
                 [total] if total else [], _cat_free(sinks, "command", np.int32))


def _cat_free(blocks: list[Block], name: str, dtype: Any) -> Any:
    """The blocks' arrays `name` end to end, each freed once copied."""
    total = sum(len(getattr(b, name)) for b in blocks)
    out = np.empty(total, dtype)
    at = 0
    for b in blocks:
        a = getattr(b, name)
        out[at:at + len(a)] = a
        at += len(a)
        setattr(b, name, np.zeros(0, dtype))
    acyclic.trim_heap()
    return out


def assemble(blocks: list[Block], c: Compiled, table: ProbTable) -> Explored:
    """The blocks as one model for the backward pass: the last explored first. Each
    block's arrays are freed once copied, the rewards kept sparse where mostly 0."""
    blocks = blocks[::-1]
    m = sum(len(b.nbranch) for b in blocks)
    rewards = [acyclic.sparse_or_dense(m, *_cat_pairs(blocks, i))
               for i in range(len(c.state_rewards))]
    keys = _cat_free(blocks, "keys", np.int64)
    n = len(keys)
    states = np.zeros(n + 1, np.int64)
    np.cumsum(_cat_free(blocks, "nchoice", np.int32), out=states[1:])
    choices = np.zeros(m + 1, np.int64)
    np.cumsum(_cat_free(blocks, "nbranch", np.int32), out=choices[1:])
    prob = acyclic.Coded(table.table(), _cat_free(blocks, "prob", table.dtype()))
    command = _cat_free(blocks, "command", np.int32)
    labels = {acyclic.LABEL + str(i): np.concatenate([b.labels[i] for b in blocks])
              for i in range(len(c.targets))}
    sizes = [s for b in blocks for s in b.layers if s]
    layers = np.zeros(len(sizes) + 1, np.int64)
    np.cumsum(sizes, out=layers[1:])
    for b in blocks:
        b.labels = []
    kept = keys if c.keep else None  # a strategy's: the states' values and ranks
    if kernels.enabled(n):
        target, initial = _targets_hashed(blocks, keys, c)
    else:
        order = np.argsort(keys)
        sorted_keys = keys[order]
        del keys
        target, initial = _targets(blocks, order, sorted_keys, c.initial)
        del order, sorted_keys
    acyclic.trim_heap()
    stay = acyclic.self_loops(states, choices, target, prob)
    arrays = Arrays(states, choices, target, prob, stay, layers, initial, labels,
                    dict(zip(c.reward_names, rewards, strict=True)), order=kept,
                    commands=command if c.keep else None)
    return Explored(arrays, n, m, len(target))


def _targets(blocks: list[Block], order: I64, sorted_keys: I64, initial_key: int
             ) -> tuple[acyclic.Idx, int]:
    """Each branch's successor as a state number (the state of key `sorted_keys[i]` is
    `order[i]`), a block at a time; and the initial state's number."""

    def numbers(part: I64) -> I64:
        # the part's successors lie among a few buckets' keys: searched there, in cache
        w0, w1 = np.searchsorted(sorted_keys, [part.min(), part.max()])
        window = sorted_keys[w0:w1 + 1]
        pos = np.searchsorted(window, part)
        if not len(window) or (window[np.minimum(pos, len(window) - 1)] != part).any():
            raise GiveUp("a successor that was not explored")
        out: I64 = order[pos + w0]
        return out

    return _renumbered(blocks, numbers), int(order[np.searchsorted(sorted_keys, initial_key)])


def _targets_hashed(blocks: list[Block], keys: I64, c: Compiled) -> tuple[acyclic.Idx, int]:
    """As _targets, by the compiled hash table of `keys` (the states' keys by number),
    a region per bucket: a block's successors lie in a few buckets, whose regions stay in
    cache while it is resolved."""
    from afsmc.verify.kernels.hashing import Regions

    bucket = c.layout.bucket
    index = Regions(keys, bucket.shift if bucket is not None else 63)

    def numbers(part: I64) -> I64:
        out = index.find(part)
        if out.min() < 0:
            raise GiveUp("a successor that was not explored")
        return out

    return _renumbered(blocks, numbers), int(numbers(np.array([c.initial], np.int64))[0])


def _renumbered(blocks: list[Block], numbers: Callable[[I64], I64]) -> acyclic.Idx:
    """Each block's branch successors (keys) as state numbers, `numbers` of a chunk at a
    time, each block's keys freed once done."""
    target = np.empty(sum(len(b.target) for b in blocks), np.int32)
    at = 0
    for k, b in enumerate(blocks):
        for i in range(0, len(b.target), acyclic.CHUNK):
            part = b.target[i:i + acyclic.CHUNK]
            target[at:at + len(part)] = numbers(part)
            at += len(part)
        b.target = np.zeros(0, np.int64)
        if k % TRIM_BUCKETS == TRIM_BUCKETS - 1:
            acyclic.trim_heap()
    return target
