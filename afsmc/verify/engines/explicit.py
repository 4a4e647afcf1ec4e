"""A job's queries answered without Storm: afsmc's own exploration of the lowered model
(:mod:`afsmc.verify.explorer.explore`) and one exact backward pass (:mod:`afsmc.verify.arrays.acyclic`).

It applies to the queries P [F T] and R [F T] (min and max on an MDP) of a model whose
clock only grows: states, choices and transitions are those Storm would build, and the
values those of Storm's solvers on an acyclic model. Other queries, and every query of a
model the explorer gives up on (a cycle, a variable out of range...), are left to Storm,
in the same process (:func:`afsmc.verify.engines.storm.execute` calls :func:`answer` first).
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any, Literal

import numpy as np

from afsmc.backends.prism import property_variants
from afsmc.lower.lowering import Lowered
from afsmc.model import expr as E
from afsmc.model import ir
from afsmc.sim.compile import SimError
from afsmc.verify import kernels
from afsmc.verify.arrays import acyclic, layering
from afsmc.verify.engines import strategy_arrays
from afsmc.verify.engines.strategy_storm import Extract, Extracted
from afsmc.verify.explorer import explore, explore_graph

Notify = Callable[[str, Any], None]


def applies(low: Lowered, engine: str, solver: str, other: bool) -> bool:
    """Whether a job tries afsmc's own exploration first: on the sparse engine (or "auto"
    before it picks one) with the default solver, nothing else asked of Storm (`other`:
    bisimulation, exact or sound mode), a single machine without undefined constants.
    Schedulers and paths come from its arrays where the backward pass gives them
    (:func:`afsmc.verify.engines.strategy_arrays.covers`), else from Storm."""
    return (engine in ("sparse", "auto") and solver == "auto" and not other
            and low.network is None and not low.parameters)


@dataclass
class Plan:
    queries: list[acyclic.Query]
    targets: list[E.Expr]
    rewards: list[str]
    left: list[str]  # the job's queries it does not answer
    # a target's text -> its index in `targets` (queries of the same target share it)
    keys: dict[str, int] = field(default_factory=dict)


def plan(low: Lowered, names: tuple[str, ...]) -> Plan:
    """The queries among `names` one backward pass answers; the others are left."""
    variants = {n: (p, opt) for p in low.model.properties for n, opt in property_variants(low, p)}
    out = Plan([], [], [], [])
    for name in names:
        found = variants.get(name)
        if found is None or not _add(out, name, found[0],
                                     "min" if found[1] == "min" else
                                     "max" if found[1] == "max" else ""):
            out.left.append(name)
    return out


MEAN = "\0uniform:"  # a uniform query's name in the pass, apart from the MDP's variants


def plan_uniform(low: Lowered, names: tuple[str, ...], p: Plan) -> list[str]:
    """Add to `p` the queries of the uniform DTMC among `names` (properties' names) that
    the MDP's pass answers as means over each state's choices; the names it takes."""
    props = {prop.name: prop for prop in low.model.properties}
    return [name for name in names
            if name in props and _add(p, MEAN + name, props[name], "mean")]


def _add(p: Plan, name: str, prop: ir.Property,
         opt: Literal["min", "max", "", "mean"]) -> bool:
    """Add the query `name` of `prop` to the plan, with its target and reward model;
    False if the pass does not answer it."""
    target = _target(prop)
    if target is None:
        return False
    key = repr(target)
    index = p.keys.setdefault(key, len(p.targets))
    if index == len(p.targets):
        p.targets.append(target)
    reward = (prop.reward or "") if prop.kind == "R" else ""
    if prop.kind == "R" and reward not in p.rewards:
        p.rewards.append(reward)
    p.queries.append(acyclic.Query(name, "P" if prop.kind == "P" else "R", opt, index, reward))
    return True


def _target(p: ir.Property) -> E.Expr | None:
    """T of P [F T] or R [F T], without a step bound; else None."""
    path = p.path
    if path.kind != "F" or path.bound is not None or path.target is None:
        return None
    if p.kind == "R" and not p.reward:
        return None
    return path.target


@dataclass
class Answer:
    values: dict[str, float]
    seconds: dict[str, float]
    states: int
    choices: int
    transitions: int
    explore_time: float
    left: list[str]
    extracted: Extracted | None = None
    uniform: Uniform | None = None  # the uniform DTMC's values, if asked
    scratch: int | None = None  # bytes written to the scratch directory (afsmc.verify.stream)
    scratch_why: str = ""  # why it was streamed: "--scratch", or the memory it would need


@dataclass
class Uniform:
    """The uniform DTMC's values from the MDP's pass (each state the mean of its
    floor/ceil choices) and that DTMC's size."""

    values: dict[str, float]
    seconds: dict[str, float]
    transitions: int


class TooMany(Exception):
    def __init__(self, states: int, partial: bool = False) -> None:
        super().__init__(states)
        self.states = states
        self.partial = partial  # at least `states`: the exploration stopped in a round


def answer(low: Lowered, names: tuple[str, ...], what: str, notify: Notify,
           max_states: int | None = None, max_bytes: int | None = None,
           extract: Extract | None = None, uniform: tuple[str, ...] = (),
           scratch: str | None = None, scratch_auto: bool = False) -> Answer | None:
    """The queries' values by exploration and a backward pass, and what `extract` asks;
    None if the explorer gives up or the pass does not give what `extract` asks (Storm
    then answers them all). `uniform`: properties whose values in the uniform DTMC the
    same exploration gives (Answer.uniform), those it can. `scratch`: a directory of the
    job's own, to explore through layer by layer (afsmc.verify.stream, strategies
    and witnesses too); with `scratch_auto`, only once the in-memory exploration passes
    route.STREAM_FROM states or would not fit comfortably (afsmc.verify.stream.route.Watch),
    going on from the buckets it explored.
    Raises TooMany past `max_states`, and ScratchFull when the scratch disk fills."""
    p = plan(low, names)
    if not p.queries or (extract is not None and not strategy_arrays.covers(extract, p.queries)):
        return None
    means = plan_uniform(low, uniform, p)
    mine = [q for q in p.queries if q.opt != "mean"]
    notify("phase", "explicit")
    started = time.perf_counter()

    def explored(event: str, data: Any) -> None:  # a progress line now and then
        notify("solver", f"explored {data[1]:,} states of the {what} so far (clock at "
               f"{data[0]}; {time.perf_counter() - started:.0f} s)")

    try:
        compiled = explore.compile_model(low, p.targets, p.rewards, extract is not None)
        found = _explored(compiled, p, means, what, notify, explored, max_states, max_bytes,
                          scratch, scratch_auto, extract, low)
        if isinstance(found, Answer):
            return found
    except (explore.GiveUp, SimError) as exc:
        notify("solver", f"afsmc's own exploration does not apply to the {what} ({exc}): "
               "Storm builds it")
        return None
    except explore.TooManyStates as exc:
        raise TooMany(exc.states, exc.partial) from None
    if layering.tiny(found.arrays):  # a long chain in each bucket: one layering for all
        again = layering.relayered(found.arrays)
        if again is not None:
            notify("solver", f"the {what}'s {len(found.arrays.layers) - 1:,} layers laid out "
                   f"again as {len(again.layers) - 1:,}: its buckets' layers were tiny")
            found.arrays = again
    built = time.perf_counter() - started
    notify("built", (found.states, found.transitions, built))
    notify("solver", f"the {what} explored by afsmc, acyclic but for self-loops "
           f"({len(found.arrays.layers) - 1:,} layers): each query by one exact backward pass")
    notify("phase", "check " + ", ".join(q.name for q in mine))
    t0 = time.perf_counter()
    out: Extracted | None = None
    if extract is None:
        values = acyclic.solve_many(found.arrays, mine)
    else:  # one query at a time, with its strategies and paths
        out = Extracted()
        values = strategy_arrays.solve(found.arrays, mine, extract,
                                       view(found.arrays, low, compiled.layout, extract), out,
                                       notify)
    secs = (time.perf_counter() - t0) / len(mine)
    for q in mine:
        notify("value", (q.name, values[q.name], secs))
    return Answer(values, {q.name: secs for q in mine}, found.states, found.choices,
                  found.transitions, built, p.left, out,
                  _uniform(found.arrays, [q for q in p.queries if q.opt == "mean"], means,
                           notify))


def _explored(compiled: explore.Compiled, p: Plan, means: list[str], what: str,
              notify: Notify, explored: Notify, max_states: int | None,
              max_bytes: int | None, scratch: str | None, scratch_auto: bool,
              extract: Extract | None, low: Lowered) -> explore_graph.Explored | Answer:
    """The model explored in memory, or the queries' answer (and what `extract` asks)
    through `scratch`: at once, or (`scratch_auto`) once the in-memory exploration would
    not fit comfortably or passes route.STREAM_FROM states, its buckets so far then
    written to the scratch and the exploration gone on from there layer by layer."""
    if scratch is None:
        return explore_graph.explore(compiled, explored, max_states, max_bytes)
    from afsmc.verify.engines.guard import mem_available
    from afsmc.verify.stream import route

    view_of = None if extract is None else key_view(low, compiled.layout, extract)
    if not scratch_auto:
        return route.answer(compiled, p, means, scratch, what, notify, max_states,
                            extract=extract, view_of=view_of)
    watch = route.Watch(mem_available())
    try:
        return explore_graph.explore(compiled, explored, max_states, max_bytes, watch.handover)
    except explore_graph.Handover as exc:
        why, partial = exc.why, exc.partial
    notify("solver", f"the {what}'s exploration {why}: the {partial.counts[-1]:,} states "
           f"explored in memory are written to the scratch directory in "
           f"{Path(scratch).parent} and the exploration goes on layer by layer (--no-scratch "
           "keeps it in memory; --scratch DIR picks the directory)")
    return route.answer(compiled, p, means, scratch, what, notify, max_states,
                        f"by default: {why}", extract=extract, view_of=view_of,
                        resume=partial)


def _uniform(a: acyclic.Arrays, queries: list[acyclic.Query], names: list[str],
             notify: Notify) -> Uniform | None:
    """The uniform DTMC's queries, answered on the MDP's arrays."""
    if not queries:
        return None
    notify("solver", "the uniform DTMC's values from the same exploration: in each state "
           "the mean of its floor/ceil choices, by one more backward pass")
    t0 = time.perf_counter()
    got = acyclic.solve_many(a, queries)
    secs = (time.perf_counter() - t0) / len(queries)
    for n in names:
        notify("solver", f"checked {n} on the uniform DTMC in {secs:.0f} s")
    return Uniform({n: got[MEAN + n] for n in names}, {n: secs for n in names},
                   _mean_transitions(a))


def view(a: acyclic.Arrays, low: Lowered, layout: explore.Layout,
          extract: Extract) -> strategy_arrays.View:
    """The explored states' values from their keys, the choices' commands as explored;
    the variables in the order of Storm's valuations (the mode, the integers, the
    booleans), as Storm's route gives them."""
    assert a.order is not None and a.commands is not None
    return key_view(low, layout, extract)(a.order, a.commands)


def key_view(low: Lowered, layout: explore.Layout, extract: Extract
             ) -> Callable[[acyclic.I64, Any], strategy_arrays.View]:
    """`view` of any states, from their keys and their choices' commands."""
    return lambda keys, commands: _key_view(low, layout, extract, keys, commands)


def _key_view(low: Lowered, layout: explore.Layout, extract: Extract, keys: acyclic.I64,
              commands: Any) -> strategy_arrays.View:
    variables = ("mode", *[v.name for v in low.model.variables if v.type is not E.Type.BOOL],
                 *[v.name for v in low.model.variables if v.type is E.Type.BOOL])
    decisive = np.asarray(extract.decisive, np.int64)

    def values(states: acyclic.I64) -> acyclic.I64:
        got = layout.decode(keys[states])
        out: acyclic.I64 = np.zeros((len(states), len(variables)), np.int64)
        for j, name in enumerate(variables):
            out[:, j] = got[name]
        return out

    def variant(choices: acyclic.I64) -> acyclic.I64:
        c = commands[choices].astype(np.int64)
        out: acyclic.I64 = np.where(np.isin(c, decisive), c, -1)
        return out

    return strategy_arrays.View(variables, values, variant,
                                lambda choice, _row: int(commands[choice]))


def fill(job: Any, res: Any, notify: Notify, too_big: Callable[[Any, int, bool], Any]) -> Any:
    """Answer what the exploration can of a Storm job (afsmc.verify.engines.storm.Job) into its
    result `res`; the job of what is left for Storm, or None if nothing is (or the model
    has too many states: `res.failure` says so)."""
    from afsmc.verify.engines.storm import StormFailure  # (storm imports this module)
    from afsmc.verify.stream.scratch import ScratchFull

    try:
        ans = answer(job.explicit, job.names, job.what, notify, job.max_states,
                     job.memory_budget, job.extract, job.uniform, job.scratch, job.scratch_auto)
    except TooMany as exc:
        res.states, res.failure = exc.states, too_big(job, exc.states, exc.partial)
        return None
    except ScratchFull as exc:
        res.failure = StormFailure("scratch", str(exc))
        return None
    if ans is None:
        return replace(job, explicit=None)
    res.states, res.choices, res.transitions = ans.states, ans.choices, ans.transitions
    res.kind, res.engine, res.solver = job.explicit.kind, "explicit", "acyclic"
    res.engine_reason = ("afsmc's own exploration: the model's clock only grows, so one "
                         "exact backward pass answers its reachability queries"
                         + ("" if ans.scratch is None else
                            f"; explored layer by layer through {ans.scratch / 1e6:,.1f} MB "
                            f"of scratch disk ({ans.scratch_why})"))
    res.build_time, res.check_time = ans.explore_time, sum(ans.seconds.values())
    res.values, res.seconds = dict(ans.values), dict(ans.seconds)
    res.extracted = ans.extracted
    res.uniform = ans.uniform
    notify("engine", "explicit")
    if not ans.left:
        return None
    return replace(job, names=tuple(ans.left), explicit=None, hybrid_extra=(), extract=None,
                   uniform=())


def _mean_transitions(a: acyclic.Arrays) -> int:
    """The transitions of the DTMC that picks each state's choices uniformly (queries
    "mean"): each state's distinct successors over all its choices, a span at a time
    (or in one pass by the compiled kernel, afsmc.verify.kernels.passes, on a large
    model)."""
    total = 0
    n = len(a.states) - 1
    if kernels.enabled(n):
        from afsmc.verify.kernels import passes

        return int(passes.distinct_successors(a.states, a.choices, a.target))
    for lo, hi in acyclic._spans(a.layers):
        c0, c1 = int(a.states[lo]), int(a.states[hi])
        b0, b1 = int(a.choices[c0]), int(a.choices[c1])
        per_choice = np.repeat(np.arange(hi - lo, dtype=np.int64), np.diff(a.states[lo:hi + 1]))
        owner = np.repeat(per_choice, np.diff(a.choices[c0:c1 + 1]))
        total += len(np.unique(owner * n + a.target[b0:b1]))
    return total
