"""Schedulers and most probable paths from the exact backward pass (inside the Storm
process), without Storm's scheduler, its induced DTMC or its state valuations.

On a model that is acyclic but for self-loops (:mod:`afsmc.verify.arrays.acyclic`), the pass that
computes a query's values also gives each state's optimal choice: the first choice whose
value is the state's optimum, which is the choice Storm's topological solver keeps (its
trivial components are solved row by row, a later row replacing the best only if strictly
better). From those choices come the states the strategy reaches, their floor/ceil variants
and whether the choice matters there (the one-step values of the state's choices differ,
as Storm's `Rmin`/`Rmax [I=1]` with the values as state rewards). The K most probable
paths are found by the recursive enumeration algorithm with the choices of Storm's
generator (:func:`_Paths`), on the strategy's transitions only.

The arrays come from one of two places, each read through a :class:`View`:

* afsmc's own exploration (:mod:`afsmc.verify.engines.explicit`, the default): each state's key
  gives its variables' values, each choice's lowered command is kept as explored, and the
  choices of a state are in Storm's order, so the same choice is the first optimal one;
* Storm's export (:func:`run`, where the exploration gives up): each choice's action
  label names its variant, and the variables' values are read from one label per bit of
  each variable, which Storm builds at a byte per 8 states, instead of its state
  valuations (a vector per state: 1.7 GB more on scenario 2).

Only what this route covers is sent here (:func:`covers`): strategies of probabilities
and expected rewards of `F target` without a bound, witnesses of those probabilities (not
into other target states). The rest, and a model with cycles,
stays on Storm's route (:mod:`afsmc.verify.engines.strategy_storm`).
"""

from __future__ import annotations

import itertools
import time
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np
import numpy.typing as npt

from afsmc.verify.arrays import acyclic, umb
from afsmc.verify.engines.strategy_storm import SAME, Extract, Extracted, Group, RawPath, _groups

I64 = npt.NDArray[np.int64]
BIT = "__afsmc_bit_"  # the labels of the variables' bits


def fits(extract: Extract, names: list[str], props: list[Any]) -> bool:
    """Whether every query `extract` asks of is a P [F T] with min or max that the
    backward pass answers, and the witness (if any) goes into that T."""
    return covers(extract, acyclic.plan(names, props, True).queries)


def covers(extract: Extract, queries: list[acyclic.Query]) -> bool:
    """Whether the backward pass of `queries` gives all that `extract` asks."""
    kinds = {q.name: q.kind for q in queries}
    w = extract.witness
    if w is not None and (w.target is not None or w.avoid):
        return False
    # a strategy (or the policy) of a probability or an expected reward: the pass's first
    # optimal choice; a witness: paths into the target of a probability only
    return all(kinds.get(q) == "P" if w is not None and q == w.query
               else kinds.get(q) in ("P", "R") and (q in extract.strategies or q == extract.policy)
               for q in extract.queries)


def _bit_vars(program: Any) -> list[tuple[str, int, int, bool]] | None:
    """Each variable of the generated model (the order of Storm's valuations in
    strategy_storm): name, lower bound, bits, boolean; None if a bound is not a number."""
    out = []
    for module in program.modules:
        for v in module.integer_variables:
            try:
                lo = int(v.lower_bound_expression.evaluate_as_int())
                hi = int(v.upper_bound_expression.evaluate_as_int())
            except RuntimeError:
                return None
            out.append((v.name, lo, (hi - lo).bit_length(), False))
        out += [(v.name, 0, 1, True) for v in module.boolean_variables]
    return out


def _bit_texts(variables: list[tuple[str, int, int, bool]]) -> list[str]:
    """A state formula per bit: bit k of (value - lower bound)."""
    out = []
    for name, lo, bits, boolean in variables:
        if boolean:
            out.append(name)
            continue
        shifted = name if lo == 0 else f"({name} - ({lo}))"
        out += [f"mod({shifted}, {2 ** (k + 1)}) >= {2 ** k}" for k in range(bits)]
    return out


def options(stormpy: Any, formulas: list[Any], program: Any) -> Any | None:
    """Storm's builder options for this route: the properties' formulas and one label per
    bit of each variable, choice labels, no state valuations; None if the variables'
    bounds are not numbers."""
    variables = _bit_vars(program)
    if variables is None:
        return None
    bits = [p.get_raw_formula() for p in stormpy.parse_properties(
        ";".join(f"P=? [ F ({t}) ]" for t in _bit_texts(variables)), program)] \
        if variables else []
    opts = stormpy.BuilderOptions(formulas + bits)
    opts.set_build_choice_labels()
    opts.set_build_all_labels()
    return opts


def _label_bits(stormpy: Any, model: Any, program: Any) -> tuple[str, ...]:
    """Label each bit's states in Storm's model (BIT + number); the labels."""
    texts = _bit_texts(_bit_vars(program) or [])
    names = []
    for i, prop in enumerate(stormpy.parse_properties(
            ";".join(f"P=? [ F ({t}) ]" for t in texts), program) if texts else []):
        states = stormpy.model_checking(
            model, prop.get_raw_formula().subformula.subformula).get_truth_values_vector()
        name = BIT + str(i)
        if not model.labeling.contains_label(name):
            model.labeling.add_label(name)
        model.labeling.set_states(name, states)
        names.append(name)
    return tuple(names)


def valuations(a: acyclic.Arrays, program: Any, states: I64) -> I64:
    """The variables' values of `states` (the pass's numbers), states x variables."""
    assert a.order is not None
    old = a.order[states]
    byte, shift = old >> 3, (old & 7).astype(np.uint8)
    variables = _bit_vars(program) or []
    out = np.zeros((len(states), len(variables)), np.int64)
    i = 0
    for j, (_, lo, bits, _) in enumerate(variables):
        col = np.full(len(states), lo, np.int64)
        for k in range(bits):
            bit = (a.packed[BIT + str(i)][byte] >> shift) & 1
            col += bit.astype(np.int64) << k
            i += 1
        out[:, j] = col
    return out


@dataclass
class View:
    """How an extraction reads its arrays: the variables' names ("mode" among them), the
    values of some states (states x variables), each choice's floor/ceil variant (its
    lowered command; -1: not a variant) and a choice's lowered command (given the values
    of its state)."""

    variables: tuple[str, ...]
    values: Callable[[I64], I64]
    variant: Callable[[I64], I64]
    command: Callable[[int, Any], int]


def storm_view(a: acyclic.Arrays, program: Any, extract: Extract) -> View:
    """The view of arrays from Storm's export: the choices' action labels name the
    commands, the bit labels give the values."""
    assert a.actions is not None
    actions = a.actions
    index = {x: i for i, x in enumerate(a.action_names)}
    table = np.full(len(a.action_names), -1, np.int64)
    for c, label in zip(extract.decisive, extract.labels, strict=True):
        if label in index:
            table[index[label]] = c
    variables = tuple(v[0] for v in _bit_vars(program) or [])

    def command(choice: int, row: Any) -> int:
        label = a.action_names[int(actions[choice])]
        mode = int(row[variables.index("mode")]) if "mode" in variables else 0
        for i, (name, modes) in enumerate(extract.commands):
            if mode in modes and name == label:
                return i
        return -1

    return View(variables, lambda states: valuations(a, program, states),
                lambda choices: table[actions[choices]], command)


Rebuild = Callable[[], Any]


def run(stormpy: Any, built: Any, res: Any, notify: Callable[[str, Any], None], job: Any,
        program: Any, rebuild: Rebuild) -> bool:
    """Check the job's queries by backward passes and extract what `job.extract` asks from
    them; False if the model has cycles (it is then built again, for Storm's route)."""
    extract: Extract = job.extract
    if _bit_vars(program) is None:  # built with state valuations: Storm's route
        return False
    p = acyclic.plan(built.names, built.props, res.kind == "mdp")
    notify("phase", "acyclic")
    started = time.perf_counter()
    raw = umb.read(stormpy, built.model, p, _label_bits(stormpy, built.model, program))
    built.model = None  # one model in memory at a time: the arrays hold all it needs
    _give_back()
    arrays = None if raw is None else umb.arrange(raw)
    del raw
    if arrays is None or arrays.order is None:
        # built again with state valuations, rather than kept for a case this rare
        notify("solver", f"the {job.what} has cycles: Storm's topological solver checks it")
        notify("phase", "build")
        built.model = rebuild()
        return False
    notify("solver", f"the {job.what} is acyclic but for self-loops "
           f"({len(arrays.layers) - 1:,} layers): each query by one exact backward pass")
    out = res.extracted = res.extracted or Extracted()
    values = solve(arrays, p.queries, extract, storm_view(arrays, program, extract), out,
                   notify)
    secs = (time.perf_counter() - started) / max(1, len(p.queries))
    for q in p.queries:
        res.values[q.name], res.seconds[q.name] = values[q.name], secs
        notify("value", (q.name, values[q.name], secs))
    left = [(n, x) for n, x in zip(built.names, built.props, strict=True) if n in p.left]
    built.names, built.props = [n for n, _ in left], [x for _, x in left]
    res.solver = "acyclic" if not left else "acyclic and topological"
    if left:  # rare: a query of another shape beside the extracted ones
        notify("phase", "build")
        built.model = rebuild()
    return True


def _give_back() -> None:
    """Return the freed heap to the system (afsmc.verify.engines.storm, which imports this module)."""
    from afsmc.verify.engines import storm

    storm._give_back()


def solve(a: acyclic.Arrays, queries: list[acyclic.Query], extract: Extract, view: View,
          out: Extracted, notify: Callable[[str, Any], None]) -> dict[str, float]:
    """Each query's value: those `extract` asks of side by side in passes of one kind
    (each with every state's value and optimal choice), then their strategies and paths
    one at a time (into `out`); the others together."""
    out.variables = view.variables
    plain = [q for q in queries if q.name not in extract.queries]
    values = acyclic.solve_many(a, plain) if plain else {}
    asked = [q for q in queries if q.name in extract.queries]
    for part, totals, best, value in acyclic.with_schedulers(a, asked):
        notify("phase", "check " + ", ".join(q.name for q in part))
        t0 = time.perf_counter()
        for j, q in enumerate(part):
            chosen = a.states[:-1] + best[:, j]
            values[q.name] = extract_query(a, q, extract, view, out,
                                           (totals[j], chosen, value[:, j]))
            del chosen
        out.seconds += time.perf_counter() - t0
    return values


def extract_query(a: acyclic.Arrays, q: acyclic.Query, extract: Extract, view: View,
                  out: Extracted, solved: tuple[float, I64, npt.NDArray[np.float64]]) -> float:
    """Query `q`'s value, and its strategy and paths as `extract` asks, into `out`, from
    `solved`: its value, each state's choice (its number in `a`) and every state's."""
    result, chosen, value = solved
    name = q.name
    if name in extract.strategies or name == extract.policy:
        reward = a.rewards[q.reward] if q.kind == "R" else None
        _tables(a, name, chosen, value, reward, extract, view, out)
    w = extract.witness
    if w is not None and w.query == name:
        out.witness_query = name
        if result == 0.0:  # exact: the pass is; nothing reaches the target
            what, under = (q.opt, f" under the {q.opt} strategy") if q.opt else (
                "probability", "")
            out.witness_note = f"the {what} is 0: no path reaches a target state{under}"
            return result
        target = a.labels[acyclic.LABEL + str(q.target)]
        _Paths(a, chosen, value > 0, target, view).collect(w.k, out)
    return result


def _tables(a: acyclic.Arrays, name: str, chosen: I64, value: npt.NDArray[np.float64],
            reward: acyclic.Vec | None, extract: Extract, view: View, out: Extracted) -> None:
    """The strategy's decisions in the states it reaches: summarised (groups) or whole
    (the policy)."""
    assert a.order is not None
    reached = _reached(a, chosen)
    states = reached[view.variant(chosen[reached]) >= 0]
    del reached
    out.reached[name] = len(states)
    if name in extract.strategies:  # a chunk at a time: the values of 60 M states are 6 GB
        merged: dict[tuple[int, int, bool], Group] = {}
        for i in range(0, len(states), CHUNK):
            part = states[i:i + CHUNK]
            for g in _groups(view.variant(chosen[part]), view.values(part),
                             _matters(a, value, reward, part), view.variables):
                _merge(merged, g)
        out.groups[name] = [merged[k] for k in sorted(merged)]
    if name == extract.policy:
        states = states[np.argsort(a.order[states], kind="stable")]  # Storm's order
        out.policy_states = [tuple(int(x) for x in row) for row in view.values(states)]
        out.policy_commands = [int(c) for c in view.variant(chosen[states])]


CHUNK = 1 << 20  # the most states whose values are read at a time


def _merge(groups: dict[tuple[int, int, bool], Group], g: Group) -> None:
    """Add group `g` (of one chunk of states) to those of the chunks before."""
    old = groups.get((g.command, g.mode, g.matters))
    if old is None:
        groups[(g.command, g.mode, g.matters)] = g
        return
    old.states += g.states
    old.low = tuple(min(x, y) for x, y in zip(old.low, g.low, strict=True))
    old.high = tuple(max(x, y) for x, y in zip(old.high, g.high, strict=True))


def _reached(a: acyclic.Arrays, chosen: I64) -> I64:
    """The states the strategy reaches from the initial state (ascending)."""
    n = len(a.states) - 1
    seen = np.zeros(n, bool)
    seen[a.initial] = True
    bounds = a.layers.tolist()
    for lo, hi in reversed(list(itertools.pairwise(bounds))):
        r = np.flatnonzero(seen[lo:hi]) + lo
        if r.size:
            c = chosen[r]
            seen[a.target[acyclic._ranges(a.choices[c], a.choices[c + 1])]] = True
    out: I64 = np.flatnonzero(seen)
    return out


def _matters(a: acyclic.Arrays, value: npt.NDArray[np.float64], reward: acyclic.Vec | None,
             states: I64) -> Any:
    """Whether the choices of `states` differ in value: their one-step values (the
    choice's reward of an expected-reward query, plus the sum of probability x
    successor's value) differ by more than SAME."""
    w = np.where(np.isfinite(value), value, 1e300)
    out = np.zeros(len(states), bool)
    for i in range(0, len(states), acyclic.SPAN):  # a span at a time: bounded temporaries
        out[i:i + acyclic.SPAN] = _differ(a, w, reward, states[i:i + acyclic.SPAN])
    return out


def _differ(a: acyclic.Arrays, w: npt.NDArray[np.float64], reward: acyclic.Vec | None,
            states: I64) -> Any:
    c0, c1 = a.states[states], a.states[states + 1]
    choices = acyclic._ranges(c0, c1)
    b0, b1 = a.choices[choices], a.choices[choices + 1]
    branches = acyclic._ranges(b0, b1)
    per_branch = a.prob[branches] * w[a.target[branches]]
    starts = np.concatenate(([0], np.cumsum(b1 - b0)[:-1]))
    per_choice = np.add.reduceat(per_branch, starts) if len(branches) else per_branch
    if reward is not None and len(choices):
        per_choice = per_choice + acyclic.pick(reward, choices)
    sstarts = np.concatenate(([0], np.cumsum(c1 - c0)[:-1]))
    lo = np.minimum.reduceat(per_choice, sstarts) if len(choices) else per_choice
    hi = np.maximum.reduceat(per_choice, sstarts) if len(choices) else per_choice
    return np.abs(hi - lo) > SAME * np.maximum(1.0, np.maximum(np.abs(hi), np.abs(lo)))


def paths_into(a: acyclic.Arrays, chosen: I64, alive: npt.NDArray[np.bool_], target: Any,
               view: View, k: int, out: Extracted) -> None:
    """The `k` most probable paths into the states `target` under the choices `chosen`
    (through the states `alive` only, from which the target is reached), into `out` as
    a witness's paths are."""
    out.variables = view.variables
    _Paths(a, chosen, alive, target, view).collect(k, out)


class _Paths:
    """The most probable paths of the strategy's DTMC into `target`, as Storm's
    k-shortest-paths generator finds them (the recursive enumeration algorithm of Jiménez
    and Marzal): the most probable path to each state first, a state's predecessor on it
    the one with the largest product, then the largest probability, then the largest
    number (Storm's Dijkstra queue); the next paths from candidates, the most probable
    first, then the smallest predecessor and rank. A path stops at its first target state
    and may loop on a self-loop. Ties fall by the states' numbers in Storm's model, as
    they do there (explored by afsmc: by their keys). Only the states from which the strategy reaches a target (`alive`)
    take part: no path into a target passes through another."""

    META = -1  # the meta-target: every target state leads to it with probability 1
    LOW = np.uint64(0xFFFFFFFF)

    def __init__(self, a: acyclic.Arrays, chosen: I64, alive: npt.NDArray[np.bool_],
                 target: Any, view: View) -> None:
        assert a.order is not None
        self.a, self.chosen, self.target, self.view = a, chosen, target, view
        self.old = a.order  # Storm's number of each state, for the ties
        self.dist, self.pred, self.into = self._dijkstra(alive)
        self.targets = np.flatnonzero(target & (self.dist > 0))
        self.meta: tuple[int | None, float] = (None, 0.0)
        if self.targets.size:
            t = self.targets
            best = t[np.lexsort((self.old[t], self.dist[t]))[-1]]
            self.meta = (int(best), float(self.dist[best]))
        self.ksp: dict[int, list[tuple[int | None, int, float]]] = {}
        self.cand: dict[int, dict[tuple[int, int], float]] = {}

    def _bound(self, sources: npt.NDArray[np.bool_]) -> int:
        """How many branches the chosen choices of `sources` have (a SPAN at a time)."""
        a, total = self.a, 0
        for lo in range(0, len(sources), acyclic.SPAN):
            c = self.chosen[lo:lo + acyclic.SPAN][sources[lo:lo + acyclic.SPAN]]
            total += int((a.choices[c + 1] - a.choices[c]).sum())
        return total

    def _dijkstra(self, alive: npt.NDArray[np.bool_]) -> tuple[Any, Any, Any]:
        """The largest product of probabilities from the initial state to each state,
        layer by layer from the initial one (the model is acyclic but for self-loops,
        which never improve it), and the predecessor Storm's Dijkstra keeps; and the
        strategy's transitions as (successor << 32 | source), sorted: who leads where."""
        a = self.a
        n = len(a.states) - 1
        dist = np.zeros(n)
        dist[a.initial] = 1.0 if alive[a.initial] else 0.0
        pred = np.full(n, -1, np.int32)
        sources = alive & ~self.target
        into = np.empty(self._bound(sources), np.uint64)
        used = 0
        for lo, hi in reversed(acyclic._spans(a.layers)):  # a span's states: one layer's
            s = np.flatnonzero((dist[lo:hi] > 0) & sources[lo:hi]) + lo
            if not s.size:
                continue
            c = self.chosen[s]
            b0, b1 = a.choices[c], a.choices[c + 1]
            br = acyclic._ranges(b0, b1)
            src = np.repeat(s, b1 - b0)
            dst = a.target[br].astype(np.int64)
            keep = alive[dst]
            src, dst, prob = src[keep], dst[keep], a.prob[br][keep]
            into[used:used + len(src)] = (dst.astype(np.uint64) << np.uint64(32)) | \
                src.astype(np.uint64)
            used += len(src)
            moving = src != dst
            self._relax(dist, pred, src[moving], dst[moving], prob[moving])
        into = into[:used]
        into.sort()
        return dist, pred, into

    def _relax(self, dist: Any, pred: Any, s: I64, d: I64, p: Any) -> None:
        """Improve the successors `d` of one layer's sources `s` (branch probabilities
        `p`): per successor, the largest (product, probability, Storm's number) wins."""
        prod = dist[s] * p
        keep = prod > 0
        s, d, prod = s[keep], d[keep], prod[keep]
        if not s.size:
            return
        o = np.lexsort((self.old[s], dist[s], prod, d))
        s, d, prod = s[o], d[o], prod[o]
        last = np.concatenate((d[1:] != d[:-1], [True]))
        s, d, prod = s[last], d[last], prod[last]
        cur = pred[d].astype(np.int64)
        cur_prod = np.where(cur >= 0, dist[d], 0.0)
        cs = np.where(cur >= 0, cur, 0)
        better = (prod > cur_prod) | ((prod == cur_prod) & (
            (dist[s] > dist[cs]) | ((dist[s] == dist[cs]) & (self.old[s] > self.old[cs]))))
        better &= prod > 0
        dist[d[better]] = prod[better]
        pred[d[better]] = s[better]

    def _edge(self, u: int, v: int) -> float:
        if v == self.META:
            return 1.0
        c = int(self.chosen[u])
        b0, b1 = int(self.a.choices[c]), int(self.a.choices[c + 1])
        hit = np.flatnonzero(self.a.target[b0:b1] == v)
        return float(self.a.prob[b0 + hit[0]])

    def _preds(self, v: int) -> list[int]:
        if v == self.META:
            return [int(x) for x in self.targets]
        lo, hi = np.searchsorted(self.into, np.array([v, v + 1], np.uint64) << np.uint64(32))
        return [int(x) for x in self.into[lo:hi] & self.LOW]

    def _dist(self, v: int) -> float:
        return self.meta[1] if v == self.META else float(self.dist[v])

    def _paths_of(self, v: int) -> list[tuple[int | None, int, float]]:
        got = self.ksp.get(v)
        if got is None:
            d = self._dist(v)
            pred = self.meta[0] if v == self.META else int(self.pred[v])
            got = self.ksp[v] = [(None if pred is None or pred < 0 else pred, 1, d)] \
                if d > 0 else []
        return got

    def _key(self, u: int) -> int:
        return -1 if u == self.META else int(self.old[u])

    def _next(self, v: int, k: int) -> None:
        """The k-th most probable path to `v` (k >= 2), if there is one."""
        paths = self._paths_of(v)
        cand = self.cand.setdefault(v, {})
        if k == 2:
            first = paths[0]
            for u in self._preds(v):
                cand.setdefault((u, 1), self._dist(u) * self._edge(u, v))
                if first[0] is not None:
                    cand.pop((first[0], 1), None)
        if not (k == 2 and v == self.a.initial):
            last, tail_k = paths[k - 2][0], paths[k - 2][1]
            assert last is not None
            u = last
            tail = self._paths_of(u)
            if len(tail) < tail_k + 1:
                self._next(u, tail_k + 1)
            if len(tail) >= tail_k + 1:
                cand.setdefault((u, tail_k + 1), tail[tail_k][2] * self._edge(u, v))
        if cand:
            # Storm's set is ordered by (predecessor, rank): the first of the most probable
            pick = min(cand, key=lambda x: (-cand[x], self._key(x[0]), x[1]))
            paths.append((pick[0], pick[1], cand.pop(pick)))

    def path(self, k: int) -> tuple[float, list[int]] | None:
        """The k-th most probable path (its probability, its states), or None."""
        meta = self._paths_of(self.META)
        if not meta:
            return None
        while len(meta) < k:
            before = len(meta)
            self._next(self.META, len(meta) + 1)
            if len(meta) == before:
                return None
        prob = meta[k - 1][2]
        states: list[int] = []
        node, rank = meta[k - 1][0], meta[k - 1][1]
        while node is not None:
            states.append(node)
            node, rank = self._paths_of(node)[rank - 1][:2]
        states.reverse()
        return prob, states

    def collect(self, k: int, out: Extracted) -> None:
        if not self.targets.size:
            out.witness_note = "no state the strategy reaches is a target state"
            return
        found: list[RawPath] = []
        for i in range(1, k + 1):
            got = self.path(i)
            if got is None or got[0] <= 0.0:
                break
            p, states = got
            vals = self.view.values(np.asarray(states, np.int64))
            steps = [self._edge(x, y) for x, y in itertools.pairwise(states)]
            commands = [self.view.command(int(self.chosen[s]), row)
                        for s, row in zip(states[:-1], vals, strict=False)] + [-1]
            found.append(RawPath(p, [tuple(int(x) for x in row) for row in vals], commands,
                                 steps))
        if len(found) < k:
            out.witness_note = f"there are only {len(found)} paths into the target states"
        out.paths = found
