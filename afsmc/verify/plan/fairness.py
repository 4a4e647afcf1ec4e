"""Min and max over fair schedulers (`compose interleaving fair;`, docs/language.md): a
scheduler is fair if, on almost every path, every agent that is able to move from some
point on moves infinitely often (weak fairness, per agent).

What fairness changes. Whatever a finite prefix decides (`F<=k`, `C<=k`, `I=k`, `X`) is
the same over fair schedulers as over all: any prefix continues fairly (say, every
enabled move with equal probability from then on). The supremum of reaching a target
(`Pmax F`, `Pmax U`, `Pmin G`) and the least expected reward of reaching it (`Rmin F`) are
the same too: the optimum over all schedulers is approached by one that follows the
optimal scheduler for n steps and then moves fairly. What changes is staying away from a
target forever (`Pmin F`, `Pmin U`, `Pmax G`): an unfair scheduler may starve an agent to
stay away. Over fair schedulers (Baier and Katoen, Principles of Model Checking, 10.6.3):

    Pmin_fair(L U T) = 1 - Pmax(K U (B or U_fair)), and Pmax_fair(G K) = Pmax(K U U_fair)

where K are the states that stay away (L and not T; for G, the states of K), B those
that fail (not L and not T), and U_fair the states of the fair end components within K.
Every path that stays in K forever ends, almost surely, in an end component of K, and
its moves there are fair only if for each agent the component holds a move of that agent
or a state where the agent cannot move; such a component is fair exactly when its
maximal end component is (a sub-component of an unfair one lacks the same agent's moves
in states where it can move). A scheduler can stay in a fair component fairly (every
move of the component with equal probability), so the bound is attained. `Rmax F` under
fairness is the same where it is finite (every scheduler then reaches the target almost
surely, the optimum approached as above); where it is infinite (a scheduler may stay
away), it is refused.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any

import numpy as np
from scipy.sparse import csr_matrix
from scipy.sparse.csgraph import connected_components

KEEP, GOAL = "__afsmc_fair_keep", "__afsmc_fair_goal"


class Refused(Exception):
    """A query afsmc does not answer over fair schedulers (the message says which)."""


def check(stormpy: Any, model: Any, prop: Any, value: float,
          movers: Mapping[str, tuple[int, ...]], agents: int, env: Any) -> float | None:
    """The value at the initial state of `prop` over the fair schedulers of `model` (a
    sparse MDP built with choice labels: each choice's labels are actions, `movers` the
    agents each action moves), or None where fairness changes nothing (Storm's own
    `value`, over all schedulers, stands). Raises Refused."""
    raw = prop.get_raw_formula()
    kind = type(raw).__name__
    minimise = str(raw.optimality_type).upper().endswith("MINIMIZE")
    if kind == "RewardOperatorFormula":
        if not minimise and type(raw.subformula).__name__ == "EventuallyFormula" \
                and math.isinf(value):
            raise Refused("a maximal expected reward to reach a target over fair schedulers "
                          "is not computed (an unfair scheduler may never reach it)")
        return None
    if kind != "ProbabilityOperatorFormula":
        return None
    path = raw.subformula
    shape = type(path).__name__
    if minimise and shape in ("EventuallyFormula", "UntilFormula"):
        goal = _states(stormpy, model, path.subformula if shape == "EventuallyFormula"
                       else path.right_subformula)
        left = (np.ones(model.nr_states, dtype=bool) if shape == "EventuallyFormula"
                else _states(stormpy, model, path.left_subformula))
        keep = left & ~goal
        fail = ~left & ~goal
        return 1.0 - _reach(stormpy, model, keep, fail | fair_states(model, keep, movers,
                                                                      agents), env)
    if not minimise and shape == "GloballyFormula":
        keep = _states(stormpy, model, path.subformula)
        return _reach(stormpy, model, keep, fair_states(model, keep, movers, agents), env)
    return None


def _states(stormpy: Any, model: Any, formula: Any) -> np.ndarray:
    out = np.zeros(model.nr_states, dtype=bool)
    out[[int(s) for s in stormpy.model_checking(model, formula).get_truth_values_vector()]] = True
    return out


def _reach(stormpy: Any, model: Any, keep: np.ndarray, goal: np.ndarray, env: Any) -> float:
    """Pmax [ keep U goal ] at the initial state, by Storm."""
    from stormpy.developer import storage

    for name, states in ((KEEP, keep), (GOAL, goal)):
        if not model.labeling.contains_label(name):
            model.labeling.add_label(name)
        bits = storage.BitVector(model.nr_states, [int(s) for s in np.flatnonzero(states)])
        model.labeling.set_states(name, bits)
    (prop,) = stormpy.parse_properties(f'Pmax=? [ "{KEEP}" U "{GOAL}" ]')
    r = (stormpy.model_checking(model, prop) if env is None
         else stormpy.model_checking(model, prop, environment=env))
    return float(r.get_value(model.initial_states[0]))


def _choices(model: Any, movers: Mapping[str, tuple[int, ...]]
             ) -> list[list[tuple[int, tuple[int, ...], tuple[int, ...]]]]:
    """Each state's choices: (choice index, successors, agents it moves)."""
    matrix = model.transition_matrix
    labels = model.choice_labeling
    out: list[list[tuple[int, tuple[int, ...], tuple[int, ...]]]] = []
    for s in range(model.nr_states):
        row: list[tuple[int, tuple[int, ...], tuple[int, ...]]] = []
        for c in range(matrix.get_row_group_start(s), matrix.get_row_group_end(s)):
            succ = tuple(e.column for e in matrix.get_row(c) if e.value > 0)
            who = sorted({a for name in labels.get_labels_of_choice(c)
                          for a in movers.get(name, ())})
            row.append((c, succ, tuple(who)))
        out.append(row)
    return out


def fair_states(model: Any, keep: np.ndarray, movers: Mapping[str, tuple[int, ...]],
                agents: int) -> np.ndarray:
    """The states of the fair maximal end components of the sub-MDP of `keep`."""
    choices = _choices(model, movers)
    n = model.nr_states
    inside = keep.copy()
    allowed = [[ch for ch in choices[s] if all(inside[t] for t in ch[1])] if inside[s] else []
               for s in range(n)]
    comp = np.full(n, -1)
    while True:
        for s in range(n):
            if inside[s] and not allowed[s]:
                inside[s] = False
        rows, cols = [], []
        for s in range(n):
            for _, succ, _ in allowed[s] if inside[s] else ():
                rows += [s] * len(succ)
                cols += list(succ)
        graph = csr_matrix((np.ones(len(rows)), (rows, cols)), shape=(n, n))
        _, comp = connected_components(graph, directed=True, connection="strong")
        changed = False
        for s in range(n):
            if not inside[s]:
                continue
            kept = [ch for ch in allowed[s]
                    if all(inside[t] and comp[t] == comp[s] for t in ch[1])]
            if len(kept) != len(allowed[s]):
                allowed[s], changed = kept, True
            if not kept:
                inside[s], changed = False, True
        if not changed:
            break
    out = np.zeros(n, dtype=bool)
    for c in {int(comp[s]) for s in range(n) if inside[s]}:
        members = [s for s in range(n) if inside[s] and comp[s] == c]
        moved = {a for s in members for _, _, who in allowed[s] for a in who}
        able = [{a for _, _, who in choices[s] for a in who} for s in members]
        if all(a in moved or any(a not in can for can in able) for a in range(agents)):
            out[members] = True
    return out
