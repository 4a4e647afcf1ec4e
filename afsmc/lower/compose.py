"""A composed mission lowered: each agent lowered as a machine of its own, its commands
renamed into the mission's variables, then put together (docs/language.md, "Composition").

* An agent's command keeps its guard (Definition 2 within the agent); its mode is the
  variable `<agent>_mode`, its own variables `<agent>_x`. Its final and deadlock
  self-loops go: an agent that cannot move simply does not; the mission stays where it
  is (one silent self-loop) only when no agent can move.
* A synchronised action: one command per combination of its partners' commands, guarded
  by all their guards, each branch a product of theirs (PRISM's synchronous product).
* Interleaving: every agent's commands stand side by side (an MDP). `compose interleaving
  uniform;` (ties "uniform"): who moves next is uniform among the agents that can move, a
  DTMC. Each agent has at most one enabled command (Definition 2 within the agent, and no
  interval constant: E253), and a DTMC's semantics (PRISM's and Storm's, both routes)
  takes each enabled command of the product with equal probability; a synchronised
  action moves all its partners, so it is taken when any of them is picked: its
  combination of commands is repeated once per partner (in the first partner's commands),
  which gives it the weight (partners)/(agents that can move), as the simulator picks
  (afsmc.sim.scheduler). Timed: a command may
  fire only if its agents' least clock is no greater than that of any other agent that
  can move (ties: `order`, the agent declared first; `nondet`, all of them).
"""

from __future__ import annotations

import itertools
from collections.abc import Callable
from dataclasses import dataclass

from afsmc.lower.lowering import Branch, Command, Lowered, Resolution, lower
from afsmc.model import expr as E
from afsmc.model import ir
from afsmc.model.expr import Type
from afsmc.model.semantics import inline


@dataclass(frozen=True)
class Part:
    """One agent's commands in the mission's names: `local` are its own, `sync` each of
    its synchronised actions' commands by name; `timing` the condition under which it may
    move first (timed composition; TRUE otherwise)."""

    agent: ir.Agent
    local: tuple[Command, ...]
    sync: tuple[tuple[str, tuple[Command, ...]], ...]
    timing: E.Expr
    sync_timing: tuple[tuple[str, E.Expr], ...]


@dataclass(frozen=True)
class Network:
    kind: str  # "interleaving" | "timed"
    ties: str
    parts: tuple[Part, ...]
    stay: Command  # the mission's self-loop where no agent can move
    # agents' own variables that other agents' commands write (the symmetry reduction's
    # canonical order, afsmc.lower.symmetry): PRISM declares them global
    global_locals: frozenset[str] = frozenset()


def _renamer(agent: ir.Agent) -> Callable[[E.Expr], E.Expr]:
    model = agent.model
    mode_var = E.VarRef(agent.mode_var, Type.INT)

    def fn(n: E.Expr) -> E.Expr | None:
        if isinstance(n, E.CurrentMode):
            return mode_var
        if isinstance(n, E.ModeVal):
            return E.Lit(n.number, Type.INT, n.span)
        if isinstance(n, E.VarRef) and n.name in agent.own:
            return E.VarRef(agent.prefix + n.name, n.type, n.span)
        return None

    def go(e: E.Expr) -> E.Expr:
        return E.transform(inline(e, model), fn)
    return go


def _rename(agent: ir.Agent, cmd: Command, name: str) -> Command:
    go = _renamer(agent)
    branches = tuple(Branch(go(b.prob), tuple(
        (agent.mode_var if v == "mode" else agent.mission_name(v), go(x)) for v, x in b.updates),
        b.span, b.hazard) for b in cmd.branches)
    # The mission has one mode (its states are the agents' modes, tested in the guard).
    return Command(name, (0,), go(cmd.guard), branches, cmd.span, cmd.choice, cmd.kind)


def _product(cmds: tuple[Command, ...], name: str, guard: E.Expr) -> Command:
    branches = []
    for combo in itertools.product(*(c.branches for c in cmds)):
        prob = combo[0].prob
        for b in combo[1:]:
            prob = E.mul(prob, b.prob)
        updates = tuple(u for b in combo for u in b.updates)
        hazard = next((b.hazard for b in combo if b.hazard), None)
        branches.append(Branch(prob, updates, combo[0].span, hazard))
    choice = tuple(x for c in cmds for x in c.choice)
    return Command(name, cmds[0].modes, E.conj(guard, *(c.guard for c in cmds)),
                   tuple(branches), cmds[0].span, choice, "action")


def lower_composed(model: ir.Model, resolution: Resolution = "nondet") -> Lowered:
    comp = model.composition
    assert comp is not None
    bounds: dict[str, tuple[str, int]] = {}
    weights: dict[str, E.Expr] = {}
    raw: list[tuple[ir.Agent, list[Command], dict[str, list[Command]]]] = []
    for agent in comp.agents:
        low = lower(agent.model, resolution)
        bounds.update(low.bounds)
        local: list[Command] = []
        sync: dict[str, list[Command]] = {}
        for c in low.commands:
            if c.kind in ("final", "deadlock"):
                continue
            if c.action in agent.syncs:
                sync.setdefault(c.action, []).append(_rename(agent, c, c.action))
            else:
                local.append(_rename(agent, c, agent.prefix + c.action))
        for a in agent.model.actions:
            weights[agent.prefix + a.name] = _renamer(agent)(low.weights[a.name])
        raw.append((agent, local, sync))
    takers: dict[str, list[int]] = {}
    for i, (_, _, sync) in enumerate(raw):
        for name in sync:
            takers.setdefault(name, []).append(i)
    if comp.ties == "uniform":  # a synchronised action's weight: its partners (above)
        for name, who in takers.items():
            sync = raw[who[0]][2]
            sync[name] = sync[name] * len(who)

    def offers(i: int, name: str) -> E.Expr:
        return E.disj(*(c.guard for c in raw[i][2].get(name, [])))

    def joint(name: str) -> E.Expr:
        return E.conj(*(offers(i, name) for i in takers[name]))

    movable = [E.disj(*(c.guard for c in local), *(joint(n) for n in sync if len(takers[n]) > 1))
               for _, local, sync in raw]
    clocks = [E.VarRef(a.mission_name(a.clock), Type.INT) if a.clock else None
              for a, _, _ in raw]

    current = [current_weight(a, weights) for a, _, _ in raw]

    def first(group: list[int]) -> E.Expr:
        """The group's least clock beats every other agent that can move."""
        if comp is None or comp.kind != "timed":
            return E.TRUE
        parts = []
        for j in range(len(raw)):
            if j in group:
                continue
            beats = []
            for i in group:
                ci, cj = clocks[i], clocks[j]
                assert ci is not None and cj is not None
                if comp.ties == "weight":
                    beats.append(_beats_by_weight(ci, cj, current[i], current[j], j < i))
                    continue
                op = "<" if comp.ties == "order" and j < i else "<="
                beats.append(E.Binary(op, ci, cj, Type.BOOL))
            parts.append(E.disj(E.neg(movable[j]), *beats))
        return E.conj(*parts)

    parts: list[Part] = []
    for i, (agent, local, sync) in enumerate(raw):
        timing = first([i])
        sync_timing = tuple((n, first(takers[n])) for n in sync)
        parts.append(Part(agent, tuple(local), tuple((n, tuple(cs)) for n, cs in sync.items()),
                          timing, sync_timing))
    stay = Command("_stay", (0,), E.neg(E.disj(*movable)),
                   (Branch(E.Lit(1, Type.INT), (), model.modes[0].span),), model.modes[0].span,
                   (), "deadlock")
    network = Network(comp.kind, comp.ties, tuple(parts), stay)
    return Lowered(model, assemble(network), resolution, weights, bounds, network=network)


def assemble(net: Network) -> tuple[Command, ...]:
    """The mission's commands from its agents' (the product PRISM and JANI form from the
    modules): each agent's own commands under its timing, a synchronised action's
    combinations of its partners' commands, and the self-loop where no agent can move.
    The reductions (afsmc.lower.reduce_compose) rewrite the agents' commands and call it
    again."""
    commands: list[Command] = []
    takers: dict[str, list[int]] = {}
    for i, part in enumerate(net.parts):
        commands += [Command(c.action, c.modes, E.conj(c.guard, part.timing), c.branches,
                             c.span, c.choice, c.kind) for c in part.local]
        for name, _ in part.sync:
            takers.setdefault(name, []).append(i)
    for name, who in takers.items():
        if len(who) < 2:
            continue
        timing = dict(net.parts[who[0]].sync_timing)[name]
        for combo in itertools.product(*(dict(net.parts[i].sync)[name] for i in who)):
            commands.append(_product(tuple(combo), name, timing))
    commands.append(net.stay)
    return tuple(commands)


def action_agents(net: Network) -> dict[str, tuple[int, ...]]:
    """Each action of the mission's commands (`agent_A`, or a synchronised action's name)
    and the agents (by declaration order) it moves."""
    owner: dict[str, tuple[int, ...]] = {}
    takers: dict[str, list[int]] = {}
    for i, part in enumerate(net.parts):
        for c in part.local:
            owner[c.action] = (i,)
        for name, _ in part.sync:
            takers.setdefault(name, []).append(i)
    for name, who in takers.items():
        owner.setdefault(name, tuple(who))
    return owner


def current_weight(agent: ir.Agent, weights: dict[str, E.Expr]) -> E.Expr:
    """The weight of the action the agent takes in a state (in the mission's names): the
    largest of its actions' effective weights (each 0 where its action is disabled)."""
    out: E.Expr | None = None
    for a in agent.model.actions:
        w = weights[agent.prefix + a.name]
        out = w if out is None else E.Call("max", (out, w), Type.DOUBLE)
    return E.Lit(0, Type.INT) if out is None else out


def _beats_by_weight(ci: E.Expr, cj: E.Expr, wi: E.Expr, wj: E.Expr, later: bool) -> E.Expr:
    """`ties weight`: agent i moves before agent j if its clock is less, or equal and its
    current action's weight larger. Equal weights at equal clocks are E314 where actions
    move both; should a hazard's move tie, declaration order settles it (`later`: j was
    declared first), so that some agent always moves."""
    same = E.Binary("==", ci, cj, Type.BOOL)
    settle = E.Binary(">" if later else ">=", wi, wj, Type.BOOL)
    return E.disj(E.Binary("<", ci, cj, Type.BOOL), E.conj(same, settle))
