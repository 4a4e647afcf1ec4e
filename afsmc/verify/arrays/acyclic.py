"""Every query of an acyclic model by one exact backward pass (inside the Storm process).

A mission whose clock only grows has a reduced model that is acyclic but for the self-loops
of its absorbing states. On such a model a reachability probability or an expected reward
is known state by state in reverse topological order: a state's value needs only its
successors', which are final by then. One visit per transition computes it exactly, against
the many sweeps of value iteration or the strongly connected components of Storm's
topological solver (one per state here).

How: Storm builds the sparse model and decides each query's target states (its own
semantics of labels and expressions); the model goes to numpy through Storm's binary export
(UMB: the matrix, labels and rewards as flat arrays; afsmc.verify.arrays.umb); the states are sorted into layers
(every successor of a state lies in an earlier layer), renumbered so that each layer's
states, choices and branches are contiguous, and each query is then one loop over the
layers, vectorised within each. A model with any other cycle, or a query of another shape
(bounded, until, cumulative), is left to Storm (:func:`plan`, :func:`load`). afsmc's own
exploration (afsmc.verify.engines.explicit) gives the same arrays without Storm.

Semantics follow Storm's: P [F T] is 1 on T; R [F T] is 0 on T and infinite where T is
missed with positive probability (under every scheduler for a min, under some for a max);
a choice that loops to its own state with probability s < 1 is solved exactly as
(value of its other branches) / (1 - s), one that only loops is 0 (P) or infinite (R).
"""

from __future__ import annotations

import contextlib
import ctypes
import itertools
from collections.abc import Callable, Iterator
from dataclasses import dataclass, field
from typing import Any, Literal, Protocol

import numpy as np
import numpy.typing as npt

from afsmc.verify import kernels

# the labels of each query's target states in the arrays (Storm's export adds them too)
LABEL = "__afsmc_target_"
F64 = npt.NDArray[np.float64]
I64 = npt.NDArray[np.int64]
Bools = npt.NDArray[np.bool_]
Idx = npt.NDArray[np.int32]  # state numbers (a model of 2^31 states or branches is Storm's)



@dataclass(frozen=True)
class Query:
    """One query the backward pass answers."""

    name: str
    kind: Literal["P", "R"]
    # "" on a DTMC; "mean" on an MDP: the DTMC that picks each state's choices uniformly
    # (the uniform resolution of interval constants, whose floor/ceil combinations are
    # exactly a state's choices), solved on the MDP's arrays
    opt: Literal["min", "max", "", "mean"]
    target: int  # index into the plan's target formulas
    reward: str  # the reward model's name ("" for P, or Storm's only reward model)


@dataclass
class Plan:
    queries: list[Query] = field(default_factory=list)
    targets: list[Any] = field(default_factory=list)  # Storm state formulas
    left: list[str] = field(default_factory=list)  # names of the queries left to Storm


def plan(names: list[str], props: list[Any], mdp: bool) -> Plan:
    """The queries of the form P [F T] and R [F T], with min/max on an MDP and without a
    bound to compare with; the others are left to Storm."""
    out = Plan()
    keys: dict[str, int] = {}
    for name, prop in zip(names, props, strict=True):
        f = prop.get_raw_formula()
        kind: Literal["P", "R"] | None = ("P" if f.is_probability_operator_formula else
                                          "R" if f.is_reward_operator_formula else None)
        sub = f.subformula if kind is not None else None
        opt: Literal["min", "max", ""] = ""
        if f.has_optimality_type:
            opt = "min" if str(f.optimality_type).upper().endswith("MINIMIZE") else "max"
        if kind is None or sub is None or f.has_bound or not sub.is_eventually_formula \
                or sub.is_bounded_until_formula or (mdp and not opt):
            out.left.append(name)
            continue
        target = sub.subformula
        key = str(target)
        if key not in keys:
            keys[key] = len(out.targets)
            out.targets.append(target)
        reward = ""
        if kind == "R" and f.has_reward_model_name():
            reward = str(f.reward_name)
        out.queries.append(Query(name, kind, opt if mdp else "", keys[key], reward))
    return out


class Vec(Protocol):
    """A float vector read by slices and index arrays: a numpy array, or a compact form."""

    def __getitem__(self, key: Any, /) -> Any: ...

    def __len__(self) -> int: ...


@dataclass
class Coded:
    """Floats stored as codes into a table of their distinct values (a model's
    probabilities take few values: 2 or 4 bytes a branch instead of 8, exactly)."""

    table: F64
    codes: npt.NDArray[np.unsignedinteger[Any]]

    def __getitem__(self, key: Any, /) -> Any:
        return self.table[self.codes[key]]

    def __len__(self) -> int:
        return len(self.codes)

    @property
    def nbytes(self) -> int:
        return int(self.table.nbytes + self.codes.nbytes)


@dataclass
class Sparse:
    """A float vector mostly 0: its non-zero entries (`at` sorted), read by slices."""

    size: int
    at: I64
    values: F64

    def __getitem__(self, key: Any, /) -> Any:
        if not isinstance(key, slice) or key.step not in (None, 1):
            raise TypeError("a Sparse vector is read by contiguous slices")
        lo, hi, _ = key.indices(self.size)
        out = np.zeros(max(hi - lo, 0))
        i, j = np.searchsorted(self.at, [lo, hi])
        out[self.at[i:j] - lo] = self.values[i:j]
        return out

    def __len__(self) -> int:
        return self.size

    @property
    def nbytes(self) -> int:
        return int(self.at.nbytes + self.values.nbytes)


def sparse_or_dense(size: int, at: I64, values: F64) -> Vec:
    """The vector of `values` at `at` (sorted), 0 elsewhere, in the smaller form."""
    if 2 * len(at) < size:
        return Sparse(size, at, values)
    out = np.zeros(size)
    out[at] = values
    return out


@dataclass
class Arrays:
    """A sparse model as flat arrays, states renumbered layer by layer (`layers[i]` is the
    first state of layer i; every successor of a state lies in an earlier layer, or is
    the state itself)."""

    states: I64  # state -> its first choice (n + 1 offsets)
    choices: I64  # choice -> its first branch (m + 1 offsets)
    target: Idx  # branch -> successor state
    prob: Vec  # branch -> probability (a strategy's extraction needs an array)
    stay: Vec | None  # choice -> probability of its self-loop (None: no self-loops)
    layers: I64  # layer boundaries (len = layers + 1)
    initial: int  # the initial state
    labels: dict[str, Bools]  # label -> states (targets)
    rewards: dict[str, Vec]  # reward model -> its reward per choice (state + action)
    # a strategy's (strategy_arrays), else None: each state's number in Storm's model (or
    # its key), each choice's action (into `action_names`) or command, packed labels
    order: I64 | None = None
    actions: npt.NDArray[np.uint32] | None = None
    commands: npt.NDArray[np.int32] | None = None
    action_names: list[str] = field(default_factory=list)
    packed: dict[str, npt.NDArray[np.uint8]] = field(default_factory=dict)

    @property
    def nbytes(self) -> int:
        parts: list[Any] = [self.states, self.choices, self.target, self.prob, self.stay,
                            *self.labels.values(), *self.rewards.values()]
        return sum(int(getattr(x, "nbytes", 0)) for x in parts)


def _ranges(starts: I64, ends: I64) -> I64:
    """The concatenation of arange(starts[i], ends[i])."""
    lens = ends - starts
    total = int(lens.sum())
    if total == 0:
        return np.zeros(0, np.int64)
    offsets = np.cumsum(lens) - lens
    out: I64 = np.arange(total, dtype=np.int64) + np.repeat(starts - offsets, lens)
    return out


def _state_of_branches(states: I64, choices: I64) -> Idx:
    """The state of each branch."""
    n = len(states) - 1
    per_choice = np.repeat(np.arange(n, dtype=np.int32), np.diff(states))
    out: Idx = np.repeat(per_choice, np.diff(choices))
    return out


def layers_of(states: I64, choices: I64, target: Idx) -> list[I64] | None:
    """States in layers (Kahn's algorithm, backwards, ignoring self-loops): layer 0 has no
    successor but itself, each later one only successors in earlier layers. None if the
    model has a cycle of more than one state."""
    n = len(states) - 1
    branch_state = _state_of_branches(states, choices)
    moving = target != branch_state
    src, dst = branch_state[moving], target[moving]
    del branch_state, moving
    pending = np.bincount(src, minlength=n)
    rev_ptr = np.zeros(n + 1, np.int64)
    np.cumsum(np.bincount(dst, minlength=n), out=rev_ptr[1:])
    rev_src = src[np.argsort(dst, kind="stable")]
    del src, dst
    out = []
    done = 0
    frontier = np.flatnonzero(pending == 0)
    while frontier.size:
        out.append(frontier)
        done += frontier.size
        preds = rev_src[_ranges(rev_ptr[frontier], rev_ptr[frontier + 1])]
        np.subtract.at(pending, preds, 1)
        ready = np.sort(preds[pending[preds] == 0])  # each as often as it was a predecessor
        frontier = ready[np.concatenate(([True], ready[1:] != ready[:-1]))] \
            if ready.size else ready
    return out if done == n else None


CHUNK = 1 << 22  # choices gathered at a time while renumbering (bounds the temporary arrays)


def renumber(states: I64, choices: I64, target: Idx, prob: F64,
             perm: I64) -> tuple[I64, I64, I64, Idx, F64, Idx]:
    """The model with its states in the order `perm` (new -> old): (state offsets, choice
    offsets, old choice of each new choice, new targets, probabilities, new number of each
    old state)."""
    n = len(perm)
    inv = np.empty(n, np.int32)
    inv[perm] = np.arange(n, dtype=np.int32)
    new_states = np.zeros(n + 1, np.int64)
    np.cumsum(np.diff(states)[perm], out=new_states[1:])
    old_choice = _ranges(states[perm], states[perm + 1])
    m = len(old_choice)
    new_choices = np.zeros(m + 1, np.int64)
    np.cumsum(np.diff(choices)[old_choice], out=new_choices[1:])
    new_target = np.empty(len(target), np.int32)
    new_prob = np.empty(len(prob))
    for c in range(0, m, CHUNK):
        old = old_choice[c:c + CHUNK]
        branch = _ranges(choices[old], choices[old + 1])
        lo, hi = new_choices[c], new_choices[min(c + CHUNK, m)]
        new_target[lo:hi] = inv[target[branch]]
        new_prob[lo:hi] = prob[branch]
    return new_states, new_choices, old_choice, new_target, new_prob, inv


def self_loops(states: I64, choices: I64, target: Idx, prob: Vec) -> Vec | None:
    """Each choice's probability of staying in its state (sparse where few choices loop);
    None if no choice loops. A slice of choices at a time (or by the compiled kernel,
    afsmc.verify.kernels.passes, on a large model)."""
    m = len(choices) - 1
    if kernels.enabled(len(states) - 1):
        from afsmc.verify.kernels import passes

        where, stays = passes.self_loops(states, choices, target, *passes.table_codes(prob))
        return sparse_or_dense(m, where, stays) if len(where) else None
    at: list[I64] = []
    sums: list[F64] = []
    for c in range(0, m, CHUNK):
        ids = np.arange(c, min(c + CHUNK, m), dtype=np.int64)
        state = np.searchsorted(states, ids, side="right") - 1
        b0, b1 = int(choices[ids[0]]), int(choices[ids[-1] + 1])
        owner = np.repeat(state, np.diff(choices[c:ids[-1] + 2]))
        loops = np.flatnonzero(target[b0:b1] == owner)
        del owner, state
        if loops.size == 0:
            continue
        choice = np.searchsorted(choices, loops + b0, side="right") - 1
        starts = np.flatnonzero(np.concatenate(([True], choice[1:] != choice[:-1])))
        at.append(choice[starts])
        sums.append(np.add.reduceat(prob[loops + b0], starts))
    if not at:
        return None
    return sparse_or_dense(m, np.concatenate(at), np.concatenate(sums))


# The most the values of one pass's queries take together: as much as the model's arrays
# (so that a pass at most doubles the memory), within these bounds.
GROUP_BYTES = (1 << 28, 1 << 31)


def solve(a: Arrays, q: Query) -> float:
    """The query's value in the initial state."""
    return solve_many(a, [q])[q.name]


@dataclass(frozen=True)
class Policy:
    """Memoryless schedulers: `offsets[s, i]` is the choice (number within state s) of
    scheduler i; `columns[j]` is the scheduler query j follows."""

    offsets: npt.NDArray[np.integer[Any]]
    columns: I64


def schedulers(a: Arrays, queries: list[Query]) -> tuple[list[float], npt.NDArray[np.int32]]:
    """Each query's value in the initial state and its optimal choices (n x queries, each
    state's first optimal choice, its number within the state), in the queries' order
    (the passes of :func:`with_schedulers`)."""
    best = np.zeros((len(a.states) - 1, len(queries)), np.int32)
    out = [0.0] * len(queries)
    column = {q.name: j for j, q in enumerate(queries)}
    for part, totals, got, _ in with_schedulers(a, queries):
        for j, (q, total) in enumerate(zip(part, totals, strict=True)):
            out[column[q.name]] = total
            best[:, column[q.name]] = got[:, j]
    return out, best


def with_schedulers(a: Arrays, queries: list[Query]
                    ) -> Iterator[tuple[list[Query], list[float], npt.NDArray[np.int32], F64]]:
    """The queries in passes of one kind, as many per pass as GROUP_BYTES allows: each
    pass's queries, their values in the initial state, each state's optimal choice for
    each (n x queries, its number within the state) and every state's value (n x
    queries)."""
    n = len(a.states) - 1
    most = _most(a, n, 12)
    groups: dict[str, list[Query]] = {}
    for q in queries:
        groups.setdefault(q.kind, []).append(q)
    for group in groups.values():
        for i in range(0, len(group), most):
            part = group[i:i + most]
            best = np.zeros((n, len(part)), np.int32)
            value = np.zeros((n, len(part)))
            totals = _pass(a, part, best, value)
            yield part, totals, best, value
            del best, value


def evaluate(a: Arrays, queries: list[Query], policy: Policy) -> list[float]:
    """Each query's value in the initial state under the scheduler of `policy` it
    follows (`policy.columns`, one per query), as many per pass as GROUP_BYTES allows."""
    n = len(a.states) - 1
    most = _most(a, n, 8)
    out: list[float] = []
    for i in range(0, len(queries), most):
        out += _pass(a, queries[i:i + most],
                     policy=Policy(policy.offsets, policy.columns[i:i + most]))
    return out


def _most(a: Arrays, n: int, per_state: int) -> int:
    """How many queries one pass takes, at `per_state` bytes per state and query."""
    return max(1, min(max(a.nbytes, GROUP_BYTES[0]), GROUP_BYTES[1]) // (per_state * max(n, 1)))


def under(a: Arrays, q: Query, policy: Policy) -> tuple[float, I64, F64]:
    """Query `q`'s value in the initial state under the one scheduler of `policy`, that
    scheduler's choice in each state (its number in `a`) and every state's value."""
    n = len(a.states) - 1
    value = np.zeros((n, 1))
    result = _pass(a, [q], None, value, policy)[0]
    chosen: I64 = policy.offsets[:, int(policy.columns[0])] + a.states[:-1]
    return result, chosen, value[:, 0]


def solve_many(a: Arrays, queries: list[Query]) -> dict[str, float]:
    """Each query's value in the initial state. Queries of the same kind share their
    passes (the values of each state side by side, a min and a max alike), as many at a
    time as GROUP_BYTES allows."""
    n = len(a.states) - 1
    most = _most(a, n, 8)
    groups: dict[tuple[str, bool], list[Query]] = {}
    for q in queries:
        groups.setdefault((q.kind, q.opt == "mean"), []).append(q)
    out: dict[str, float] = {}
    for group in groups.values():
        for i in range(0, len(group), most):
            part = group[i:i + most]
            out |= zip([q.name for q in part], _pass(a, part), strict=True)
    return {q.name: out[q.name] for q in queries}


def _pass(a: Arrays, qs: list[Query], best: npt.NDArray[np.integer[Any]] | None = None,
          value: F64 | None = None, policy: Policy | None = None) -> list[float]:
    """One pass over the layers for queries of one kind, from the absorbing states back
    to the initial one: per layer, the choices' values (their branches' probabilities
    times their successors' values), then each state's is the min or max over its
    choices. With `best` (n x queries): each state's first choice (number within the
    state) whose value is the optimum of each query, which is the choice Storm's
    topological solver keeps; with `value` (n x queries): every state's value. With
    `policy`, no optimum: each query's states take the choices of its policy. A large
    model's spans are solved by the compiled kernel (afsmc.verify.kernels.passes), a
    small one's by numpy (:func:`_numpy_step`), to the same values."""
    k, n = len(qs), len(a.states) - 1
    if value is None:
        value = np.zeros((n, k))
    assert not (qs[0].opt == "mean" and (best is not None or policy is not None))
    if kernels.enabled(n):
        from afsmc.verify.kernels import passes

        step = passes.stepper(a, qs, best, value, policy)
    else:
        step = _numpy_step(a, qs, best, value, policy)
    for i, (lo, hi) in enumerate(_spans(a.layers)):
        if i % TRIM_EVERY == TRIM_EVERY - 1:
            trim_heap()
        step(lo, hi)
    return [float(v) for v in value[a.initial]]


Step = Callable[[int, int], None]  # solves the states lo..hi of a layer into the values


def _numpy_step(a: Arrays, qs: list[Query], best: npt.NDArray[np.integer[Any]] | None,
                value: F64, policy: Policy | None) -> Step:
    """A span's states solved by numpy: the choices' values are one sparse product (a
    CSR matrix of the span's branches times the value matrix), then :func:`settle`."""
    from scipy.sparse import csr_matrix

    n = len(a.states) - 1
    on_target = [a.labels[LABEL + str(q.target)] for q in qs]
    reward = [a.rewards[q.reward] for q in qs] if qs[0].kind == "R" else None
    sense = Sense.of(qs)

    def step(lo: int, hi: int) -> None:
        c0, c1 = int(a.states[lo]), int(a.states[hi])
        b0, b1 = int(a.choices[c0]), int(a.choices[c1])
        rows = (a.choices[c0:c1 + 1] - b0).astype(np.int32 if b1 - b0 < 2**31 else np.int64)
        matrix = csr_matrix((a.prob[b0:b1], a.target[b0:b1], rows), shape=(c1 - c0, n))
        per_choice = np.asarray(matrix @ value)
        if reward is not None:
            per_choice += np.stack([r[c0:c1] for r in reward], axis=1)
        picked = None if policy is None else policy.offsets[lo:hi][:, policy.columns]
        value[lo:hi] = settle(per_choice, None if a.stay is None else a.stay[c0:c1],
                              a.states[lo:hi + 1] - c0,
                              np.stack([t[lo:hi] for t in on_target], axis=1), sense,
                              None if best is None else best[lo:hi], picked)

    return step


@dataclass(frozen=True)
class Sense:
    """What the queries of one pass share: their kind's value on the target and of a
    choice that only loops, whether they are means, and which are minima."""

    stuck: float  # a choice that only loops
    reached: float  # on the target
    mean: bool  # the uniform DTMC's (a pass's queries are all means or none)
    low: Bools  # per query: a min (else a max)

    @classmethod
    def of(cls, qs: list[Query]) -> Sense:
        mean = qs[0].opt == "mean"
        assert all(q.kind == qs[0].kind and (q.opt == "mean") == mean for q in qs)
        p = qs[0].kind == "P"
        return cls(0.0 if p else np.inf, 1.0 if p else 0.0, mean,
                   np.array([q.opt == "min" for q in qs]))


def settle(per_choice: F64, stay: Vec | None, offsets: I64, on: Bools, sense: Sense,
           best: npt.NDArray[np.integer[Any]] | None = None,
           picked: npt.NDArray[np.integer[Any]] | None = None) -> F64:
    """The values of a span of one layer's states, from their choices' (`per_choice`,
    choices x queries: each one's reward plus its branches' probabilities times their
    successors' values; `stay`: each choice's self-loop probability, None if none loops;
    `offsets`: the states' first choices and the end, from 0; `on`: states x queries, on
    the query's target). A self-loop of probability s < 1 divides the rest by 1 - s, one
    of 1 is `sense.stuck`; then each state's min or max over its choices (with `best`:
    each state's first optimal choice, written there), or its policy's choice
    (`picked`: states x queries, the choice's number within its state), or the mean."""
    k = per_choice.shape[1]
    if kernels.enabled(len(per_choice)):
        from afsmc.verify.kernels import passes

        return passes.settled(per_choice, stay, offsets, on, sense, best, picked)
    if sense.mean:
        per_state = _mean(per_choice, None if stay is None else np.asarray(stay, np.float64),
                          offsets, sense.stuck)
        out: F64 = np.where(on, sense.reached, per_state)
        return out
    if stay is not None:
        s = np.asarray(stay, np.float64)[:, None]
        if s.any():
            with np.errstate(divide="ignore", invalid="ignore"):
                per_choice = np.where(s >= 1.0, sense.stuck, per_choice / (1.0 - s))
    n = len(offsets) - 1
    low = sense.low
    if picked is not None:
        per_state = per_choice[offsets[:-1][:, None] + picked, np.arange(k)]
    elif len(per_choice) == n:
        per_state = per_choice
    else:
        # the optimum of each state's j-th choice (its last, past its count) over j:
        # elementwise, where numpy's reduceat or a min down a middle axis is slower
        first = offsets[:-1]
        last = offsets[1:] - 1
        signed = per_choice if low.all() else per_choice * np.where(low, 1.0, -1.0)
        per_state = signed[first]
        for j in range(1, int((last - first).max()) + 1):
            np.minimum(per_state, signed[np.minimum(first + j, last)], out=per_state)
        if not low.all():
            per_state *= np.where(low, 1.0, -1.0)
    if best is not None:
        for j in range(k):
            best[:, j] = _first_best(per_choice[:, j], per_state[:, j], offsets)
    out = np.where(on, sense.reached, per_state)
    return out


def _mean(per_choice: F64, stay: F64 | None, offsets: I64, stuck: float) -> F64:
    """Each state's value in the DTMC that picks its choices uniformly: the mean of its
    choices' values (`per_choice`: each one's reward and branches' probabilities times
    their successors' values, its self-loop left out; `offsets`: the states' first
    choices, and the end). With self-loops the state's value v solves v = mean(o) +
    mean(s) v, so v = sum(o) / (k - sum(s)) for k choices of self-loop probabilities s; a
    state that only loops is `stuck` (0 for P, infinite for R)."""
    sizes = np.diff(offsets)[:, None]
    total = np.add.reduceat(per_choice, offsets[:-1], axis=0)
    if stay is None or not stay.any():
        out: F64 = total / sizes
        return out
    leave = sizes - np.add.reduceat(stay, offsets[:-1])[:, None]
    with np.errstate(divide="ignore", invalid="ignore"):
        out = np.where(leave <= 0.0, stuck, total / leave)
    return out


TRIM_EVERY = 32  # spans solved between two trim_heap()


def trim_heap() -> None:
    """Give the C heap's free memory back to the system. The many mid-sized temporaries
    of a pass (or of an exploration), freed, leave free memory amid the heap that glibc
    keeps: 0.7 GB of a pass over scenario 2's 0.6 GB model, 1.2 GB of its exploration."""
    with contextlib.suppress(OSError, AttributeError):  # not glibc: nothing to do
        ctypes.CDLL("libc.so.6").malloc_trim(0)


SPAN = 1 << 18  # the most states of a layer solved at a time (bounds the temporaries)


def _spans(layers: I64) -> list[tuple[int, int]]:
    """The layers as ranges of states, the large ones cut into ranges of SPAN: the states
    of a layer do not depend on each other."""
    out = []
    for lo, hi in itertools.pairwise(layers.tolist()):
        out += [(k, min(k + SPAN, hi)) for k in range(lo, hi, SPAN)]
    return out


def _first_best(per_choice: F64, per_state: F64, offsets: I64) -> I64:
    """Each state's first choice (number within the state) whose value is the state's
    optimum (`offsets`: the states' first choices, and the end)."""
    sizes = np.diff(offsets)
    local = np.arange(len(per_choice), dtype=np.int64) - np.repeat(offsets[:-1], sizes)
    hit = per_choice == np.repeat(per_state, sizes)
    out: I64 = np.minimum.reduceat(np.where(hit, local, np.int64(1) << 40), offsets[:-1])
    return np.where(out == np.int64(1) << 40, 0, out)


def pick(v: Vec, at: I64) -> F64:
    """The entries `at` of a vector (a Sparse one's by a search in its sorted non-zeros)."""
    if isinstance(v, Sparse):
        out = np.zeros(len(at))
        if len(v.at):
            pos = np.minimum(np.searchsorted(v.at, at), len(v.at) - 1)
            hit = v.at[pos] == at
            out[hit] = v.values[pos[hit]]
        return out
    return np.asarray(v[at], np.float64)
