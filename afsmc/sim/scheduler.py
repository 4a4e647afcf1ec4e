"""Who moves in a run of a composed mission whose agents interleave (`compose
interleaving;`, or `compose timed ties nondet;` at equal clocks): the simulator's stated
scheduler, docs/simulation.md "Composed missions".

Each step, among the agents with an enabled action (one whose command's guard holds,
timing included), one is picked uniformly at random and its enabled action fires; a
synchronised action is an enabled action of each of its partners, so it fires when any of
them is picked. That is one memoryless randomised scheduler of the MDP, so every estimate
lies within verify's [min, max] (up to the Monte Carlo error).
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
import numpy.typing as npt

from afsmc.lower.compose import action_agents
from afsmc.lower.lowering import Lowered

UNIFORM = "uniform over the agents that can move"


def movers(low: Lowered) -> dict[int, tuple[int, ...]] | None:
    """For a composed MDP: each lowered command's index -> the agents (by declaration
    order) it moves; the mission's own self-loop moves none. None: no choice of mover
    (a single machine, or a timed composition whose ties are settled). `compose
    interleaving uniform;` is this scheduler made the mission's own (a DTMC)."""
    net = low.network
    if net is None or not (low.kind == "mdp" or net.ties == "uniform"):
        return None
    owner = action_agents(net)
    return {i: owner.get(c.action, ()) for i, c in enumerate(low.commands)
            if c.kind not in ("final", "deadlock")}


def pick(enabled: Sequence[npt.NDArray[np.bool_]], who: Sequence[tuple[int, ...]],
         agents: int, rng: np.random.Generator) -> npt.NDArray[np.int64]:
    """Each run's command (an index into `enabled`, -1: none): `enabled[c]` says in which
    runs command c is enabled, `who[c]` the agents it moves (() for the mission's
    self-loop, taken only where no agent can move). An agent picked uniformly among those
    with an enabled command takes its first enabled command."""
    n = len(enabled[0]) if enabled else 0
    first = np.full((agents, n), -1, dtype=np.int64)  # each agent's first enabled command
    for c in range(len(enabled) - 1, -1, -1):
        for a in who[c]:
            first[a][enabled[c]] = c
    can = first >= 0
    count = can.sum(axis=0)
    which = np.full(n, -1, dtype=np.int64)
    for c in range(len(enabled) - 1, -1, -1):  # no agent can move: the first enabled
        if not who[c]:
            which[enabled[c] & (count == 0)] = c
    live = count > 0
    if live.any():
        # the r-th agent (0-based) among those that can move, r uniform in [0, count)
        r = np.floor(rng.random(n) * np.maximum(count, 1)).astype(np.int64)
        rank = np.cumsum(can, axis=0) - 1
        chosen = np.argmax(can & (rank == r), axis=0)
        cols = np.arange(n)
        which[live] = first[chosen, cols][live]
    return which


def trace_names(low: Lowered) -> tuple[list[tuple[str, str, dict[int, str]]], dict[int, str]]:
    """A composed mission's sample runs in mission terms: each agent's name, mode
    variable and mode names ("uav1: Search"), and each command's action as "uav1: Look"
    (a synchronised one by its name). Empty for a single machine."""
    net = low.network
    if net is None:
        return [], {}
    modes = [(p.agent.name, p.agent.mode_var, {m.number: m.name for m in p.agent.model.modes})
             for p in net.parts]
    local = {c.action: f"{p.agent.name}: {c.action.removeprefix(p.agent.prefix)}"
             for p in net.parts for c in p.local}
    return modes, {i: local.get(c.action, c.action) for i, c in enumerate(low.commands)}


def displays(low: Lowered) -> dict[str, str]:
    """A composed mission's variables for people: `robot_b` is `robot.b`, the mode
    variable `robot_mode` is `robot.mode`; shared variables keep their names."""
    net = low.network
    out: dict[str, str] = {}
    for p in net.parts if net is not None else ():
        out[p.agent.mode_var] = f"{p.agent.name}.mode"
        for v in p.agent.model.variables:
            if v.name in p.agent.own:
                out[p.agent.prefix + v.name] = f"{p.agent.name}.{v.display}"
    return out
