"""Strategies and witnesses from the streamed layers (afsmc.verify.stream.layers): what
afsmc.verify.engines.strategy_arrays gives on the in-memory arrays, from the files of the
same exploration, so that a strategy or a witness asks for no exploration of its own.

Three steps, each reading the files once:

1. *Backward* (sweep.run with :class:`Kept`): every query's value (in one sweep where
   they fit sweep.sweep_bytes(), else the asked ones apart), and per file,
   in a file of its own (``x`` + the file's name), each state's first optimal choice per
   asked query; for a summarised strategy, whether the state's choices differ in value (as
   strategy_arrays._matters says it); for a witness's query, whether the state reaches the
   target (its value is above 0) and `h`, the largest probability of one path from it into
   the target under the strategy.
2. *Forward* (:func:`forward`), the files in exploration order (the buckets from the first,
   each from its last layer; the late states; the sinks): per asked query, the states its
   strategy reaches and their decisions, summarised (groups) or whole (the policy); for a
   witness, `dist`, the largest probability of one path from the initial state to each
   state, as strategy_arrays._Paths computes it.
3. *A witness's paths* (:func:`witness`): every state on a path of probability at least
   tau has dist x h >= tau, so the k most probable paths are those of the sub-model of
   such states once the k-th of them has probability tau or more; tau starts at the k-th
   largest dist of a target state (the most probable paths into k distinct targets reach
   that far). The sub-model, gathered by one more forward read, is searched by
   strategy_arrays._Paths, its ties falling by the states' keys as on the in-memory
   arrays; a path outside it ranks after every path inside, so the first k are the same.
   Where fewer than k paths are found above tau, tau is lowered (at last to 0: every state
   that reaches the target) and the sub-model gathered again.

Memory: per asked query a byte per state (reached), for a witness 8 bytes per state
(dist); the live rows of `h` beside the sweep's values; the sub-model of the witness.
"""

from __future__ import annotations

import itertools
import time
from collections.abc import Callable, Iterator
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import numpy.typing as npt

from afsmc.verify import kernels
from afsmc.verify.arrays import acyclic
from afsmc.verify.arrays.acyclic import F64, I64, Query
from afsmc.verify.engines import strategy_arrays
from afsmc.verify.engines.strategy_storm import SAME, Extract, Extracted, Group, _groups
from afsmc.verify.stream import sweep
from afsmc.verify.stream.layers import Streamed, opened, smallest, widen
from afsmc.verify.stream.sweep import Part, Rows

# A view of some states, from their keys and their choices' commands
ViewOf = Callable[[I64, Any], strategy_arrays.View]
Notify = Callable[[str, Any], None]


@dataclass
class _Column:
    """An asked query's place: its group and column in the sweep, its number among the
    asked ones, its reward model among the files' (R), whether its strategy is
    summarised (its choices' differences kept) and, for the witness, its target."""

    query: Query
    g: int
    j: int
    index: int
    reward: int | None
    summarised: bool
    witness: int | None


def columns(queries: list[Query], groups: list[sweep.Group], extract: Extract
            ) -> list[_Column]:
    """Where each asked query sits in the sweep's groups."""
    w = extract.witness
    out = []
    for g, grp in enumerate(groups):
        for j, q in enumerate(grp.queries):
            if q.name not in extract.queries:
                continue
            out.append(_Column(q, g, j, queries.index(q),
                               None if grp.reward is None else grp.reward[j],
                               q.name in extract.strategies,
                               q.target if w is not None and w.query == q.name else None))
    return out


class Kept:
    """The backward sweep's keeper (sweep.Keep): each file's optimal choices, choices'
    differences and, for the witness, `h` and whether each state reaches the target,
    saved as ``x`` + the file's name; `h` of the live states in rows beside the values."""

    def __init__(self, st: Streamed, cols: list[_Column], rows: int) -> None:
        self.st, self.cols = st, cols
        self.by_group: dict[int, list[_Column]] = {}
        for c in cols:
            self.by_group.setdefault(c.g, []).append(c)
        self.h_live = np.zeros(rows)
        self.h_other = np.zeros(st.sinks + st.late)
        self.name = ""
        self.arrays: dict[str, npt.NDArray[Any]] = {}
        self.fast = kernels.enabled(st.states)  # the choices' differences compiled

    def begin(self, name: str, part: Part, reg: list[F64] | None, other: list[F64],
              at: int | Rows) -> None:
        self.name, self.part, self.reg, self.other, self.at = name, part, reg, other, at
        n = len(part.states) - 1
        self.arrays = {}
        for c in self.cols:
            self.arrays[f"best{c.index}"] = np.zeros(n, np.int64)
            if c.summarised:
                self.arrays[f"matters{c.index}"] = np.zeros(n, bool)
            if c.witness is not None:
                self.arrays["h"], self.arrays["alive"] = np.zeros(n), np.zeros(n, bool)

    def _own(self, lo: int, hi: int) -> tuple[bool, I64]:
        """Where the states lo..hi of the file keep their values: live rows (True) or
        the other values' rows (False)."""
        if isinstance(self.at, int):
            return False, np.arange(self.at + lo, self.at + hi, dtype=np.int64)
        return True, np.asarray(self.at[lo:hi], np.int64)

    def _successors(self, values: tuple[F64 | None, F64], branches: slice | I64) -> F64:
        """Each branch's successor's entry of `values` (live, other)."""
        reg, oth = self.part.reg[branches], self.part.oth[branches]
        live, other = values
        got = other[np.maximum(oth, 0)]
        if live is not None:
            got = np.where(reg >= 0, live[np.maximum(reg, 0)], got)
        out: F64 = got
        return out

    def span(self, g: int, lo: int, hi: int, best: I64) -> None:
        for c in self.by_group.get(g, []):
            self.arrays[f"best{c.index}"][lo:hi] = best[:, c.j]
            live = None if self.reg is None else self.reg[g][:, c.j]
            values = (live, self.other[g][:, c.j])
            if c.summarised:
                self.arrays[f"matters{c.index}"][lo:hi] = self._matters(c, lo, hi, values)
            if c.witness is not None:
                self._reach(c, lo, hi, best[:, c.j], values)

    def _matters(self, c: _Column, lo: int, hi: int, values: tuple[F64 | None, F64]
                 ) -> npt.NDArray[np.bool_]:
        """Whether the choices of the states lo..hi differ in value: strategy_arrays'
        _differ, on the values of their successors (their own ones in place)."""
        p = self.part
        if self.fast:
            from afsmc.verify.kernels import streamed

            out = np.zeros(hi - lo, bool)
            streamed.differ(p.states, p.choices, p.reg, p.oth, p.prob,
                            np.zeros(0) if values[0] is None else values[0], values[1],
                            np.zeros(0) if c.reward is None else p.rewards[c.reward],
                            lo, hi, SAME, out)
            return out
        c0, c1 = int(p.states[lo]), int(p.states[hi])
        b0, b1 = int(p.choices[c0]), int(p.choices[c1])
        v = self._successors(values, slice(b0, b1))
        per_branch = p.prob[b0:b1] * np.where(np.isfinite(v), v, 1e300)
        sizes = np.diff(p.choices[c0:c1 + 1])
        starts = np.concatenate(([0], np.cumsum(sizes)[:-1])).astype(np.int64)
        per_choice = np.add.reduceat(per_branch, starts) if len(per_branch) else per_branch
        if c.reward is not None and c1 > c0:
            per_choice = per_choice + p.rewards[c.reward][c0:c1]
        offsets = p.states[lo:hi + 1] - c0
        some = np.diff(offsets) > 0  # a state without a choice decides nothing
        out = np.zeros(hi - lo, bool)
        if some.any():
            first = offsets[:-1][some]
            low = np.minimum.reduceat(per_choice, first)
            high = np.maximum.reduceat(per_choice, first)
            out[some] = np.abs(high - low) > SAME * np.maximum(
                1.0, np.maximum(np.abs(high), np.abs(low)))
        return out

    def _reach(self, c: _Column, lo: int, hi: int, best: I64,
               values: tuple[F64 | None, F64]) -> None:
        """The witness's `h` and "reaches the target" of the states lo..hi."""
        p = self.part
        live, rows = self._own(lo, hi)
        h_own = self.h_live if live else self.h_other
        h_own[rows] = 0.0  # a self-loop never improves a path: its own h counts as 0
        own_values = (values[0] if live else values[1])
        assert own_values is not None
        alive = own_values[rows] > 0
        chosen = p.states[lo:hi] + best
        b0, b1 = p.choices[chosen], p.choices[chosen + 1]
        br = acyclic._ranges(b0, b1)
        owner = np.repeat(np.arange(hi - lo, dtype=np.int64), b1 - b0)
        h = np.zeros(hi - lo)
        np.maximum.at(h, owner, p.prob[br] * self._successors((self.h_live, self.h_other), br))
        assert c.witness is not None
        on = p.labels[c.witness][lo:hi]
        h = np.where(on, 1.0, np.where(alive, h, 0.0))
        h_own[rows] = h
        self.arrays["h"][lo:hi] = h
        self.arrays["alive"][lo:hi] = alive | on

    def end(self) -> None:
        out: dict[str, npt.NDArray[Any]] = {}
        for k, v in self.arrays.items():
            out[k] = smallest(v) if k.startswith("best") else \
                np.packbits(v) if v.dtype == bool else v
        self.st.scratch.save("x" + self.name, False, **out)


@dataclass
class _File:
    """One file as the forward steps read it: its states' global numbers (regular ones
    from 0, the sinks and late states after them), their choices and branches (each
    branch's successor as a global number), its layers, its states' keys, its choices'
    commands and labels, and its kept arrays (Kept)."""

    own: I64
    states: I64
    choices: I64
    succ: I64
    prob: F64
    layers: I64
    keys: I64
    command: I64
    labels: list[npt.NDArray[np.bool_]]
    kept: dict[str, npt.NDArray[Any]]

    def best(self, index: int) -> I64:
        out: I64 = self.kept[f"best{index}"].astype(np.int64)
        return out

    def bools(self, name: str) -> npt.NDArray[np.bool_]:
        out: npt.NDArray[np.bool_] = np.unpackbits(
            self.kept[name], count=len(self.own)).astype(bool)
        return out


def _files(st: Streamed, notify: Notify | None = None, what: str = "") -> Iterator[_File]:
    """The files in exploration order: the buckets, the late states, the sinks; with
    `notify`, a progress line now and then saying how many are read for `what`."""
    regular = sum(st.size)
    late = sweep.late_index(st)

    def read(name: str, first: int, base: int, keys: I64) -> _File:
        a = opened(st.scratch.load(name))
        target = widen(a["target"], first)
        if "late_at" in a:
            target[a["late_at"]] = -1 - sweep.late_numbers(st, *late, a["late_key"])
        n = len(a["nchoice"])
        labels = [a[k] for k in sorted((k for k in a if k.startswith("label")),
                                       key=lambda k: int(k[5:]))]
        return _File(base + np.arange(n, dtype=np.int64), sweep._offsets(a["nchoice"]),
                     sweep._offsets(a["nbranch"]),
                     np.where(target >= 0, target, regular - 1 - target), st.table[a["prob"]],
                     sweep._offsets(a["layers"]), keys, a.get("command", np.zeros(0)).astype(np.int64),
                     labels, st.scratch.load("x" + name))

    def every() -> Iterator[_File]:
        for i, first in enumerate(st.start):
            yield read(f"b{i}", first, first, st.scratch.load(f"keys{i}")["keys"])
        if st.late:
            yield read("late", 0, regular + st.sinks, st.late_keys)
        for i, first in enumerate(st.sink_start):
            yield read(f"s{i}", 0, regular + first, st.scratch.load(f"sk{i}")["keys"])

    files = len(st.start) + len(st.sink_start) + (1 if st.late else 0)
    shown = time.monotonic()
    for done, f in enumerate(every(), 1):
        yield f
        if notify is not None and time.monotonic() - shown > PROGRESS_EVERY:
            shown = time.monotonic()
            notify("solver", f"read {done:,} of {files:,} files forward for {what}")


def _chosen_branches(f: _File, states: I64, best: I64) -> tuple[I64, I64]:
    """The branches of the chosen choices of `states` (numbers in the file), and each
    branch's state."""
    ch = f.states[states] + best[states]
    b0, b1 = f.choices[ch], f.choices[ch + 1]
    return acyclic._ranges(b0, b1), np.repeat(states, b1 - b0)


def _initial(st: Streamed) -> int:
    return st.initial if st.initial >= 0 else sum(st.size) - 1 - st.initial


@dataclass
class _Decisions:
    """An asked query's decisions so far: the states its strategy reaches and, of those
    that decide, the groups (summarised) and the keys and commands (the policy)."""

    column: _Column
    reached: npt.NDArray[np.bool_]
    count: int = 0
    groups: dict[tuple[int, int, bool], Group] = field(default_factory=dict)
    keys: list[I64] = field(default_factory=list)
    commands: list[I64] = field(default_factory=list)


def forward(st: Streamed, cols: list[_Column], extract: Extract, view_of: ViewOf,
            out: Extracted, notify: Notify | None = None) -> tuple[F64 | None, F64]:
    """Step 2: every asked query's decisions into `out` (strategy_arrays._tables on the
    files); for a witness, every state's dist and the largest dists of its targets."""
    total = st.states
    decisions = [_Decisions(c, np.zeros(total, bool)) for c in cols
                 if c.query.name in extract.strategies or c.query.name == extract.policy]
    w = next((c for c in cols if c.witness is not None), None)
    dist = None if w is None else np.zeros(total)
    init = _initial(st)
    for d in decisions:
        d.reached[init] = True
    if dist is not None:
        dist[init] = 1.0
    decisive = np.asarray(extract.decisive, np.int64)
    tops = np.zeros(0)
    fast = kernels.enabled(total)
    for f in _files(st, notify, "the strategies"):
        bests = {c.index: f.best(c.index) for c in cols}
        alive = on = None
        if w is not None:
            assert w.witness is not None
            alive, on = f.bools("alive"), f.labels[w.witness]
        (_through_compiled if fast else _through)(f, decisions, bests, dist, alive, on, w)
        for d in decisions:
            _decide(f, d, bests[d.column.index], decisive, extract, view_of)
        if dist is not None:
            assert alive is not None and on is not None
            t = dist[f.own[on & alive]]
            tops = np.sort(np.concatenate((tops, t[t > 0])))[::-1][:max(1, _k(extract))]
    for d in decisions:
        name = d.column.query.name
        out.reached[name] = d.count
        if name in extract.strategies:
            out.groups[name] = [d.groups[k] for k in sorted(d.groups)]
        if name == extract.policy:
            keys = np.concatenate(d.keys) if d.keys else np.zeros(0, np.int64)
            commands = np.concatenate(d.commands) if d.commands else np.zeros(0, np.int64)
            order = np.argsort(keys, kind="stable")  # Storm's order: by key
            view = view_of(keys[order], commands[order])
            out.policy_states = [tuple(int(x) for x in row)
                                 for row in view.values(np.arange(len(keys), dtype=np.int64))]
            out.policy_commands = [int(x) for x in commands[order]]
    return dist, tops


def _through(f: _File, decisions: list[_Decisions], bests: dict[int, I64],
             dist: F64 | None, alive: npt.NDArray[np.bool_] | None,
             on: npt.NDArray[np.bool_] | None, w: _Column | None) -> None:
    """forward's steps through one file, from its last layer to its first: each
    strategy's reached states mark their chosen choices' successors reached, and the
    witness's dist is passed on (_relax)."""
    for lo, hi in reversed(list(itertools.pairwise(f.layers.tolist()))):
        for d in decisions:
            r = np.flatnonzero(d.reached[f.own[lo:hi]]) + lo
            if r.size:
                br, _ = _chosen_branches(f, r, bests[d.column.index])
                d.reached[f.succ[br]] = True
        if dist is not None and w is not None:
            assert alive is not None and on is not None
            _relax(f, lo, hi, dist, alive, on, bests[w.index])


def _through_compiled(f: _File, decisions: list[_Decisions], bests: dict[int, I64],
                      dist: F64 | None, alive: npt.NDArray[np.bool_] | None,
                      on: npt.NDArray[np.bool_] | None, w: _Column | None) -> None:
    """_through by the compiled kernels (streamed.follow and relax): the same marks and
    dists."""
    from afsmc.verify.kernels import streamed

    for d in decisions:
        streamed.follow(f.states, f.choices, f.succ, bests[d.column.index], f.layers, f.own,
                        d.reached)
    if dist is not None and w is not None:
        assert alive is not None and on is not None
        streamed.relax(f.states, f.choices, f.succ, f.prob, bests[w.index], f.layers, f.own,
                       dist, alive, on)


def _k(extract: Extract) -> int:
    return 0 if extract.witness is None else extract.witness.k


def _relax(f: _File, lo: int, hi: int, dist: F64, alive: npt.NDArray[np.bool_],
           on: npt.NDArray[np.bool_], best: I64) -> None:
    """dist of the successors of the layer lo..hi's states that lead somewhere: a path
    stops at its first target, and a self-loop never improves it. (A state that does
    not reach the target passes its dist on only to states that do not either.)"""
    s = np.flatnonzero((dist[f.own[lo:hi]] > 0) & alive[lo:hi] & ~on[lo:hi]) + lo
    if not s.size:
        return
    br, src = _chosen_branches(f, s, best)
    dst, own = f.succ[br], f.own[src]
    moving = dst != own
    np.maximum.at(dist, dst[moving], dist[own[moving]] * f.prob[br][moving])


def _decide(f: _File, d: _Decisions, best: I64, decisive: I64, extract: Extract,
            view_of: ViewOf) -> None:
    """The file's states reached by `d`'s strategy that decide: counted, summarised and
    kept for the policy as strategy_arrays._tables does."""
    r = np.flatnonzero(d.reached[f.own])
    if not r.size:
        return
    command = f.command[f.states[r] + best[r]]
    variant = np.where(np.isin(command, decisive), command, -1)
    keep = variant >= 0
    s, variant = r[keep], variant[keep]
    d.count += len(s)
    name = d.column.query.name
    if name in extract.strategies:
        view = view_of(f.keys, f.command)
        matters = f.bools(f"matters{d.column.index}")
        for i in range(0, len(s), strategy_arrays.CHUNK):
            part = s[i:i + strategy_arrays.CHUNK]
            for g in _groups(variant[i:i + strategy_arrays.CHUNK], view.values(part),
                             matters[part], view.variables):
                strategy_arrays._merge(d.groups, g)
    if name == extract.policy:
        d.keys.append(f.keys[s])
        d.commands.append(variant)


def _sub(st: Streamed, w: _Column, dist: F64, tau: float, notify: Notify | None = None
         ) -> acyclic.Arrays:
    """Step 3's sub-model: the states that reach the target with dist x h >= tau (all
    that reach it with dist > 0 for tau 0), each with its chosen choice's branches into
    such states, numbered so that successors come first (the reverse of the forward
    order), a layer for each file's layer; `order` the states' keys, `commands` their
    chosen choices' commands, the label "target" the witness's targets."""
    own, keys, command, target, layer = [], [], [], [], []
    src, dst, prob = [], [], []
    count = 0
    for f in _files(st, notify, "the witness's paths"):
        assert w.witness is not None
        alive = f.bools("alive")
        h, best = f.kept["h"], f.best(w.index)
        d = dist[f.own]
        pick = alive & (d > 0)
        if tau > 0:
            pick &= d * h >= tau * (1 - 1e-9)
        s = np.flatnonzero(pick)
        layers = len(f.layers) - 1
        if not s.size:
            count += layers
            continue
        # in forward order: the file's last layer first; each state's layer counted
        # across the files in that order
        at_layer = np.searchsorted(f.layers, s, side="right") - 1
        by = np.argsort(-at_layer, kind="stable")
        s = s[by]
        layer.append(count + layers - 1 - at_layer[by])
        count += layers
        br, at = _chosen_branches(f, s, best)
        own.append(f.own[s])
        keys.append(f.keys[s])
        command.append(f.command[f.states[s] + best[s]])
        target.append(f.labels[w.witness][s])
        src.append(f.own[at])
        dst.append(f.succ[br])
        prob.append(f.prob[br])
    return _numbered(own, keys, command, target, layer, src, dst, prob, _initial(st))


def _cat(parts: list[Any], kind: Any) -> Any:
    return np.concatenate(parts) if parts else np.zeros(0, kind)


def _numbered(own: list[I64], keys: list[I64], command: list[I64], target: list[Any],
              layer: list[I64], src: list[I64], dst: list[I64], prob: list[F64],
              initial: int) -> acyclic.Arrays:
    """The sub-model's arrays (see _sub), from its states in forward order."""
    g, k, c = _cat(own, np.int64), _cat(keys, np.int64), _cat(command, np.int64)
    on, lay = _cat(target, bool), _cat(layer, np.int64)
    s, d, p = _cat(src, np.int64), _cat(dst, np.int64), _cat(prob, np.float64)
    n = len(g)
    # numbers: the last in forward order first (its successors come before it)
    rev = np.arange(n - 1, -1, -1)
    order = np.argsort(g)
    sorted_g = g[order]

    def number(x: I64) -> tuple[I64, npt.NDArray[np.bool_]]:
        pos = np.minimum(np.searchsorted(sorted_g, x), max(n - 1, 0))
        hit = sorted_g[pos] == x if n else np.zeros(len(x), bool)
        return (n - 1 - order[pos]) if n else np.zeros(len(x), np.int64), hit

    ms, _ = number(s)
    md, inside = number(d)
    ms, md, p = ms[inside], md[inside], p[inside]
    by = np.argsort(ms, kind="stable")  # a state's branches together, in their order
    ms, md, p = ms[by], md[by], p[by]
    choices = np.zeros(n + 1, np.int64)
    np.cumsum(np.bincount(ms, minlength=n), out=choices[1:])
    lays = lay[rev]  # by number: ascending
    bounds = np.flatnonzero(np.concatenate(([True], lays[1:] != lays[:-1], [True])))
    init, hit = number(np.array([initial], np.int64))
    return acyclic.Arrays(np.arange(n + 1, dtype=np.int64), choices, md.astype(np.int32), p, None,
                          bounds.astype(np.int64), int(init[0]) if hit[0] else -1,
                          {"target": on[rev]}, {}, order=k[rev],
                          commands=c[rev].astype(np.int32))


def witness(st: Streamed, w: _Column, extract: Extract, value: float, dist: F64, tops: F64,
            view_of: ViewOf, out: Extracted, notify: Notify | None = None) -> None:
    """Step 3: the witness's paths into `out`, or why there are none."""
    q = w.query
    assert extract.witness is not None
    k = extract.witness.k
    out.witness_query = q.name
    if value == 0.0:
        what, under = (q.opt, f" under the {q.opt} strategy") if q.opt else ("probability", "")
        out.witness_note = f"the {what} is 0: no path reaches a target state{under}"
        return
    if not tops.size:
        out.witness_note = "no state the strategy reaches is a target state"
        return
    tau = float(tops[k - 1]) if len(tops) >= k else float(tops[-1]) * LOWER
    for attempt in range(TRIES + 1):
        if attempt == TRIES:
            tau = 0.0
        sub = _sub(st, w, dist, tau, notify)
        got = Extracted()
        n = len(sub.states) - 1
        assert sub.commands is not None and sub.order is not None
        strategy_arrays.paths_into(sub, np.arange(n, dtype=np.int64), np.ones(n, bool),
                                   sub.labels["target"], view_of(sub.order, sub.commands),
                                   k, got)
        if tau == 0.0 or (len(got.paths) == k and got.paths[-1].probability >= tau):
            break
        tau *= LOWER
    out.paths, out.witness_note = got.paths, got.witness_note


PROGRESS_EVERY = 2.0  # seconds between two progress lines of a forward read

# Where fewer than k paths are found above tau: tau times LOWER, at most TRIES times, then 0
LOWER = 1e-3
TRIES = 4


def run(st: Streamed, queries: list[Query], reward_names: list[str], targets: int,
        extract: Extract, view_of: ViewOf, out: Extracted, notify: Notify,
        progress: sweep.Progress | None = None) -> tuple[dict[str, float], int]:
    """Every query's value and the uniform DTMC's transitions (as sweep.run gives them),
    and the strategies and witness `extract` asks into `out`."""
    t0 = time.perf_counter()
    rows = sweep.live_rows(st)
    # every query in the one sweep that keeps the choices where their values fit the
    # bytes a sweep may take; else the asked ones there and the rest in sweeps of their own
    together = len(queries) * rows * 8 <= sweep.sweep_bytes()
    mine = queries if together else [q for q in queries if q.name in extract.queries]
    cols = columns(mine, sweep.groups_of(mine, reward_names), extract)
    kept = Kept(st, cols, rows)
    values, pairs = sweep.run(st, mine, reward_names, targets, progress, kept)
    del kept
    rest = [q for q in queries if q not in mine]
    if rest:
        more, counted = sweep.run(st, rest, reward_names, targets, progress)
        values, pairs = values | more, pairs + counted
    notify("solver", "the strategies' decisions read forward from the same layers")
    out.variables = view_of(np.zeros(0, np.int64), np.zeros(0, np.int64)).variables
    dist, tops = forward(st, cols, extract, view_of, out, notify)
    w = next((c for c in cols if c.witness is not None), None)
    if w is not None and dist is not None:
        witness(st, w, extract, values[w.query.name], dist, tops, view_of, out, notify)
    out.seconds += time.perf_counter() - t0
    return values, pairs
