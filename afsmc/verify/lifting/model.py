"""The explored model of a mission with interval probabilities, each branch probability
known as a function of them (afsmc.verify.lifting).

afsmc's explorer (afsmc.verify.explorer.explore) explores the model once, at a generic
point p0 of the box (not its midpoint, where distinct functions such as P and a constant
0.5 could coincide), and evaluates each branch's probability at the box's 2^k corners
too, merged as the branches are. Every probability is multilinear in the parameters
(afsmc.verify.lifting.symbolic, checked before), so its corner values determine it: its
value at any point x is their multilinear interpolation, `values_at`. The structure (the
states, the branches) does not depend on the point: the parameters appear only in
probabilities (E250), and a box whose every probability is positive at every corner keeps
it positive inside (a multilinear function's minimum over a box is at a corner).
"""

from __future__ import annotations

import itertools
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Literal

import numpy as np

from afsmc.lower.lowering import Lowered
from afsmc.model import expr as E
from afsmc.model import ir
from afsmc.model.semantics import inline
from afsmc.sim.compile import SimError
from afsmc.verify.arrays import acyclic
from afsmc.verify.arrays.acyclic import F64, Arrays
from afsmc.verify.explorer import explore, explore_graph
from afsmc.verify.lifting.symbolic import multilinear

Box = Mapping[str, tuple[float, float]]

# Where p0 lies in each interval, as a fraction of it: irrational-looking, so that two
# different branch functions almost surely differ there (the explorer checks it anyway)
GENERIC = (0.5127318, 0.4862217, 0.5341871, 0.4719433, 0.5263541, 0.4588191)
SUM_TOLERANCE = 1e-9  # a distribution's probabilities at a corner sum to 1 within this


class NotLiftable(Exception):
    """The explorer or the lifting does not take this mission: Storm's parametric engine
    bounds it instead. The message says why."""


@dataclass(frozen=True)
class Query:
    """One bound the passes compute: `prop`'s `end` ("min" or "max"), over the parameters
    in that direction, and over the scheduler in `sched` ("min"/"max"; "" on a DTMC)."""

    prop: str
    end: Literal["min", "max"]
    kind: Literal["P", "R"]
    sched: Literal["min", "max", ""]
    target: int  # into Lifted's targets
    reward: str


@dataclass
class Lifted:
    """The explored model and each branch probability's values at the box's corners."""

    arrays: Arrays
    codes: np.ndarray  # branch -> its probability's row of `corners`
    corners: F64  # (distinct probabilities) x (2^k corners of `box`)
    names: tuple[str, ...]  # the parameters, in the order of the corners' bits
    box: dict[str, tuple[float, float]]
    states: int
    choices: int
    transitions: int
    loop: np.ndarray  # branch -> whether it leads back to its own state
    # per layer, how many of its first states depend on the parameters, where the states
    # are renumbered so (afsmc.verify.lifting.order); None where they are not
    leading: np.ndarray | None = None

    def weights(self, points: Sequence[Mapping[str, float]]) -> F64:
        """(2^k corners) x (points): the multilinear interpolation's weights."""
        out = np.ones((1 << len(self.names), len(points)))
        for j, p in enumerate(points):
            for c, bits in enumerate(itertools.product((0, 1), repeat=len(self.names))):
                for name, bit in zip(self.names, bits, strict=True):
                    lo, hi = self.box[name]
                    t = (p[name] - lo) / (hi - lo) if hi > lo else 0.0
                    out[c, j] *= t if bit else 1.0 - t
        return out

    def values_at(self, points: Sequence[Mapping[str, float]]) -> F64:
        """(distinct probabilities) x (points): each branch probability at each point."""
        out: F64 = self.corners @ self.weights(points)
        return out


def corners_of(names: Sequence[str], box: Box) -> list[dict[str, float]]:
    """The box's 2^k corners, the first parameter's bit most significant."""
    return [{n: box[n][bit] for n, bit in zip(names, bits, strict=True)}
            for bits in itertools.product((0, 1), repeat=len(names))]


def center(box: Box) -> dict[str, float]:
    return {n: (lo + hi) / 2 for n, (lo, hi) in box.items()}


def check_multilinear(low: Lowered, names: Sequence[str]) -> None:
    """NotLiftable unless every branch probability is multilinear in `names`."""
    params = set(names)
    for cmd in low.commands:
        for b in cmd.branches:
            e = inline(b.prob, low.model)
            if E.consts_read(e) & params and not multilinear(e, params):
                raise NotLiftable(f"a probability of {cmd.action} is not multilinear in the "
                                  "interval probabilities")


def build(low: Lowered, box: Box, targets: Sequence[E.Expr], rewards: Sequence[str],
          max_states: int | None = None, max_bytes: int | None = None) -> Lifted:
    """Explore `low` (its interval probabilities given values: the nondet lowering at the
    midpoint) once, with each branch probability's values at the corners of `box`."""
    if not box:
        raise NotLiftable("no interval probabilities")
    names = tuple(sorted(box))
    check_multilinear(low, names)
    p0 = {n: lo + (hi - lo) * GENERIC[i % len(GENERIC)]
          for i, (n, (lo, hi)) in enumerate((n, box[n]) for n in names)}
    corners = corners_of(names, box)
    try:
        compiled = explore.compile_model(low, list(targets), list(rewards), points=[p0, *corners])
        found = explore_graph.explore(compiled, None, max_states, max_bytes)
    except (explore.GiveUp, SimError) as exc:
        raise NotLiftable(f"afsmc's explorer does not take it ({exc})") from None
    except explore.TooManyStates as exc:
        raise NotLiftable(f"more than {exc.states:,} states") from None
    a = found.arrays
    assert compiled.at is not None and isinstance(a.prob, acyclic.Coded)
    table = a.prob.table
    rows = np.array([compiled.at.row(float(v)) for v in table.tolist()]).reshape(len(table), -1)
    owner = acyclic._state_of_branches(a.states, a.choices)
    loop = a.target == owner
    del owner
    lifted = Lifted(a, a.prob.codes, rows, names, {n: box[n] for n in names}, found.states,
                    found.choices, found.transitions, loop)
    why = ill_defined(lifted)
    if why is not None:
        raise NotLiftable(why)
    return lifted


def ill_defined(lifted: Lifted) -> str | None:
    """Why the box is not one lifting takes, or None: a branch probability outside (0, 1]
    at a corner (a transition that disappears: Storm's route reports E440). That every
    distribution sums to 1 at every corner the explorer checked as it evaluated them
    (explore._command)."""
    bad = (lifted.corners <= 0.0) | (lifted.corners > 1.0)
    if bad.any():
        return "a branch probability leaves (0, 1] at a corner of the box"
    return None


def queries(low: Lowered, props: Sequence[ir.Property]
            ) -> tuple[list[Query], list[E.Expr], list[str], list[str]]:
    """The lifted queries of the properties the passes answer (P [F T] and R{"r"} [F T]
    without a step bound: min and max each), their targets and reward structures, and
    the names of the others (left to Storm's parametric engine)."""
    out: list[Query] = []
    targets: list[E.Expr] = []
    rewards: list[str] = []
    left: list[str] = []
    keys: dict[str, int] = {}
    for p in props:
        path = p.path
        if path.kind != "F" or path.bound is not None or path.target is None or (
                p.kind == "R" and not p.reward) or p.kind not in ("P", "R"):
            left.append(p.name)
            continue
        key = repr(path.target)
        if key not in keys:
            keys[key] = len(targets)
            targets.append(path.target)
        reward = (p.reward or "") if p.kind == "R" else ""
        if reward and reward not in rewards:
            rewards.append(reward)
        kind: Literal["P", "R"] = "P" if p.kind == "P" else "R"
        for end in ("min", "max"):
            sched = (p.opt or end) if low.kind == "mdp" else ""
            out.append(Query(p.name, end, kind, sched,
                             keys[key], reward))
    return out, targets, rewards, left
