"""The backward passes of parameter lifting on the explored model (afsmc.verify.lifting).

One pass visits the layers from the absorbing states back to the initial one, as the
exact pass does (afsmc.verify.arrays.acyclic), with each branch's probability given per
column of a table (afsmc.verify.lifting.model.Lifted.values_at):

* **at points** (`lift=False`): each query with its own valuation of the parameters; the
  values are those of the model there, exactly as a point-valued run computes them
  (attained values);
* **lifted** (`lift=True`): the columns the corners of a box; each state takes, for each
  of its choices, the worst corner for its own distribution in the query's direction
  (a minimum: the least value), independently of every other state, and then the
  scheduler's best choice. This is a relaxation of one fixed valuation for all states,
  hence an outer bound: by induction over the layers, a state's lifted value is at most
  (for a minimum) its value at any valuation in the box, because its value there is its
  successors' values weighted by probabilities at that valuation, the weighting is
  monotone in the successors' values, and over the box a choice's value for fixed
  successor values is extreme at a corner (multilinear in the parameters; with a
  self-loop of probability s, the ratio (rest) / (1 - s) is a ratio of functions affine
  in each parameter separately, so monotone in each, hence again extreme at a corner).
"""

from __future__ import annotations

import functools
import itertools
from collections.abc import Sequence

import numpy as np
import numpy.typing as npt

from afsmc.verify.arrays import acyclic
from afsmc.verify.arrays.acyclic import F64, I64
from afsmc.verify.lifting.model import Lifted, Query

# the most elements (branches x boxes x corners x queries) a span of states computes at a
# time: a layer of more is cut (its states do not depend on each other)
SPAN_ELEMENTS = 1 << 21
TRIM_STATES = 1 << 20  # a model of more states gives its heap back now and then in a pass


def attained(lifted: Lifted, qs: Sequence[Query], probs: F64, base: F64 | None = None
             ) -> F64:
    """Each query's value at the initial state with the branch probabilities of its own
    column of `probs` (distinct probabilities x queries): values at valuations, attained.
    `base`: see `sweep`."""
    values, _, _ = sweep(lifted, qs, probs, lift=False, base=base)
    return values


def lifted_bounds(lifted: Lifted, qs: Sequence[Query], probs: F64
                  ) -> tuple[F64, I64, npt.NDArray[np.bool_]]:
    """Each query's lifted bound at the initial state over the box whose corners are the
    columns of `probs`; the corner the choices' votes pick (`_votes`); and per parameter
    and query, whether the choices disagree on its end (the value may not be monotone in
    it: splitting the box along it may tighten the bound, along the others not)."""
    return sweep(lifted, qs, probs, lift=True)


def sweep(lifted: Lifted, qs: Sequence[Query], probs: F64, *, lift: bool, every: bool = False,
          base: F64 | None = None) -> tuple[F64, I64, npt.NDArray[np.bool_]]:
    """The pass: the initial state's value of each query and, lifted over one box, the
    corner the choices' votes pick for each and the parameters they disagree on.
    Lifted, the columns of `probs` are the corners of one box or of several, box after
    box (then the values are boxes x queries); else column j gives query j's
    probabilities. With `every`, the values of every state (states x boxes x queries)
    instead of the initial state's. With `base` (every state's value for these queries at
    any one point, on a model renumbered by afsmc.verify.lifting.order), only the states
    that depend on the parameters are computed, the others' values taken from it."""
    a = lifted.arrays
    n, q = len(a.states) - 1, len(qs)
    k = 1 << len(lifted.names) if lift else 1
    boxes = probs.shape[1] // k if lift else 1
    value = np.zeros((n, boxes, q))
    if base is not None:
        value[:] = base[:, None, None]
    kind = qs[0].kind
    if any(x.kind != kind for x in qs):
        raise ValueError("one pass answers queries of one kind")
    on_target = np.stack([a.labels[acyclic.LABEL + str(x.target)] for x in qs], axis=1)
    reward = (np.stack([_dense(a.rewards[x.reward]) for x in qs], axis=1)
              if kind == "R" else None)
    stuck, reached = (0.0, 1.0) if kind == "P" else (np.inf, 0.0)
    psign = np.array([1.0 if x.end == "min" else -1.0 for x in qs])
    ssign = np.array([-1.0 if x.sched == "max" else 1.0 for x in qs])
    votes = np.zeros((2, len(lifted.names), q))
    trim = n > TRIM_STATES
    # a probability the same in every column is summed once, not per corner: most of a
    # model's branches do not read an interval probability
    varies = (probs != probs[:, :1]).any(axis=1)
    fixed = np.where(varies, 0.0, probs[:, 0])
    per_span = max(64, SPAN_ELEMENTS // (boxes * q * 4))
    spans = _spans(a.layers, per_span, None if base is None else lifted.leading)
    for i, (lo, hi) in enumerate(spans):
        if trim and i % acyclic.TRIM_EVERY == acyclic.TRIM_EVERY - 1:
            acyclic.trim_heap()
        c0, c1 = int(a.states[lo]), int(a.states[hi])
        b0, b1 = int(a.choices[c0]), int(a.choices[c1])
        rows = a.choices[c0:c1] - b0
        codes = lifted.codes[b0:b1]
        loop = lifted.loop[b0:b1]
        succ = value[a.target[b0:b1]]  # branches x boxes x q
        succ[loop] = 0.0
        vb = np.flatnonzero(varies[codes])
        if 2 * vb.size > len(codes):  # mostly varying: every branch per corner
            vb = np.arange(len(codes))
            base = np.zeros((c1 - c0, boxes, q))
            stay = np.zeros(c1 - c0)
        else:
            pf = fixed[codes]
            with np.errstate(invalid="ignore"):
                contrib = pf[:, None, None] * succ
            contrib[vb] = 0.0  # a varying branch's placeholder 0 times an infinite value
            base = np.add.reduceat(contrib, rows, axis=0)  # choices x boxes x q
            stay = np.add.reduceat(np.where(loop, pf, 0.0), rows)
        if reward is not None:
            base += reward[c0:c1][:, None, :]
        per_choice = base.copy()
        loops = np.flatnonzero(stay > 0.0)  # few choices loop: solved where they do
        if loops.size:
            per_choice[loops] = _ratio(base[loops], stay[loops][:, None, None], stuck)
        if vb.size:
            # the choices with a branch that varies: each corner (or point) separately
            owner = np.repeat(np.arange(c1 - c0), np.diff(a.choices[c0:c1 + 1]))[vb]
            u, first = np.unique(owner, return_index=True)
            pv = probs[codes[vb]]
            pv = pv.reshape(len(vb), boxes, k, 1) if lift else pv[:, None, None, :]
            var = np.add.reduceat(pv * succ[vb][:, :, None, :], first, axis=0)
            s_u = stay[u][:, None, None, None] + np.add.reduceat(
                np.where(loop[vb][:, None, None, None], pv, 0.0), first, axis=0)
            signed = _ratio(base[u][:, :, None, :] + var, s_u, stuck) * psign
            if lift and boxes == 1:
                votes += _votes(signed[:, 0], len(lifted.names))
            per_choice[u] = signed.min(axis=2) * psign
        if c1 - c0 == hi - lo:  # one choice a state (a DTMC, or this span of an MDP)
            per_state = per_choice
        else:
            per_state = np.minimum.reduceat(per_choice * ssign, a.states[lo:hi] - c0,
                                            axis=0) * ssign
        hit = on_target[lo:hi]
        value[lo:hi] = per_state
        if hit.any():
            value[lo:hi][np.broadcast_to(hit[:, None, :], per_state.shape)] = reached
    # each parameter at the end most choices prefer: the corner of the first parameter's
    # bit most significant
    bits = (votes[1] > votes[0]).astype(np.int64)
    picks = (bits * (1 << np.arange(len(lifted.names) - 1, -1, -1))[:, None]).sum(axis=0)
    mixed: npt.NDArray[np.bool_] = np.all(votes > 0, axis=0)
    if every:
        return value, picks, mixed
    return value[a.initial] if boxes > 1 else value[a.initial, 0], picks, mixed


def _ratio(total: F64, stay: F64, stuck: float) -> F64:
    """A choice's value from its other branches' `total` and its self-loop's probability
    `stay`: total / (1 - stay), and `stuck` for a choice that only loops."""
    with np.errstate(divide="ignore", invalid="ignore"):
        out: F64 = np.where(stay >= 1.0, stuck, np.where(stay > 0.0, total / (1.0 - stay), total))
    return out


def _votes(signed: F64, k: int) -> F64:
    """Per parameter and query: how many choices prefer its lower end over its upper end
    ([0]) and the converse ([1]), comparing the best corner of either side (`signed`:
    choices x corners x queries, least is best). The corner these votes pick is where the
    refinement looks for an attained value: for a value monotone in each parameter, every
    choice that depends on a parameter prefers the same end."""
    out = np.zeros((2, k, signed.shape[2]))
    for i in range(k):
        # the corners with the parameter's bit 0 and 1 (the first parameter's the most
        # significant), their least values by elementwise minima of the corners' columns
        bit = 1 << (k - 1 - i)
        ends = [[c for c in range(1 << k) if bool(c & bit) == side] for side in (False, True)]
        lo, hi = (functools.reduce(np.minimum, [signed[:, c] for c in cs]) for cs in ends)
        with np.errstate(invalid="ignore"):
            d = hi - lo
            out[0, i] = (d > 0).sum(axis=0)
            out[1, i] = (d < 0).sum(axis=0)
    return out


def _dense(v: acyclic.Vec) -> F64:
    out: F64 = np.asarray(v[0:len(v)], np.float64)
    return out


def _spans(layers: I64, span: int, leading: npt.NDArray[np.int64] | None = None
           ) -> list[tuple[int, int]]:
    """The layers as ranges of states, those of more than `span` cut (their states are
    independent); with `leading`, only each layer's first `leading[i]` states."""
    out = []
    for i, (lo, hi) in enumerate(itertools.pairwise(layers.tolist())):
        end = hi if leading is None else lo + int(leading[i])
        out += [(x, min(x + span, end)) for x in range(lo, end, span)]
    return out
