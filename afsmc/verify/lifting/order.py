"""The explored model's states renumbered within each layer, those whose value depends on
the interval probabilities first (afsmc.verify.lifting).

A state **depends** on the parameters if a branch of one of its choices has a probability
that varies over the box, or leads to a state that depends (a self-loop to itself adds
nothing: its probability varies or it does not). Every other state has one value at
every point of the box: on the UAV more than half of them (56% of the default
instance's states over P_DROP x P_INIT_FAIL). The states of a layer do not depend on each
other, so their order within it is free: with the dependent ones first, a point pass
(afsmc.verify.lifting.passes.sweep with `base`) computes only a prefix of each layer and
takes the others' values from one pass made before, the same for every point.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from afsmc.verify.engines import acyclic
from afsmc.verify.engines.acyclic import I64, Idx
from afsmc.verify.lifting import passes
from afsmc.verify.lifting.model import Lifted


def dependent(lifted: Lifted) -> np.ndarray:
    """Per state, whether its value depends on the parameters over the lifted box."""
    a = lifted.arrays
    varies = (lifted.corners != lifted.corners[:, :1]).any(axis=1)
    out = np.zeros(len(a.states) - 1, dtype=bool)
    for lo, hi in passes._spans(a.layers, 1 << 20):
        c0, c1 = int(a.states[lo]), int(a.states[hi])
        b0, b1 = int(a.choices[c0]), int(a.choices[c1])
        by_branch = varies[lifted.codes[b0:b1]] | out[a.target[b0:b1]]
        by_choice = np.logical_or.reduceat(by_branch, a.choices[c0:c1] - b0)
        out[lo:hi] = np.logical_or.reduceat(by_choice, a.states[lo:hi] - c0)
    return out


def dependent_first(lifted: Lifted) -> Lifted:
    """`lifted` with each layer's dependent states first (the same layers, choices and
    branches, renumbered), and per layer how many of its states depend (`leading`)."""
    a = lifted.arrays
    dep = dependent(lifted)
    n = len(dep)
    layer_of = np.repeat(np.arange(len(a.layers) - 1), np.diff(a.layers))
    # the new order: by layer, dependent before independent, stable
    order = np.lexsort((np.arange(n), ~dep, layer_of))
    counts: I64 = np.add.reduceat(dep.astype(np.int64), a.layers[:-1]) if n else np.zeros(0,
                                                                                     np.int64)
    new_of = np.empty(n, dtype=np.int64)
    new_of[order] = np.arange(n)
    per_state = np.diff(a.states)[order]
    states: I64 = np.concatenate(([0], np.cumsum(per_state))).astype(np.int64)
    choice_order = acyclic._ranges(a.states[:-1][order], a.states[1:][order])
    per_choice = np.diff(a.choices)[choice_order]
    choices: I64 = np.concatenate(([0], np.cumsum(per_choice))).astype(np.int64)
    branch_order = acyclic._ranges(a.choices[:-1][choice_order], a.choices[1:][choice_order])
    target: Idx = new_of[np.asarray(a.target)[branch_order]].astype(a.target.dtype)
    assert isinstance(a.prob, acyclic.Coded)
    codes = a.prob.codes[branch_order]
    arrays = dataclasses.replace(
        a, states=states, choices=choices, target=target,
        prob=acyclic.Coded(a.prob.table, codes),
        stay=None if a.stay is None else np.asarray(a.stay[0:len(a.stay)])[choice_order],
        initial=int(new_of[a.initial]),
        labels={k: np.asarray(v)[order] for k, v in a.labels.items()},
        rewards={k: np.asarray(v[0:len(v)], np.float64)[choice_order]
                 for k, v in a.rewards.items()})
    return dataclasses.replace(lifted, arrays=arrays, codes=codes,
                               loop=lifted.loop[branch_order], leading=counts)
