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

from afsmc.verify.arrays import acyclic
from afsmc.verify.arrays.acyclic import I64
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


CHUNK_STATES = 1 << 20  # states renumbered at a time (whole layers), to bound the temporaries


def dependent_first(lifted: Lifted) -> Lifted:
    """`lifted` with each layer's dependent states first (the same layers, choices and
    branches, renumbered), and per layer how many of its states depend (`leading`).
    A layer's choices and branches keep their place as a whole, so the arrays are
    rewritten a group of layers at a time."""
    a = lifted.arrays
    assert isinstance(a.prob, acyclic.Coded)
    dep = dependent(lifted)
    n = len(dep)
    layer_of = np.repeat(np.arange(len(a.layers) - 1), np.diff(a.layers))
    # the new order: by layer, dependent before independent, stable
    order = np.lexsort((~dep, layer_of)).astype(np.int32)
    del layer_of
    new_of = np.empty(n, dtype=np.int32)
    new_of[order] = np.arange(n, dtype=np.int32)
    states, choices = np.empty_like(a.states), np.empty_like(a.choices)
    states[0], choices[0] = 0, 0
    target, codes = np.empty_like(a.target), np.empty_like(a.prob.codes)
    loop = np.empty_like(lifted.loop)
    stay = None if a.stay is None else np.asarray(a.stay[0:len(a.stay)])
    new_stay = None if stay is None else np.empty_like(stay)
    rewards = {k: np.asarray(v[0:len(v)], np.float64) for k, v in a.rewards.items()}
    new_rewards = {k: np.empty_like(v) for k, v in rewards.items()}
    for lo, hi in _chunks(a.layers):
        old = order[lo:hi]
        c0, b0 = int(a.states[lo]), int(a.choices[a.states[lo]])
        states[lo + 1:hi + 1] = c0 + np.cumsum(a.states[old + 1] - a.states[old])
        c_order = acyclic._ranges(a.states[old], a.states[old + 1])
        c1 = c0 + len(c_order)
        choices[c0 + 1:c1 + 1] = b0 + np.cumsum(a.choices[c_order + 1] - a.choices[c_order])
        b_order = acyclic._ranges(a.choices[c_order], a.choices[c_order + 1])
        b1 = b0 + len(b_order)
        target[b0:b1] = new_of[a.target[b_order]]
        codes[b0:b1] = a.prob.codes[b_order]
        loop[b0:b1] = lifted.loop[b_order]
        if stay is not None and new_stay is not None:
            new_stay[c0:c1] = stay[c_order]
        for k, v in rewards.items():
            new_rewards[k][c0:c1] = v[c_order]
    leading: I64 = np.add.reduceat(dep.astype(np.int64), a.layers[:-1])
    arrays = dataclasses.replace(
        a, states=states, choices=choices, target=target,
        prob=acyclic.Coded(a.prob.table, codes), stay=new_stay,
        initial=int(new_of[a.initial]),
        labels={k: np.asarray(v)[order] for k, v in a.labels.items()},
        rewards={k: _vec(v) for k, v in new_rewards.items()})
    return dataclasses.replace(lifted, arrays=arrays, codes=codes, loop=loop, leading=leading)


def _vec(v: np.ndarray) -> acyclic.Vec:
    out: acyclic.Vec = v
    return out


def _chunks(layers: I64) -> list[tuple[int, int]]:
    """Ranges of states of whole layers, each of about CHUNK_STATES states or one layer."""
    out: list[tuple[int, int]] = []
    start = 0
    bounds = layers.tolist()
    for end in bounds[1:]:
        if end - start >= CHUNK_STATES:
            out.append((start, end))
            start = end
    if start < bounds[-1]:
        out.append((start, bounds[-1]))
    return out
