"""Monotonicity of a query's value over a box, proven by an interval bound on its slopes
carried along the backward pass (afsmc.verify.lifting; docs/uncertainty.md,
"Monotonicity from the slopes").

For a state s and a parameter p_i, the **slope** of s over a box is the set of difference
quotients (V_s(x + h e_i) - V_s(x)) / h for x and x + h e_i in the box, h > 0. The pass
carries an interval [lo, hi] containing it, state by state from the absorbing states back
to the initial one, next to the lifted bounds [Vlo, Vhi] of the value (the lifted passes
of afsmc.verify.lifting.passes, both ends, under the query's scheduler):

* a choice's value is T(x) / (1 - s(x)), T = r + sum_j P_j(x) V_j(x) over the branches
  that leave the state and s the self-loop's probability. Moving x along p_i,
  (1 - s(x)) * quotient(V) = sum_j D_j(x) V_j(x + h e_i) + sum_j P_j(x) quotient(V_j),
  the first sum over every branch (the self-loop's V_j is the state's own value), where
  D_j = dP_j/dp_i, constant along p_i since P_j is multilinear. With V_j(y) in
  [Vlo_j, Vhi_j] and quotient(V_j) in the successor's slope, the numerator is at least
  N(x) = sum_j min(D_j(x) Vlo_j, D_j(x) Vhi_j) + sum_j P_j(x) lo_j: concave in each
  parameter separately (a minimum of affine functions of an affine function plus an
  affine function), so its least value over the box is at a corner; likewise the most
  with max and hi_j. Dividing the numerator's interval by the interval of 1 - s over the
  corners (positive) bounds the choice's slope;
* a state's value is the best of its choices' (the scheduler's min or max): its
  quotient lies between the least of the choices' lower slopes and the most of their
  upper ones (with a the choice best at x + h e_i and b at x, for a minimum,
  V(x + h e_i) - V(x) is at least f_a(x + h e_i) - f_a(x) and at most
  f_b(x + h e_i) - f_b(x));
* a target, and a state that only loops, has a constant value: slope [0, 0].

If the initial state's slope excludes the inside of 0 for every parameter (lo >= 0: the
value does not decrease along it; hi <= 0: does not increase), the value is monotone in
each parameter over the box, so its least and greatest values are at two known corners
and a point pass at each gives them exactly (afsmc.verify.lifting.passes.attained). On
every sub-box the same holds with the same corners' rule.

Rounding: each state's numerator is widened by a bound of its floating-point error
(`_rounding`), where any of its terms is not exactly zero; a state none of whose terms
can be non-zero (every branch's D_j exactly 0, as its probability does not read p_i, or
its successor's bounds exactly [0, 0]; and every successor's slope exactly [0, 0]) has
slope exactly [0, 0].
"""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from afsmc.verify.arrays import acyclic
from afsmc.verify.arrays.acyclic import F64
from afsmc.verify.lifting import passes
from afsmc.verify.lifting.model import Box, Lifted, Query, center, corners_of

UNIT = 2.0 ** -53  # the unit roundoff of a double


@dataclass(frozen=True)
class Slopes:
    """A query's lifted bounds at the initial state over a box (`low`, `high`) and, per
    parameter (in the lifted model's order), an interval containing the value's slope."""

    low: float
    high: float
    slopes: tuple[tuple[float, float], ...]

    def signs(self) -> tuple[int, ...] | None:
        """Per parameter +1 (the value does not decrease along it), -1 (does not
        increase) or 0 (does not depend on it); None unless every parameter has one."""
        out = []
        for lo, hi in self.slopes:
            if lo == 0.0 and hi == 0.0:
                out.append(0)
            elif lo >= 0.0:
                out.append(1)
            elif hi <= 0.0:
                out.append(-1)
            else:
                return None
        return tuple(out)


def extreme_corner(names: Sequence[str], box: Box, signs: Sequence[int], end: str
                   ) -> dict[str, float]:
    """The corner of `box` where a value monotone with `signs` is least (`end` "min") or
    greatest ("max")."""
    up = end == "max"
    return {n: box[n][1] if (s > 0) == up and s != 0 else box[n][0]
            for n, s in zip(names, signs, strict=True)}


def slopes(lifted: Lifted, q: Query, box: Box) -> Slopes:
    """`q`'s lifted bounds and slopes at the initial state over `box` (a sub-box of the
    lifted model's), under `q`'s scheduler (`q.end` is not read: both ends)."""
    a = lifted.arrays
    k = len(lifted.names)
    corners = corners_of(lifted.names, box)
    probs = lifted.values_at(corners)  # distinct probabilities x corners
    ends = [dataclasses.replace(q, end="min"), dataclasses.replace(q, end="max")]
    value = passes.sweep(lifted, ends, probs, lift=True, every=True)[0][:, 0, :]  # n x 2
    deriv = _derivatives(probs, lifted.names, box)
    slope = _pass(lifted, q, value, probs, deriv)
    lo, hi = value[a.initial]
    return Slopes(float(lo), float(hi),
                  tuple((float(slope[a.initial, i, 0]), float(slope[a.initial, i, 1]))
                        for i in range(k)))


def _derivatives(probs: F64, names: Sequence[str], box: Box) -> F64:
    """(distinct probabilities) x corners x parameters: each probability's partial
    derivative in each parameter at each corner (constant along that parameter, as the
    probability is multilinear: the two corners that differ in its bit get the same)."""
    k = len(names)
    out = np.zeros((*probs.shape, k))
    for i, n in enumerate(names):
        width = box[n][1] - box[n][0]
        if width <= 0.0:
            continue  # the parameter does not vary: its slope is never needed
        bit = 1 << (k - 1 - i)
        for c in range(probs.shape[1]):
            out[:, c, i] = (probs[:, c | bit] - probs[:, c & ~bit]) / width
    return out


def _rounding(lifted: Lifted, value: F64, deriv: F64) -> tuple[float, float]:
    """(gamma, e0): a bound gamma of the relative error of one state's sums (each branch's
    term and their sum, at most `most` branches a choice: (most + 4) roundings), and e0,
    the error the lifted bounds' own rounding adds to a numerator (the sum of a choice's
    |D_j| times the bounds' accumulated error, at most one gamma of the largest value per
    layer). A numerator's error is at most gamma * (largest slope so far) + e0."""
    a = lifted.arrays
    most = int(np.diff(a.choices).max(initial=1))
    gamma = 2.0 * (most + 4) * UNIT
    finite = value[np.isfinite(value)]
    vmax = float(np.abs(finite).max(initial=0.0))
    dmax = float(np.abs(deriv).max(initial=0.0))
    layers = len(a.layers)
    return gamma, gamma * most * dmax * vmax * (layers + 1)


def _pass(lifted: Lifted, q: Query, value: F64, probs: F64, deriv: F64) -> F64:
    """Every state's slope interval (states x parameters x (lo, hi)), layer by layer."""
    a = lifted.arrays
    n, k = len(a.states) - 1, len(lifted.names)
    corners = probs.shape[1]
    slope = np.zeros((n, k, 2))
    on_target = a.labels[acyclic.LABEL + str(q.target)]
    finite: npt.NDArray[np.bool_] = np.asarray(np.isfinite(value).all(axis=1))
    varies = (probs != probs[:, :1]).any(axis=1)
    fixed = np.where(varies, 0.0, probs[:, 0])
    gamma, e0 = _rounding(lifted, value, deriv)
    largest = 0.0  # the largest |slope| bound so far (finite)
    trim = n > passes.TRIM_STATES
    per_span = max(64, passes.SPAN_ELEMENTS // (corners * k * 4))
    for i, (lo, hi) in enumerate(passes._spans(a.layers, per_span)):
        if trim and i % acyclic.TRIM_EVERY == acyclic.TRIM_EVERY - 1:
            acyclic.trim_heap()
        c0, c1 = int(a.states[lo]), int(a.states[hi])
        b0, b1 = int(a.choices[c0]), int(a.choices[c1])
        numer, den, nonzero = _numerators(lifted, b0, b1, c0, c1, value, slope, probs, deriv,
                                          varies, fixed)
        eps = gamma * largest + e0
        numer[:, :, 0] -= np.where(nonzero, eps, 0.0)
        numer[:, :, 1] += np.where(nonzero, eps, 0.0)
        per_choice = _divided(numer, den, gamma)
        rows = a.states[lo:hi] - c0
        if c1 - c0 == hi - lo:
            per_state = per_choice
        else:
            per_state = np.stack([np.minimum.reduceat(per_choice[:, :, 0], rows, axis=0),
                                  np.maximum.reduceat(per_choice[:, :, 1], rows, axis=0)],
                                 axis=2)
        per_state[on_target[lo:hi]] = 0.0
        unbounded = ~finite[lo:hi]
        per_state[unbounded, :, 0] = -np.inf
        per_state[unbounded, :, 1] = np.inf
        slope[lo:hi] = per_state
        bounded = per_state[np.isfinite(per_state)]
        largest = max(largest, float(np.abs(bounded).max(initial=0.0)))
    return slope


def _numerators(lifted: Lifted, b0: int, b1: int, c0: int, c1: int, value: F64, slope: F64,
                probs: F64, deriv: F64, varies: np.ndarray, fixed: F64
                ) -> tuple[F64, tuple[F64, F64], np.ndarray]:
    """The choices c0..c1's numerators' intervals (choices x parameters x (lo, hi)), the
    intervals of their 1 - s (each (choices,)), and per choice and parameter whether any
    term may be non-zero."""
    a = lifted.arrays
    rows = a.choices[c0:c1] - b0
    codes = lifted.codes[b0:b1]
    loop = lifted.loop[b0:b1]
    succ = slope[a.target[b0:b1]]  # branches x k x 2
    succ[loop] = 0.0  # the self-loop's share is the division by 1 - s
    vary = varies[codes]
    with np.errstate(invalid="ignore"):
        contrib = fixed[codes][:, None, None] * succ
    contrib[vary] = 0.0
    numer = np.add.reduceat(contrib, rows, axis=0)  # choices x k x 2
    stay = np.add.reduceat(np.where(loop & ~vary, fixed[codes], 0.0), rows)
    nonzero = np.add.reduceat((succ != 0.0).any(axis=2), rows, axis=0) > 0
    den_lo, den_hi = 1.0 - stay, 1.0 - stay
    vb = np.flatnonzero(vary)
    if vb.size:
        owner = np.repeat(np.arange(c1 - c0), np.diff(a.choices[c0:c1 + 1]))[vb]
        u, first = np.unique(owner, return_index=True)
        pv = probs[codes[vb]]  # nv x corners
        dv = deriv[codes[vb]]  # nv x corners x k
        v = value[a.target[b0:b1][vb]]  # nv x 2 (a self-loop's: the state's own bounds)
        sv = succ[vb]  # nv x k x 2
        with np.errstate(invalid="ignore"):
            d_lo, d_hi = dv * v[:, None, None, 0], dv * v[:, None, None, 1]
            t_lo = np.minimum(d_lo, d_hi) + pv[:, :, None] * sv[:, None, :, 0]
            t_hi = np.maximum(d_lo, d_hi) + pv[:, :, None] * sv[:, None, :, 1]
        n_lo = np.add.reduceat(t_lo, first, axis=0).min(axis=1)  # u x k
        n_hi = np.add.reduceat(t_hi, first, axis=0).max(axis=1)
        numer[u, :, 0] += np.where(np.isnan(n_lo), -np.inf, n_lo)
        numer[u, :, 1] += np.where(np.isnan(n_hi), np.inf, n_hi)
        s_u = stay[u][:, None] + np.add.reduceat(np.where(loop[vb][:, None], pv, 0.0),
                                                 first, axis=0)
        den_lo[u], den_hi[u] = 1.0 - s_u.max(axis=1), 1.0 - s_u.min(axis=1)
        # D_j * V_j(y) is an exact 0 where D_j is 0 or V_j is 0 at every point
        moves = (dv != 0.0).any(axis=1) & (v != 0.0).any(axis=1)[:, None]
        nonzero[u] |= np.add.reduceat(moves, first, axis=0) > 0
    numer[:, :, 0] = np.where(np.isnan(numer[:, :, 0]), -np.inf, numer[:, :, 0])
    numer[:, :, 1] = np.where(np.isnan(numer[:, :, 1]), np.inf, numer[:, :, 1])
    return numer, (den_lo, den_hi), nonzero


def _divided(numer: F64, den: tuple[F64, F64], gamma: float) -> F64:
    """The choices' slopes: each numerator's interval divided by its 1 - s's (positive),
    widened by one more rounding; a choice that only loops (1 - s = 0) keeps a constant
    value: [0, 0]."""
    den_lo, den_hi = (d[:, None] for d in den)
    lo, hi = numer[:, :, 0], numer[:, :, 1]
    out = np.empty_like(numer)
    with np.errstate(divide="ignore", invalid="ignore"):
        out[:, :, 0] = np.where(lo >= 0.0, lo / den_hi, lo / den_lo)
        out[:, :, 1] = np.where(hi >= 0.0, hi / den_lo, hi / den_hi)
    out[:, :, 0] -= gamma * np.abs(out[:, :, 0])
    out[:, :, 1] += gamma * np.abs(out[:, :, 1])
    out[(den_hi <= 0.0)[:, 0]] = 0.0
    return out


def exact_values(lifted: Lifted, q: Query, points: Sequence[Mapping[str, float]],
                 value_bytes: int, base: F64 | None = None) -> list[float]:
    """`q`'s value (under its scheduler) at each point, by point passes of as many points
    as `value_bytes` allows (a pass keeps a value per state and point). `base`: every
    state's value at one point, on a model renumbered by afsmc.verify.lifting.order (then
    only the states that depend on the parameters are computed)."""
    per = max(1, value_bytes // (8 * max(lifted.states, 1)))
    out: list[float] = []
    for i in range(0, len(points), per):
        part = list(points[i:i + per])
        out += passes.attained(lifted, [q] * len(part), lifted.values_at(part),
                               base).tolist()
    return out


def base_values(lifted: Lifted, q: Query) -> F64:
    """Every state's value of `q` at the box's centre: for a state whose value does not
    depend on the parameters, its value at every point (afsmc.verify.lifting.order)."""
    at = lifted.values_at([center(lifted.box)])
    out: F64 = passes.sweep(lifted, [q], at, lift=False, every=True)[0][:, 0, 0]
    return out
