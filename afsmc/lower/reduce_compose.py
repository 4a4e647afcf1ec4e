"""The exact reductions of a composed mission (afsmc.lower.reduce for one machine).

Each rewrites the agents' own commands (`Network.parts`, what the PRISM modules and the
JANI automata hold) and the mission's commands are assembled from them again, so every
backend and the simulator see the same reduced model.

* ``saturate`` -- as for one machine, decided on the mission's commands (each agent's
  guards, the timed composition's clock comparisons, the products of synchronised
  actions) and the labels, rewards and properties: a counter is saturated only if every
  read of it anywhere is a comparison with a constant. A clock that the timed
  composition compares with another agent's is therefore never saturated. The agents'
  mode variables are left alone (a mode number is what the strategies and traces name).
* ``dead_reset`` -- per agent, over the agent's modes: an agent's own variable is live in
  its mode M if some command of the mission (any agent's, the timing conditions
  included), a label, reward or property may read it while the agent is in M, folded
  with the agent's mode fixed at M, or if the agent may move from M to a mode where it
  is live without writing it first. Only the agent writes its own variables and only its
  own moves change its mode, so while the agent stays in M its variables' reads are
  those of M: a transition of the agent into a mode where a variable is dead resets it
  to its initial value. Shared variables (`written by`) are kept as they are: several
  agents write them, and no one agent's mode tells when they are read again.
* ``reorder`` -- the variable order, as for one machine; each agent's module keeps its
  variables in that order. The state space is unchanged.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import replace

from afsmc.lower.compose import Network, Part, assemble
from afsmc.lower.lowering import Branch, Command, Lowered
from afsmc.lower.reduce import (
    Reductions,
    capped,
    fold,
    reorder,
    saturated_variables,
    saturation_points,
)
from afsmc.lower.symmetry import symmetric
from afsmc.model import expr as E
from afsmc.model import ir
from afsmc.model.semantics import inline


def reduce_composed(low: Lowered, options: Reductions) -> Lowered:
    net = low.network
    assert isinstance(net, Network)
    if options.saturate:
        low, done = _saturate(low, net)
        if done:
            low = replace(low, reductions=(*low.reductions, "saturated " + ", ".join(done)))
    if options.dead_reset:
        low = _dead_reset(low)
        low = replace(low, reductions=(*low.reductions, "dead-variable reset"))
    if options.reorder:
        low = _reorder(low)
        low = replace(low, reductions=(*low.reductions, "variable order"))
    return symmetric(low, options)


def _map_parts(net: Network, fn: Callable[[Part, Command], Command]) -> Network:
    parts = tuple(replace(part, local=tuple(fn(part, c) for c in part.local),
                          sync=tuple((n, tuple(fn(part, c) for c in cs)) for n, cs in part.sync))
                  for part in net.parts)
    return replace(net, parts=parts)


def _rebuilt(low: Lowered, net: Network, model: ir.Model | None = None) -> Lowered:
    return replace(low, model=model or low.model, commands=assemble(net), network=net)


# ---- saturating counters -------------------------------------------------------------


def _saturate(low: Lowered, net: Network) -> tuple[Lowered, list[str]]:
    modes = {part.agent.mode_var for part in net.parts}
    points, done = saturation_points(low)
    keep = {v: p for v, p in points.items() if v not in modes}
    done = [d for d, v in zip(done, points, strict=True) if v in keep]
    if not keep:
        return low, []

    def cap(_part: Part, cmd: Command) -> Command:
        return replace(cmd, branches=tuple(
            replace(b, updates=tuple((v, capped(low, keep, v, x)) for v, x in b.updates))
            for b in cmd.branches))

    model = replace(low.model, variables=saturated_variables(low.model, keep))
    return _rebuilt(low, _map_parts(net, cap), model), done


# ---- dead variables, per agent --------------------------------------------------------


def _observed(model: ir.Model) -> list[E.Expr]:
    """What labels, rewards and properties read, formulas inlined."""
    exprs: list[E.Expr] = [lb.value for lb in model.labels]
    for r in model.rewards:
        exprs += [x for it in r.items for x in (it.guard, it.value)]
    for p in model.properties:
        exprs += [x for x in (getattr(p.path, "target", None), getattr(p.path, "left", None),
                              getattr(p.path, "bound", None)) if x is not None]
    return [inline(e, model) for e in exprs]


def _at(e: E.Expr, mode_var: str, mode: int) -> E.Expr:
    """`e` with the agent's mode fixed at `mode`, folded as far as that goes."""
    def fn(n: E.Expr) -> E.Expr | None:
        if isinstance(n, E.VarRef) and n.name == mode_var:
            return E.Lit(mode, E.Type.INT)
        return None

    return fold(E.transform(e, fn))


def _never(e: E.Expr) -> bool:
    return isinstance(e, E.Lit) and e.value is False


def _mission_reads(low: Lowered) -> list[tuple[E.Expr, tuple[E.Expr, ...]]]:
    """Every command's guard and what its branches read, formulas inlined; the labels,
    rewards and properties as commands whose guard always holds."""
    out: list[tuple[E.Expr, tuple[E.Expr, ...]]] = [(E.TRUE, tuple(_observed(low.model)))]
    for cmd in low.commands:
        reads = [inline(x, low.model) for b in cmd.branches
                 for x in (b.prob, *(value for _, value in b.updates))]
        out.append((inline(cmd.guard, low.model), tuple(reads)))
    return out


class _Partial:
    """Expressions with one agent's mode fixed: each node's value where that alone decides
    it, else the variables it depends on. Nodes are kept by identity: the timed
    composition's conditions are shared by many commands and evaluated once."""

    def __init__(self, mode_var: str, mode: int) -> None:
        self.mode_var, self.mode = mode_var, mode
        self.memo: dict[int, tuple[object, frozenset[str]]] = {}

    def __call__(self, e: E.Expr) -> tuple[object, frozenset[str]]:
        key = id(e)
        if key not in self.memo:
            self.memo[key] = self._eval(e)
        return self.memo[key]

    def _eval(self, e: E.Expr) -> tuple[object, frozenset[str]]:
        none: frozenset[str] = frozenset()
        if isinstance(e, E.Lit):
            return e.value, none
        if isinstance(e, E.ModeVal):
            return e.number, none
        if isinstance(e, E.VarRef):
            return (self.mode, none) if e.name == self.mode_var else (None, frozenset({e.name}))
        if isinstance(e, E.Unary) and e.op == "!":
            v, r = self(e.operand)
            return (not v, none) if isinstance(v, bool) else (None, r)
        if isinstance(e, E.Ite):
            c, _ = self(e.cond)
            if isinstance(c, bool):
                return self(e.then if c else e.other)
        if isinstance(e, E.Binary) and e.op in ("&&", "||", "=>"):
            return self._connective(e)
        if isinstance(e, E.Binary) and e.op in _CMP:
            (a, ra), (b, rb) = self(e.left), self(e.right)
            if a is not None and b is not None:
                return bool(_CMP[e.op](a, b)), none
            return None, ra | rb
        return None, frozenset().union(*(self(c)[1] for c in E.children(e)))

    def _connective(self, e: E.Binary) -> tuple[object, frozenset[str]]:
        (a, ra), (b, rb) = self(e.left), self(e.right)
        if e.op == "=>":
            a = (not a) if isinstance(a, bool) else None
        stop = e.op != "&&"  # the value that decides the connective alone
        if a is stop or b is stop:
            return stop, frozenset()
        if isinstance(a, bool):
            return b, rb
        if isinstance(b, bool):
            return a, ra
        return None, ra | rb


_CMP = {"==": lambda a, b: a == b, "!=": lambda a, b: a != b, "<": lambda a, b: a < b,
        "<=": lambda a, b: a <= b, ">": lambda a, b: a > b, ">=": lambda a, b: a >= b}


def _reads_at(reads: list[tuple[E.Expr, tuple[E.Expr, ...]]], agent: ir.Agent, mode: int,
              own: set[str]) -> set[str]:
    """The agent's own variables that may be read while it is in `mode`."""
    at = _Partial(agent.mode_var, mode)
    out: set[str] = set()
    for guard, values in reads:
        g, r = at(guard)
        if g is False:
            continue
        out |= r
        for value in values:
            out |= at(value)[1]
    return out & own


def _sources(cmd: Command, agent: ir.Agent, modes: list[int]) -> list[int]:
    return [m for m in modes if not _never(_at(cmd.guard, agent.mode_var, m))]


def _targets(b: Branch, agent: ir.Agent, source: int, modes: list[int]) -> list[int]:
    for var, value in b.updates:
        if var == agent.mode_var:
            return [value.value] if isinstance(value, E.Lit) and isinstance(
                value.value, int) else modes
    return [source]


def _agent_commands(part: Part) -> list[Command]:
    return [*part.local, *(c for _, cs in part.sync for c in cs)]


def _live(reads: list[tuple[E.Expr, tuple[E.Expr, ...]]], part: Part) -> dict[int, set[str]]:
    agent = part.agent
    own = {agent.prefix + v for v in agent.own}
    modes = [m.number for m in agent.model.modes]
    live = {m: _reads_at(reads, agent, m, own) for m in modes}
    moves = [(b, m, _targets(b, agent, m, modes)) for c in _agent_commands(part)
             for m in _sources(c, agent, modes) for b in c.branches]
    changed = True
    while changed:
        changed = False
        for b, m, targets in moves:
            need = set().union(*(live[t] for t in targets)) - {v for v, _ in b.updates}
            if not need <= live[m]:
                live[m] |= need
                changed = True
    return live


def _dead_reset(low: Lowered) -> Lowered:
    net = low.network
    assert isinstance(net, Network)
    model = low.model
    init = {v.name: v.init for v in model.variables}
    order = {v.name: i for i, v in enumerate(model.variables)}
    reads = _mission_reads(low)
    lives = {part.agent.name: _live(reads, part) for part in net.parts}

    def reset(part: Part, cmd: Command) -> Command:
        agent = part.agent
        own = [agent.prefix + v for v in agent.own]
        modes = [m.number for m in agent.model.modes]
        live = lives[agent.name]
        sources = _sources(cmd, agent, modes)
        branches = []
        for b in cmd.branches:
            alive: set[str] = set().union(
                *(live[t] for m in sources for t in _targets(b, agent, m, modes)))
            updates = dict(b.updates)
            for var in own:
                if var not in alive and updates.get(var) != E.lit(init[var]):
                    updates[var] = E.lit(init[var])
            if len(updates) == len(b.updates):
                branches.append(b)
                continue
            new = tuple(sorted(updates.items(), key=lambda kv: order[kv[0]]))
            branches.append(replace(b, updates=new))
        return replace(cmd, branches=tuple(branches))

    return _rebuilt(low, _map_parts(net, reset))


# ---- variable order --------------------------------------------------------------------


def _reorder(low: Lowered) -> Lowered:
    net = low.network
    assert isinstance(net, Network)
    model = reorder(low).model
    if model is low.model:
        return low
    order = {v.name: i for i, v in enumerate(model.variables)}

    def sort(_part: Part, cmd: Command) -> Command:
        return replace(cmd, branches=tuple(
            replace(b, updates=tuple(sorted(b.updates, key=lambda kv: order[kv[0]])))
            for b in cmd.branches))

    return _rebuilt(low, _map_parts(net, sort), model)
