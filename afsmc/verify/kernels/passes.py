"""Compiled kernels of the backward pass (afsmc.verify.arrays.acyclic) and of the uniform
DTMC's size (afsmc.verify.engines.explicit).

Each kernel does, state by state, what its numpy reference does with whole arrays, and in
the same floating-point order, so that the values are the same to the bit:

- a choice's value is 0 plus each branch's probability times its successor's value, in
  the branches' order (scipy's CSR product), plus the choice's reward;
- a choice that loops with probability s is divided by 1 - s (one that only loops is the
  query's `stuck` value); a state's value is the min or max over its choices, or its
  policy's choice, or the uniform DTMC's mean; its optimal choice is the first that
  reaches the optimum;
- a sum over a state's choices (the mean) or over a choice's self-loops is numpy's
  `add.reduceat`: the first term plus the pairwise sum of the others (:func:`_pairwise`).

Without the CSR matrix, the value matrix of each span or the temporaries of numpy's
min/max over choices, a pass does one visit per branch and query. :func:`stepper`,
:func:`settled` and :func:`table_codes` put acyclic's arrays in the kernels' form.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import TYPE_CHECKING, Any

import numpy as np
import numpy.typing as npt

from afsmc.verify.kernels import jit

if TYPE_CHECKING:  # (acyclic imports this module when it takes the kernels)
    from afsmc.verify.arrays.acyclic import Arrays, Policy, Query, Sense, Vec

F64 = npt.NDArray[np.float64]
I64 = npt.NDArray[np.int64]
Ints = npt.NDArray[np.integer[Any]]
Bools = npt.NDArray[np.bool_]


@jit
def _pairwise(x: F64, start: int, n: int) -> float:
    """numpy's pairwise sum of x[start:start + n] (its `add` reduction): a plain loop from
    0 below 8 terms, 8 running sums up to 128, and halves (cut at a multiple of 8) above."""
    if n < 8:
        res = 0.0
        for i in range(n):
            res += x[start + i]
        return res
    if n <= 128:
        r = np.empty(8)
        for j in range(8):
            r[j] = x[start + j]
        i = 8
        while i < n - n % 8:
            for j in range(8):
                r[j] += x[start + i + j]
            i += 8
        res = float(((r[0] + r[1]) + (r[2] + r[3])) + ((r[4] + r[5]) + (r[6] + r[7])))
        while i < n:
            res += x[start + i]
            i += 1
        return res
    half = n // 2
    half -= half % 8
    return _pairwise(x, start, half) + _pairwise(x, start + half, n - half)


@jit
def _reduceat(x: F64, start: int, n: int) -> float:
    """The sum of x[start:start + n] (n >= 1) as numpy's add.reduceat gives it: the first
    term plus the pairwise sum of the rest."""
    return float(x[start]) + _pairwise(x, start + 1, n - 1)


@jit
def _states(pc: F64, offsets: I64, s0: int, s1: int, row0: int, stay: F64, on: Bools,
            on0: int, ocol: I64, stuck: float, reached: float, mean: bool, sign: F64,
            out: F64, best: Ints, picked: Ints, pcol: I64) -> None:
    """The values of states s0..s1 (`out[s, q]` for each query q) from their choices', as
    acyclic.settle gives them. State s's choices are rows offsets[s] - row0 to
    offsets[s + 1] - row0 of `pc` and of `stay` (their self-loops; empty if none loops);
    row s - on0 of `on` says which targets it is on, column ocol[q] query q's; `sign[q]`
    is 1 for a min, -1 for a max (the min of the negated values, as numpy takes it);
    with `best` (not empty), its first optimal choice is written at best[s, q]; with
    `picked` (not empty), it takes the choice picked[s, pcol[q]]. Only scalars are
    passed to helpers in the loop over states: a call with arrays costs more than a
    state's work."""
    k = len(sign)
    cur = np.empty(k)
    loops = len(stay) > 0
    for s in range(s0, s1):
        c0, c1 = offsets[s] - row0, offsets[s + 1] - row0
        if mean:
            _mean(pc, c0, c1, stay, stuck, cur)
        elif len(picked):
            for q in range(k):
                c = c0 + picked[s, pcol[q]]
                cur[q] = _left(pc[c, q], stay[c] if loops else 0.0, stuck)
        else:
            for c in range(c0, c1):
                loop = stay[c] if loops else 0.0
                for q in range(k):
                    y = _left(pc[c, q], loop, stuck) * sign[q]
                    if c == c0 or y < cur[q] or y != y:  # numpy's minimum keeps a NaN
                        cur[q] = y
            for q in range(k):
                cur[q] *= sign[q]
        if len(best) and not mean:
            for q in range(k):
                best[s, q] = 0
                for c in range(c0, c1):
                    if _left(pc[c, q], stay[c] if loops else 0.0, stuck) == cur[q]:
                        best[s, q] = c - c0
                        break
        for q in range(k):
            out[s, q] = reached if on[s - on0, ocol[q]] else cur[q]


@jit
def _left(x: float, loop: float, stuck: float) -> float:
    """A choice's value `x` once its self-loop of probability `loop` is solved: divided by
    1 - loop, `stuck` if it only loops."""
    if loop >= 1.0:
        return stuck
    if loop != 0.0:
        return x / (1.0 - loop)
    return x


@jit
def _mean(pc: F64, c0: int, c1: int, stay: F64, stuck: float, cur: F64) -> None:
    """The uniform DTMC's value of a state (`cur[q]` per query) from its choices' rows
    c0..c1 of `pc`: their sum over (their number less their self-loops' probabilities),
    `stuck` if they only loop; each sum as numpy's add.reduceat gives it (the first row
    plus the pairwise sum of the others: a plain loop below 9 rows)."""
    size = c1 - c0
    k = len(cur)
    leave = float(size)
    if len(stay):
        if size > 8:
            leave = size - (float(stay[c0]) + _pairwise(stay, c0 + 1, size - 1))
        else:
            rest = 0.0
            for c in range(c0 + 1, c1):
                rest += stay[c]
            leave = size - (stay[c0] + rest)
    if size > 8:
        for q in range(k):
            cur[q] = float(pc[c0, q]) + _pairwise(pc[:, q], c0 + 1, size - 1)
    else:
        for q in range(k):
            cur[q] = 0.0
        for c in range(c0 + 1, c1):
            for q in range(k):
                cur[q] += pc[c, q]
        for q in range(k):
            cur[q] = pc[c0, q] + cur[q]
    for q in range(k):
        cur[q] = stuck if leave <= 0.0 else cur[q] / leave


@jit
def settle(pc: F64, stay: F64, offsets: I64, on: Bools, stuck: float, reached: float,
           mean: bool, sign: F64, best: Ints, picked: Ints) -> F64:
    """acyclic.settle's values of a span's states (states x queries) from their choices'
    (`pc`, choices x queries; `stay` empty if no choice loops, `best` and `picked` empty
    when not asked)."""
    n, k = len(offsets) - 1, pc.shape[1]
    out = np.empty((n, k))
    cols = np.arange(k)
    _states(pc, offsets, 0, n, 0, stay, on, 0, cols, stuck, reached, mean, sign, out, best,
            picked, cols)
    return out


CHUNK = 1024  # states whose choices' values are computed before they are settled


@jit
def span(lo: int, hi: int, states: I64, choices: I64, target: Ints, table: F64, codes: Ints,
         value: F64, reward: F64, rcol: I64, stay: F64, on: Bools, ocol: I64, stuck: float,
         reached: float, mean: bool, sign: F64, best: Ints, picked: Ints,
         pcol: I64) -> None:
    """The values of states lo..hi (one span of a layer) written into `value` (n x
    queries), as acyclic._pass's numpy code gives them: CHUNK states at a time, their
    choices' values (0, plus each branch's probability times its successor's value in
    the branches' order, plus the choice's reward), then :func:`_states`. A branch b's
    probability is table[codes[b]], or table[b] when `codes` is empty; `reward` (the
    span's choices x reward models, none if it has no column) gives query q its column
    rcol[q]; `on` (the span's states x targets) its column ocol[q]; `stay` is the span's
    choices' self-loops (empty: none loops). `best` and `picked` (empty when not asked)
    are indexed by state number."""
    k = value.shape[1]
    c_lo = states[lo]
    coded = len(codes) > 0
    most = 0
    for s0 in range(lo, hi, CHUNK):
        most = max(most, states[min(s0 + CHUNK, hi)] - states[s0])
    pc = np.empty((most, k))
    for s0 in range(lo, hi, CHUNK):
        s1 = min(s0 + CHUNK, hi)
        row0 = states[s0]
        for c in range(row0, states[s1]):
            row = c - row0
            for q in range(k):
                pc[row, q] = 0.0
            for b in range(choices[c], choices[c + 1]):
                p = table[codes[b]] if coded else table[b]
                t = target[b]
                for q in range(k):
                    pc[row, q] += p * value[t, q]
            if reward.shape[1]:
                for q in range(k):
                    pc[row, q] += reward[c - c_lo, rcol[q]]
        _states(pc, states, s0, s1, row0,
                stay[row0 - c_lo:states[s1] - c_lo] if len(stay) else stay, on, lo, ocol,
                stuck, reached, mean, sign, value, best, picked, pcol)


@jit
def distinct_successors(states: I64, choices: I64, target: Ints) -> int:
    """The number of distinct (state, successor) pairs over all choices: `stamp[t]` is the
    last state that had t as a successor, so each pair counts once."""
    n = len(states) - 1
    stamp = np.full(n, -1, np.int32)  # a state number (fewer than 2^31)
    total = 0
    for s in range(n):
        for b in range(choices[states[s]], choices[states[s + 1]]):
            t = target[b]
            if stamp[t] != s:
                stamp[t] = s
                total += 1
    return total


@jit
def self_loops(states: I64, choices: I64, target: Ints, table: F64,
               codes: Ints) -> tuple[I64, F64]:
    """The choices that loop to their own state (ascending) and each one's probability of
    doing so (the sum of its looping branches, as numpy's add.reduceat gives it); a
    branch's probability as in :func:`span`. The output grows by doubling: few choices
    loop, and a count first would read every branch twice."""
    coded = len(codes) > 0
    most = 1
    for c in range(len(choices) - 1):
        most = max(most, choices[c + 1] - choices[c])
    buf = np.empty(most)
    at = np.empty(1024, np.int64)
    sums = np.empty(1024)
    i = 0
    for s in range(len(states) - 1):
        for c in range(states[s], states[s + 1]):
            here = 0
            for b in range(choices[c], choices[c + 1]):
                if target[b] == s:
                    buf[here] = table[codes[b]] if coded else table[b]
                    here += 1
            if here:
                if i == len(at):
                    at = np.concatenate((at, np.empty_like(at)))
                    sums = np.concatenate((sums, np.empty_like(sums)))
                at[i] = c
                sums[i] = _reduceat(buf, 0, here)
                i += 1
    return at[:i].copy(), sums[:i].copy()


def table_codes(prob: Vec) -> tuple[F64, npt.NDArray[np.unsignedinteger[Any]]]:
    """A probability vector as a kernel reads it: branch b's probability is
    table[codes[b]], or table[b] where `codes` is empty (a plain array)."""
    from afsmc.verify.arrays.acyclic import Coded

    if isinstance(prob, Coded):
        return prob.table, prob.codes
    return np.asarray(prob[0:len(prob)], np.float64), np.zeros(0, np.uint8)


def stepper(a: Arrays, qs: list[Query], best: Ints | None, value: F64,
            policy: Policy | None) -> Callable[[int, int], None]:
    """acyclic._pass's step by :func:`span`: solves the states lo..hi of a layer into
    `value` (and `best`), visiting each branch once per query and building no matrix.
    Each distinct target and reward model is sliced once per span, the queries pointing
    at their columns."""
    from afsmc.verify.arrays.acyclic import LABEL, Sense

    k = len(qs)
    sense = Sense.of(qs)
    table, codes = table_codes(a.prob)
    targets = sorted({q.target for q in qs})
    labels = [a.labels[LABEL + str(t)] for t in targets]
    ocol = np.array([targets.index(q.target) for q in qs], np.int64)
    names = sorted({q.reward for q in qs}) if qs[0].kind == "R" else []
    rewards = [a.rewards[r] for r in names]
    rcol = np.array([names.index(q.reward) if names else 0 for q in qs], np.int64)
    sign = np.where(sense.low, 1.0, -1.0)
    no_best = np.zeros((0, k), np.int32)
    picked = np.zeros((0, 1), np.int32) if policy is None else policy.offsets
    pcol = np.zeros(k, np.int64) if policy is None else np.asarray(policy.columns, np.int64)

    def step(lo: int, hi: int) -> None:
        c0, c1 = int(a.states[lo]), int(a.states[hi])
        reward = (np.stack([r[c0:c1] for r in rewards], axis=1) if rewards
                  else np.zeros((0, 0)))
        stay = np.zeros(0) if a.stay is None else np.asarray(a.stay[c0:c1], np.float64)
        on = np.stack([t[lo:hi] for t in labels], axis=1)
        span(lo, hi, a.states, a.choices, a.target, table, codes, value, reward, rcol, stay,
             on, ocol, sense.stuck, sense.reached, sense.mean, sign,
             no_best if best is None else best, picked, pcol)

    return step


def settled(per_choice: F64, stay: Vec | None, offsets: I64, on: Bools, sense: Sense,
            best: Ints | None, picked: Ints | None) -> F64:
    """acyclic.settle by the :func:`settle` kernel (its arguments, the same values)."""
    k = per_choice.shape[1]
    out: F64 = settle(per_choice, np.zeros(0) if stay is None else np.asarray(stay, np.float64),
                      offsets, on, sense.stuck, sense.reached, sense.mean,
                      np.where(sense.low, 1.0, -1.0),
                      np.zeros((0, k), np.int32) if best is None else best,
                      np.zeros((0, k), np.int32) if picked is None else picked)
    return out
