"""Inside the Storm process: Storm's schedulers and most probable paths, as plain data.

A :class:`Extract` on a :class:`afsmc.verify.engines.storm.Job` asks for more than values: the
scheduler of some queries (summarised per command and mode, over the states the scheduler
reaches), the whole scheduler of one query (for `simulate --strategy`), and the K most
probable paths of one query into its target states. The sparse model is then built with
state valuations and choice origins (which PRISM command each choice comes from); the
caller, who has the lowered model, maps command indices back to actions and interval
constants (:mod:`afsmc.verify.outcome.strategy`, :mod:`afsmc.verify.outcome.witness`).
"""

from __future__ import annotations

import itertools
import math
from dataclasses import dataclass, field
from typing import Any


@dataclass(frozen=True)
class WitnessRequest:
    """The `k` most probable paths of query `query` (e.g. ``success_max``: an MDP's paths
    follow that query's scheduler; a DTMC's query is the property's name). `target`: a
    PRISM state formula whose states the paths go into instead of the property's own
    target (a failed requirement's violating states); None: the property's target.
    `avoid`: the paths go into the states from which the property's (unbounded) path
    formula can no longer hold, its probability 0 there: how a `P>=` requirement is missed.
    """

    query: str
    k: int
    target: str | None = None
    avoid: bool = False


@dataclass(frozen=True)
class Extract:
    strategies: tuple[str, ...] = ()  # queries whose scheduler is summarised
    policy: str | None = None  # a query whose scheduler is returned whole
    witness: WitnessRequest | None = None
    # the commands that are floor/ceil variants: in their states the scheduler chooses;
    # their action labels in the generated model (backends.prism.variant_label)
    decisive: tuple[int, ...] = ()
    labels: tuple[str, ...] = ()
    # every command's action label ("": unlabelled) and modes
    commands: tuple[tuple[str, tuple[int, ...]], ...] = ()

    @property
    def queries(self) -> tuple[str, ...]:
        extra = tuple(q for q in (self.policy, self.witness and self.witness.query) if q)
        return tuple(dict.fromkeys(self.strategies + extra))


@dataclass
class Group:
    """The states a scheduler reaches in which it takes `command` (a floor/ceil variant),
    in mode number `mode`: how many, and each variable's smallest and largest value."""

    command: int
    mode: int
    states: int
    low: tuple[int, ...]
    high: tuple[int, ...]
    matters: bool = True  # False: every choice of these states has the same value


@dataclass
class RawPath:
    probability: float
    states: list[tuple[int, ...]]  # valuations, in `Extracted.variables` order
    commands: list[int]  # the command of each state's choice (the last: none, -1)
    steps: list[float]  # each step's probability


@dataclass
class Extracted:
    """What one Storm process extracted: per query, its groups; the policy's decision
    states and commands; the witness paths (or why there are none)."""

    variables: tuple[str, ...] = ()  # the generated model's variables ("mode" among them)
    groups: dict[str, list[Group]] = field(default_factory=dict)
    reached: dict[str, int] = field(default_factory=dict)  # its decisions, per query
    policy_states: list[tuple[int, ...]] = field(default_factory=list)
    policy_commands: list[int] = field(default_factory=list)
    paths: list[RawPath] = field(default_factory=list)
    witness_note: str = ""  # why fewer paths than asked (none left, or the search limit)
    witness_query: str | None = None  # the query the paths follow
    seconds: float = 0.0


def builder_options(stormpy: Any, props: list[Any], program: Any, extract: Extract) -> Any:
    """Storm's builder options for `props` (and a witness's own target) with state
    valuations and choice labels."""
    formulas = [p.get_raw_formula() for p in props]
    if extract.witness is not None and extract.witness.target is not None:
        formulas += [p.get_raw_formula() for p in stormpy.parse_properties(
            f"P=? [ F ({extract.witness.target}) ]", program)]
    opts = stormpy.BuilderOptions(formulas)
    opts.set_build_state_valuations()
    opts.set_build_choice_labels()
    opts.set_build_all_labels()
    return opts


def _variables(stormpy: Any, program: Any) -> list[tuple[str, Any, bool]]:
    out = []
    for module in program.modules:
        out += [(v.name, v.expression_variable, False) for v in module.integer_variables]
        out += [(v.name, v.expression_variable, True) for v in module.boolean_variables]
    return out


def _valuations(model: Any, variables: list[tuple[str, Any, bool]]) -> Any:
    """Every state's values, as a numpy array (states x variables)."""
    import numpy as np

    sv = model.state_valuations
    n = int(model.nr_states)
    out = np.zeros((n, len(variables)), dtype=np.int64)
    for j, (_, var, boolean) in enumerate(variables):
        if boolean:  # a BitVector: iterating it gives the states where the variable is true
            out[np.fromiter((int(s) for s in sv.get_boolean_values(var)), dtype=np.int64), j] = 1
        else:
            out[:, j] = np.asarray(sv.get_int64_values(var), dtype=np.int64)
    return out


def _keys(vals: Any) -> Any:
    """Each row of values as one integer (mixed radix over the columns' ranges)."""
    import numpy as np

    key = np.zeros(len(vals), dtype=np.int64)
    if len(vals) == 0:
        return key
    lo, hi = vals.min(axis=0), vals.max(axis=0)
    for j in range(vals.shape[1]):
        key = key * int(hi[j] - lo[j] + 1) + (vals[:, j] - lo[j])
    return key


def _chosen(model: Any, extract: Extract) -> Any:
    """The floor/ceil variant each state's (first) choice takes, by its action label
    (-1: none), as a numpy array."""
    import numpy as np

    out = np.full(int(model.nr_states), -1, dtype=np.int64)
    if not model.has_choice_labeling():
        return out
    labeling = model.choice_labeling
    present = labeling.get_labels()
    for c, label in zip(extract.decisive, extract.labels, strict=True):
        if label in present:
            rows = np.fromiter((int(r) for r in labeling.get_choices(label)), dtype=np.int64)
            out[rows] = c  # a DTMC's choice r is its state r
    return out


def induced(stormpy: Any, model: Any, result: Any) -> tuple[Any, Any]:
    """The DTMC a query's scheduler induces on the states it reaches (a DTMC: itself), and
    the MDP's states where Storm's scheduler left the choice open (None: none).

    Storm leaves a choice undefined where the path formula is decided whatever is chosen
    (an until's states where neither side holds), and applying such a partial scheduler
    fails ("Cannot insert value at illegal column"): those states take their first
    choice, which changes no value."""
    import numpy as np

    if not str(model.model_type).upper().endswith("MDP"):
        return model, None
    scheduler = result.get_scheduler()
    free = None
    if scheduler.partial:
        free = np.zeros(int(model.nr_states), dtype=bool)
        for s in range(int(model.nr_states)):
            choice = scheduler.get_choice(s)
            if not choice.defined:
                scheduler.set_choice(type(choice)(0), s)
                free[s] = True
    return model.apply_scheduler(scheduler, True), free


def analyse(stormpy: Any, program: Any, model: Any, name: str, prop: Any, result: Any,
            extract: Extract, out: Extracted) -> None:
    """Add what `extract` asks of query `name` (checked: `result`) to `out`. A failure to
    find the witness paths is their note: the query's value stands."""
    import time

    t0 = time.perf_counter()
    variables = _variables(stormpy, program)
    out.variables = tuple(n for n, _, _ in variables)
    w = extract.witness
    paths = w is not None and w.query == name
    mdp = str(model.model_type).upper().endswith("MDP")
    strategy = mdp and (name in extract.strategies or name == extract.policy)
    try:
        dtmc, free = induced(stormpy, model, result)
    except RuntimeError as exc:
        if strategy or not paths:
            raise
        out.witness_query = name
        out.witness_note = f"Storm could not apply the strategy to find paths: {exc}"
        return
    vals = _valuations(dtmc, variables)
    if strategy:
        chosen = _chosen(dtmc, extract)
        states = (chosen >= 0).nonzero()[0]
        out.reached[name] = len(states)
        if name in extract.strategies:
            matters = _matters(stormpy, model, prop, result, variables, vals[states], free)
            out.groups[name] = _groups(chosen[states], vals[states], matters, out.variables)
        if name == extract.policy:
            out.policy_states = [tuple(int(x) for x in row) for row in vals[states]]
            out.policy_commands = [int(c) for c in chosen[states]]
    if w is not None and paths:
        out.witness_query = name
        value = float(result.get_value(model.initial_states[0]))
        try:
            _paths(stormpy, program, dtmc, prop, w, vals, extract, out, value)
        except RuntimeError as exc:
            out.paths = []
            out.witness_note = f"Storm could not find the paths: {exc}"
    out.seconds += time.perf_counter() - t0


def _groups(commands: Any, vals: Any, matters: Any, variables: tuple[str, ...]) -> list[Group]:
    """The decisions per command, mode and whether the end matters there: how many, and
    each variable's range; by command, then mode, then not mattering before mattering.
    (One sort of the states by that key, then each run's minima and maxima at once.)"""
    import numpy as np

    n = len(commands)
    if n == 0:
        return []
    mode_i = variables.index("mode") if "mode" in variables else -1
    modes = vals[:, mode_i] if mode_i >= 0 else np.zeros(n, dtype=np.int64)
    c = np.asarray(commands, dtype=np.int64)
    flag = np.asarray(matters, dtype=bool)
    order = np.lexsort((flag, modes, c))
    c, m, f = c[order], np.asarray(modes, dtype=np.int64)[order], flag[order]
    starts = np.flatnonzero(np.concatenate(
        ([True], (c[1:] != c[:-1]) | (m[1:] != m[:-1]) | (f[1:] != f[:-1]))))
    part = np.asarray(vals)[order]
    low = np.minimum.reduceat(part, starts, axis=0)
    high = np.maximum.reduceat(part, starts, axis=0)
    counts = np.diff(np.append(starts, n))
    return [Group(int(c[s]), int(m[s]), int(k), tuple(int(x) for x in lo),
                  tuple(int(x) for x in hi), bool(f[s]))
            for s, k, lo, hi in zip(starts, counts, low, high, strict=True)]


# Two choices whose values differ by at most this (relative to the larger) are equal: the
# scheduler's choice between them is arbitrary.
SAME = 1e-9


def _matters(stormpy: Any, model: Any, prop: Any, result: Any,
             variables: list[tuple[str, Any, bool]], reached: Any, free: Any = None) -> Any:
    """For each of the `reached` states (values): whether its choices differ in value,
    i.e. min and max over the choices of (sum of probability x successor's value) differ,
    computed by Storm as the instantaneous reward after one step with the values as state
    rewards. An expected reward with action rewards: True (not compared). `free`: the
    MDP's states whose choice Storm left open (`induced`), where it never matters."""
    import numpy as np
    import stormpy.models as models

    if _action_rewards(model, prop):
        return np.ones(len(reached), dtype=bool)
    raw = list(result.get_value_vector())
    # an exact model's values are rationals, compared exactly (rewards: finite here, as
    # an infinite expected reward has no rational)
    exact = bool(getattr(model, "is_exact", False))
    values = raw if exact else [float(v) if math.isfinite(v) else 1e300 for v in raw]
    rm = (models.SparseRewardModel[stormpy.Rational] if exact else models.SparseRewardModel)(
        optional_state_reward_vector=values)
    comp = models.SparseModelComponents(transition_matrix=model.transition_matrix,
                                        state_labeling=model.labeling, reward_models={"v": rm})
    one = models.SparseMdp(comp)
    lo_q, hi_q = ([x for x in stormpy.model_checking(one, q).get_value_vector()]
                  for q in stormpy.parse_properties("Rmin=? [I=1]; Rmax=? [I=1]"))
    del one, comp, rm
    if exact:
        gap = np.fromiter((a != b for a, b in zip(lo_q, hi_q, strict=True)), dtype=bool,
                          count=len(lo_q))
    else:
        lo, hi = np.asarray(lo_q, dtype=float), np.asarray(hi_q, dtype=float)
        gap = np.abs(hi - lo) > SAME * np.maximum(1.0, np.maximum(np.abs(hi), np.abs(lo)))
    # the reached states among the MDP's, by their values
    keys_all = _keys(np.vstack([_valuations(model, variables), reached]))
    n = int(model.nr_states)
    order = np.argsort(keys_all[:n], kind="stable")
    pos = np.searchsorted(keys_all[:n][order], keys_all[n:])
    at = order[pos]
    return gap[at] if free is None else gap[at] & ~free[at]


def _action_rewards(model: Any, prop: Any) -> bool:
    """Whether an expected-reward query's structure has per-choice rewards."""
    formula = prop.get_raw_formula()
    if not formula.is_reward_operator_formula or not model.reward_models:
        return False
    name = formula.reward_name if formula.has_reward_model_name() else None
    rm = model.reward_models[name] if name else next(iter(model.reward_models.values()))
    return bool(rm.has_state_action_rewards)


# Paths the search may enumerate, per path asked, before it gives up on finding more that
# respect a step bound (the others are skipped).
SEARCH_FACTOR = 50


def _under(dtmc: Any, prop: Any) -> tuple[str, str]:
    """How the value is named ("min", "max"; a DTMC's: "probability") and the strategy the
    paths follow (" under the min strategy"; a DTMC's: "")."""
    formula = prop.get_raw_formula()
    if not getattr(formula, "has_optimality_type", False):
        return "probability", ""
    opt = "min" if "min" in str(formula.optimality_type).lower() else "max"
    return opt, f" under the {opt} strategy"


def _paths(stormpy: Any, program: Any, dtmc: Any, prop: Any, w: WitnessRequest,
           vals: Any, extract: Extract, out: Extracted, value: float) -> None:
    """The `w.k` most probable paths of the induced DTMC into the target states, by
    Storm's k-shortest-paths generator (recursive enumeration; paths stop at their first
    target state and may loop). `value`: the query's value from the initial state.

    The generator is never handed what it cannot take: with the initial state among its
    targets it crashes (signal 11) at the second path, so the only path, the empty one,
    is given here; and it crashes asking for a path beyond the last where a target is
    reached only through another, so its targets are those a path reaches first
    (`_frontier`). An until's states where neither side holds are targets of the
    generator too, as its paths end there, and such paths are dropped."""
    from stormpy.analysis import _utility
    from stormpy.datastructures import BitVector

    target, left, bound = _target(stormpy, program, dtmc, prop, w)
    what, under = _under(dtmc, prop)
    reach = ("satisfies the until" if left is not None else "reaches a target state") + (
        f" within {bound} steps" if bound is not None else "")
    if target is None:
        out.witness_note = "the property has no target states to reach"
        return
    if not w.avoid and value == 0.0:  # Storm's graph analysis gives exact zeros
        out.witness_note = f"the {what} is 0: no path {reach}{under}"
        return
    if not target:
        out.witness_note = (f"no state reachable{under} is one from which the property can "
                            "no longer hold" if w.avoid else
                            f"no state reachable{under} is a target state")
        return
    init = int(dtmc.initial_states[0])
    if init in target:
        out.paths = [RawPath(1.0, [tuple(int(x) for x in vals[init])], [-1], [])]
        out.witness_note = (
            f"the {what} is 0: the property can no longer hold from the initial state"
            f"{under}, so every path misses it; the only path is the empty one"
            if w.avoid else "the initial state is a target state: the only path is the "
            "empty one")
        return
    dead = set() if left is None else set(range(dtmc.nr_states)) - left - target
    first = _frontier(dtmc, init, target | dead)
    if not first - dead:  # nothing to enumerate: the generator is not asked
        out.witness_note = f"no path {reach}{under}"
        return
    gen = _utility.ShortestPathsGenerator(dtmc, BitVector(dtmc.nr_states, sorted(first)))
    tm = dtmc.transition_matrix
    k = 0
    found: list[RawPath] = []
    while len(found) < w.k:
        k += 1
        if k > w.k * SEARCH_FACTOR:
            out.witness_note = (f"stopped after {k - 1} paths: the others break the step bound "
                                "or leave the until's left side")
            break
        try:
            p = float(gen.get_distance(k))
            states = list(gen.get_path_as_list(k))
        except (RuntimeError, IndexError):
            break
        if p <= 0.0 or not states:
            break
        states.reverse()
        if states[-1] in dead or (bound is not None and len(states) - 1 > bound):
            continue
        steps = []
        for a, b in itertools.pairwise(states):
            steps.append(sum(float(e.value) for e in tm.get_row(tm.get_row_group_start(a))
                             if int(e.column) == b))
        found.append(RawPath(p, [tuple(int(x) for x in vals[s]) for s in states],
                             [_command(dtmc, s, vals[s], extract, out.variables)
                              for s in states[:-1]] + [-1], steps))
    if not found and not out.witness_note:
        out.witness_note = f"no path {reach}{under}"
    elif len(found) < w.k and not out.witness_note:
        out.witness_note = f"there are only {len(found)} paths into the target states"
    out.paths = found


def _frontier(dtmc: Any, init: int, stops: set[int]) -> set[int]:
    """The states of `stops` that a path from `init` reaches before any other of them
    (Storm's graph search, which does not go on from a stop)."""
    from stormpy import developer
    from stormpy.datastructures import BitVector

    n = int(dtmc.nr_states)
    go_on = BitVector(n, sorted(set(range(n)) - stops))
    reached = developer.get_reachable_states(dtmc.transition_matrix, BitVector(n, [init]),
                                             go_on, BitVector(n, sorted(stops)))
    return {int(s) for s in reached} & stops


def _command(dtmc: Any, s: int, row: Any, extract: Extract, variables: tuple[str, ...]) -> int:
    """The lowered command of state `s`'s choice: by its action label, and the mode."""
    labels = dtmc.choice_labeling.get_labels_of_choice(s) if dtmc.has_choice_labeling() \
        else set()
    mode = int(row[variables.index("mode")]) if "mode" in variables else 0
    for i, (label, modes) in enumerate(extract.commands):
        if mode in modes and (label in labels if label else not labels):
            return i
    return -1


def _target(stormpy: Any, program: Any, dtmc: Any, prop: Any,
            w: WitnessRequest) -> tuple[set[int] | None, set[int] | None, int | None]:
    """The target states, the states an until's left side allows (None: all), and a step
    bound (None: none) of the query's path formula."""
    formula = prop.get_raw_formula()
    path = formula.subformula if hasattr(formula, "subformula") else None
    bound: int | None = None
    left: Any = None
    if path is None:
        return None, None, None
    kind = type(path).__name__
    if kind == "EventuallyFormula":
        right = path.subformula
    elif kind in ("UntilFormula", "BoundedUntilFormula"):
        left, right = path.left_subformula, path.right_subformula
        if kind == "BoundedUntilFormula":
            bound = int(path.upper_bound_expression.evaluate_as_int())
            if str(left) == "true":
                left = None
    else:
        return None, None, None
    if w.avoid and bound is None:
        # prob0 states come out of Storm's graph analysis as exact zeros (an exact
        # model's are rationals, which equal 0 but not 0.0)
        whole = stormpy.parse_properties(f"P=? [ {path} ]", program)[0]
        values = stormpy.model_checking(dtmc, whole).get_value_vector()
        return {s for s in range(dtmc.nr_states) if float(values[s]) == 0.0}, None, None
    if w.target is not None:
        right = stormpy.parse_properties(f"P=? [ F ({w.target}) ]", program)[0] \
            .get_raw_formula().subformula.subformula
    return (_states(stormpy, dtmc, right),
            None if left is None else _states(stormpy, dtmc, left), bound)


def _states(stormpy: Any, dtmc: Any, formula: Any) -> set[int]:
    """The states where a state formula holds (iterating a BitVector gives its set bits)."""
    return {int(s) for s in stormpy.model_checking(dtmc, formula).get_truth_values_vector()}
