"""Compiled kernels (numba) of a block's arrays in afsmc.verify.explorer.explore_graph._block:
which states are absorbing, and the block's choices and branches in its layered order;
and of afsmc.verify.explorer.explore._ordered, an expansion's choices sorted by state.
Each is one pass over the arrays where numpy sorts or builds index arrays first and
gathers through them (its code there is the reference the tests compare these with)."""

from __future__ import annotations

from typing import Any

import numpy as np
import numpy.typing as npt

from afsmc.verify.kernels import jit

I64 = npt.NDArray[np.int64]


@jit
def _absorbing(states: I64, choices: I64, target: I64, keys: I64, out: Any) -> None:
    for s in range(len(states) - 1):
        stays = True
        for b in range(choices[states[s]], choices[states[s + 1]]):
            if target[b] != keys[s]:
                stays = False
                break
        out[s] = stays


def absorbing(states: I64, choices: I64, target: I64, keys: I64) -> npt.NDArray[np.bool_]:
    """Per state (offsets `states` into the choices, `choices` into the branches): is every
    branch's successor key its own key?"""
    out = np.empty(len(states) - 1, np.bool_)
    _absorbing(states, choices, target, keys, out)
    return out


@jit
def _permute(perm: I64, states: I64, choices: I64, nbranch: Any, target: I64, prob: Any,
             old_choice: I64, nbranch_out: Any, target_out: I64, prob_out: Any) -> None:
    c_at = 0
    b_at = 0
    for s in perm:
        for c in range(states[s], states[s + 1]):
            old_choice[c_at] = c
            nbranch_out[c_at] = nbranch[c]
            c_at += 1
            for b in range(choices[c], choices[c + 1]):
                target_out[b_at] = target[b]
                prob_out[b_at] = prob[b]
                b_at += 1


def permuted(perm: I64, states: I64, choices: I64, nbranch: Any, target: I64, prob: Any
             ) -> tuple[I64, Any, I64, Any]:
    """The states in the order `perm` (a permutation of them): each choice's old index,
    its branch count, each branch's target and probability, as gathered through the
    choices' and the branches' ranges."""
    m = int(states[-1])
    k = int(choices[-1])
    old_choice = np.empty(m, np.int64)
    nbranch_out = np.empty(m, nbranch.dtype)
    target_out = np.empty(k, target.dtype)
    prob_out = np.empty(k, prob.dtype)
    _permute(perm, states, choices, nbranch, target, prob, old_choice, nbranch_out, target_out,
             prob_out)
    return old_choice, nbranch_out, target_out, prob_out


@jit
def _by_state(state: I64, per_state: I64, first: I64, order: I64, branch: I64) -> None:
    at = np.zeros(len(per_state) + 1, np.int64)
    for s in range(len(per_state)):
        at[s + 1] = at[s] + per_state[s]
    for c in range(len(state)):  # a counting sort: stable
        order[at[state[c]]] = c
        at[state[c]] += 1
    b_at = 0
    for c in order:
        for b in range(first[c], first[c + 1]):
            branch[b_at] = b
            b_at += 1


def by_state(state: I64, per_state: I64, first: I64) -> tuple[I64, I64]:
    """The choices (each of state `state[c]`, `per_state` of each state; choice c's
    branches first[c]:first[c + 1]) in the order of their states, stably: the order of
    the choices, and of the branches."""
    order = np.empty(len(state), np.int64)
    branch = np.empty(int(first[-1]), np.int64)
    _by_state(state, per_state, first, order, branch)
    return order, branch
