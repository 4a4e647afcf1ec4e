"""Inside the Storm process: Storm's schedulers and most probable paths, as plain data.

A :class:`Extract` on a :class:`afsmc.verify.storm.Job` asks for more than values: the
scheduler of some queries (summarised per command and mode, over the states the scheduler
reaches), the whole scheduler of one query (for `simulate --strategy`), and the K most
probable paths of one query into its target states. The sparse model is then built with
state valuations and choice origins (which PRISM command each choice comes from); the
caller, who has the lowered model, maps command indices back to actions and interval
constants (:mod:`afsmc.verify.strategy`, :mod:`afsmc.verify.witness`).
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
    target (a failed requirement's violating states); None: the property's target."""

    query: str
    k: int
    target: str | None = None


@dataclass(frozen=True)
class Extract:
    strategies: tuple[str, ...] = ()  # queries whose scheduler is summarised
    policy: str | None = None  # a query whose scheduler is returned whole
    witness: WitnessRequest | None = None
    # the commands that are floor/ceil variants: in their states the scheduler chooses
    decisive: tuple[int, ...] = ()

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


def builder_options(stormpy: Any, props: list[Any]) -> Any:
    """Storm's builder options for `props` with state valuations and choice origins."""
    opts = stormpy.BuilderOptions([p.get_raw_formula() for p in props])
    opts.set_build_state_valuations()
    opts.set_build_choice_origins()
    opts.set_build_all_labels()
    return opts


def _variables(stormpy: Any, program: Any) -> list[tuple[str, Any, bool]]:
    out = []
    for module in program.modules:
        out += [(v.name, v.expression_variable, False) for v in module.integer_variables]
        out += [(v.name, v.expression_variable, True) for v in module.boolean_variables]
    return out


def _valuations(model: Any, variables: list[tuple[str, Any, bool]]) -> list[list[int]]:
    sv = model.state_valuations
    cols = []
    n = int(model.nr_states)
    for _, var, boolean in variables:
        if boolean:  # a BitVector: iterating it gives the states where the variable is true
            col = [0] * n
            for s in sv.get_boolean_values(var):
                col[int(s)] = 1
            cols.append(col)
        else:
            cols.append([int(x) for x in sv.get_int64_values(var)])
    return cols


def _commands(model: Any) -> list[int]:
    """The PRISM command of each state's first choice (-1: none, a state Storm fixed)."""
    co = model.choice_origins
    tm = model.transition_matrix
    out = []
    for s in range(model.nr_states):
        cs = list(co.get_command_set(tm.get_row_group_start(s)))
        out.append(int(cs[0]) if cs else -1)
    return out


def induced(stormpy: Any, model: Any, result: Any) -> Any:
    """The DTMC a query's scheduler induces on the states it reaches (a DTMC: itself)."""
    if not str(model.model_type).upper().endswith("MDP"):
        return model
    return model.apply_scheduler(result.get_scheduler(), True)


def analyse(stormpy: Any, program: Any, model: Any, name: str, prop: Any, result: Any,
            extract: Extract, out: Extracted) -> None:
    """Add what `extract` asks of query `name` (checked: `result`) to `out`."""
    import time

    t0 = time.perf_counter()
    variables = _variables(stormpy, program)
    out.variables = tuple(n for n, _, _ in variables)
    mdp = str(model.model_type).upper().endswith("MDP")
    if mdp and (name in extract.strategies or name == extract.policy):
        decisions = _decisions(model, prop, result, frozenset(extract.decisive))
        out.reached[name] = len(decisions)
        cols = _valuations(model, variables)
        if name in extract.strategies:
            out.groups[name] = _groups(decisions, cols, out.variables)
        if name == extract.policy:
            out.policy_states = [tuple(col[s] for col in cols) for s, _, _ in decisions]
            out.policy_commands = [c for _, c, _ in decisions]
    w = extract.witness
    if w is not None and w.query == name:
        out.witness_query = name
        dtmc = induced(stormpy, model, result)
        _paths(stormpy, program, dtmc, prop, w, _valuations(dtmc, variables), _commands(dtmc),
               out)
    out.seconds += time.perf_counter() - t0


def _groups(decisions: list[tuple[int, int, bool]], cols: list[list[int]],
            variables: tuple[str, ...]) -> list[Group]:
    """The decisions per command, mode and whether the end matters there."""
    mode_i = variables.index("mode") if "mode" in variables else -1
    groups: dict[tuple[int, int, bool], list[list[int]]] = {}
    for s, c, matters in decisions:
        row = [col[s] for col in cols]
        key = (c, row[mode_i] if mode_i >= 0 else 0, matters)
        g = groups.get(key)
        if g is None:
            groups[key] = [[1], row, list(row)]
        else:
            g[0][0] += 1
            g[1] = [min(a, b) for a, b in zip(g[1], row, strict=True)]
            g[2] = [max(a, b) for a, b in zip(g[2], row, strict=True)]
    return [Group(c, m, g[0][0], tuple(g[1]), tuple(g[2]), matters)
            for (c, m, matters), g in sorted(groups.items())]


# Two choices whose values differ by at most this (relative to the larger) are equal: the
# scheduler's choice between them is arbitrary.
SAME = 1e-9


def _decisions(model: Any, prop: Any, result: Any,
               decisive: frozenset[int]) -> list[tuple[int, int, bool]]:
    """(state, command, whether the end matters) for each state the scheduler reaches in
    which it resolves an interval constant. The end matters where another choice of the
    state has a different value (sum of probability x successor's value, plus the choice's
    reward for an expected reward)."""
    sched = result.get_scheduler()
    tm = model.transition_matrix
    co = model.choice_origins
    values = list(result.get_value_vector())
    action_rewards = _action_rewards(model, prop)
    seen = bytearray(int(model.nr_states))
    stack = [int(s) for s in model.initial_states]
    for s in stack:
        seen[s] = 1
    out = []
    while stack:
        s = stack.pop()
        first, last = tm.get_row_group_start(s), tm.get_row_group_end(s)
        row = first + sched.get_choice(s).get_deterministic_choice()
        for e in tm.get_row(row):
            t = int(e.column)
            if not seen[t]:
                seen[t] = 1
                stack.append(t)
        if last - first < 2:
            continue
        cs = list(co.get_command_set(row))
        if not cs or int(cs[0]) not in decisive:
            continue
        qs = [math.fsum(float(e.value) * values[int(e.column)] for e in tm.get_row(r))
              + (action_rewards[r] if action_rewards else 0.0) for r in range(first, last)]
        hi, lo = max(qs), min(qs)
        matters = not (hi == lo or abs(hi - lo) <= SAME * max(1.0, abs(hi), abs(lo)))
        out.append((s, int(cs[0]), matters))
    out.sort()
    return out


def _action_rewards(model: Any, prop: Any) -> list[float] | None:
    """The per-choice rewards of an expected-reward query's structure, if it has any."""
    formula = prop.get_raw_formula()
    if not formula.is_reward_operator_formula or not model.reward_models:
        return None
    name = formula.reward_name if formula.has_reward_model_name() else None
    rm = model.reward_models[name] if name else next(iter(model.reward_models.values()))
    return [float(x) for x in rm.state_action_rewards] if rm.has_state_action_rewards else None


# Paths the search may enumerate, per path asked, before it gives up on finding more that
# respect a step bound or an until's left side (the others are skipped).
SEARCH_FACTOR = 50


def _paths(stormpy: Any, program: Any, dtmc: Any, prop: Any, w: WitnessRequest,
           cols: list[list[int]], commands: list[int], out: Extracted) -> None:
    """The `w.k` most probable paths of the induced DTMC into the target states, by
    Storm's k-shortest-paths generator (recursive enumeration; paths stop at their first
    target state and may loop)."""
    from stormpy.analysis import _utility
    from stormpy.datastructures import BitVector

    target, left, bound = _target(stormpy, program, dtmc, prop, w)
    if target is None:
        out.witness_note = "the property has no target states to reach"
        return
    if not target:
        out.witness_note = "no state the strategy reaches is a target state"
        return
    bits = BitVector(dtmc.nr_states, sorted(target))
    gen = _utility.ShortestPathsGenerator(dtmc, bits)
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
        if bound is not None and len(states) - 1 > bound:
            continue
        if left is not None and not all(s in left for s in states[:-1]):
            continue
        steps = []
        for a, b in itertools.pairwise(states):
            steps.append(sum(float(e.value) for e in tm.get_row(tm.get_row_group_start(a))
                             if int(e.column) == b))
        found.append(RawPath(p, [tuple(col[s] for col in cols) for s in states],
                             [commands[s] for s in states[:-1]] + [-1], steps))
    if len(found) < w.k and not out.witness_note:
        out.witness_note = f"there are only {len(found)} paths into the target states"
    out.paths = found


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
    if w.target is not None:
        right = stormpy.parse_properties(f"P=? [ F ({w.target}) ]", program)[0] \
            .get_raw_formula().subformula.subformula
    return (_states(stormpy, dtmc, right),
            None if left is None else _states(stormpy, dtmc, left), bound)


def _states(stormpy: Any, dtmc: Any, formula: Any) -> set[int]:
    """The states where a state formula holds (iterating a BitVector gives its set bits)."""
    return {int(s) for s in stormpy.model_checking(dtmc, formula).get_truth_values_vector()}
