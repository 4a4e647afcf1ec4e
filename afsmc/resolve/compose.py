"""A composed mission (`agent` blocks) resolved: each agent as a machine of its own, and
the mission around them (docs/language.md, "Composition").

Each agent's view is a module of its own that the single-agent resolver takes as it is:
the mission's constants, the shared variables, the other agents' modes it reads (as
variables `<agent>_mode`) and its own declarations. The mission's module holds the
constants, the shared variables, every agent's mode and variables by their mission names
(`uav1.t` is `uav1_t`), and the formulas, labels, rewards and properties. Names that
cross agents (`uav2.mode == Search`, `uav1.t`) are rewritten in the syntax tree before.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable
from typing import Any, Literal, cast

from afsmc.diagnostics import Diagnostic, Reporter, Span, codes
from afsmc.resolve.declarations import numbered
from afsmc.resolve.expressions import modes_in
from afsmc.syntax import ast

_AGENT_ITEMS = (ast.VarDecl, ast.ModeDecl, ast.ActionDecl, ast.HazardDecl, ast.FormulaDecl)
_MISSION_ITEMS = (ast.ConstDecl, ast.ParamDecl, ast.VarDecl, ast.FormulaDecl, ast.LabelDecl,
                  ast.RewardsDecl, ast.PropertyDecl)
# The one mode of the mission's own module: its states are the agents' modes and variables.
MISSION_MODE = "_mission"


def is_composed(module: ast.Module) -> bool:
    return any(isinstance(d, (ast.AgentDecl, ast.AgentsDecl, ast.FamilyDecl, ast.ComposeDecl))
               for d in module.decls)


def mode_numbers(decls: tuple[ast.Decl, ...]) -> dict[str, int]:
    """The agent's modes by name, numbered as the resolver numbers them (a number written
    is kept by its first mode; the others take the next free ones, in order)."""
    modes = [d for d in decls if isinstance(d, ast.ModeDecl)]
    used: dict[int, ast.ModeDecl] = {}
    for d in modes:
        if d.number is not None and d.number not in used:
            used[d.number] = d
    first: dict[str, ast.ModeDecl] = {}
    for d in modes:
        first.setdefault(d.name.text, d)
    return {d.name.text: number for d, number in numbered(list(first.values()), used)}


def rewrite(node: Any, fn: Callable[[Any], Any]) -> Any:
    """The syntax tree with `fn` applied top-down: where it returns a node, that node
    stands (and is not entered); elsewhere the node's fields are rewritten."""
    new = fn(node)
    if new is not None:
        return new
    if isinstance(node, tuple):
        return tuple(rewrite(x, fn) for x in node)
    if not dataclasses.is_dataclass(node) or isinstance(node, (ast.Ident, Span)):
        return node
    changes = {}
    for f in dataclasses.fields(node):
        old = getattr(node, f.name)
        if isinstance(old, (tuple, ast.Ident, Span)) or dataclasses.is_dataclass(old):
            value = rewrite(old, fn)
            if value is not old:
                changes[f.name] = value
    return dataclasses.replace(cast(Any, node), **changes) if changes else node


class _Names:
    """What names mean across agents: each agent's modes, variables and the name of its
    mode variable; `here` is the agent an expression stands in (None: the mission)."""

    def __init__(self, agents: list[ast.AgentDecl], rep: Reporter) -> None:
        self.agents = {a.name.text: a for a in agents}
        self.modes = {a.name.text: mode_numbers(a.decls) for a in agents}
        self.vars = {a.name.text: {d.name.text for d in a.decls if isinstance(d, ast.VarDecl)}
                     for a in agents}
        self.rep = rep
        self.read_modes: set[str] = set()

    def fn(self, here: str | None) -> Callable[[Any], Any]:
        def go(n: Any) -> Any:
            if isinstance(n, ast.Binary) and n.op in ("==", "!="):
                return self._mode_compare(n, go, here)
            if isinstance(n, ast.FieldRef) and n.base.text in self.agents:
                return self._field(n, here)
            if isinstance(n, ast.ModeIn) and n.agent is not None:
                return self._mode_in(n, here)
            if isinstance(n, ast.ModeRef) and here is None:
                self.rep.error(codes.E253, "which agent's mode? A mission of several agents "
                               "names it", n.span, hint="write e.g. 'uav1.mode'")
            return None
        return go

    def _mode_compare(self, n: ast.Binary, go: Callable[[Any], Any], here: str | None) -> Any:
        for ref, other in ((n.left, n.right), (n.right, n.left)):
            if (isinstance(ref, ast.FieldRef) and ref.field.text == "mode"
                    and ref.base.text in self.agents and isinstance(other, ast.Name)
                    and other.name.text in self.modes[ref.base.text]):
                if ref.base.text == here:
                    return None  # its own mode: `mode == Idle` as a single machine reads it
                number = self.modes[ref.base.text][other.name.text]
                left = rewrite(ref, go)
                num = ast.Num(number, str(number), other.span)
                return ast.Binary(n.op, left, num, n.span)
        return None

    def _mode_in(self, n: ast.ModeIn, here: str | None) -> Any:
        """`r1.mode in {Wait, Charging}`: the agent's own `mode in {...}`, or a test of
        its mode variable for every other view (as `r1.mode == Wait` is)."""
        assert n.agent is not None
        agent = n.agent.text
        if agent not in self.agents:
            self.rep.error(codes.E253, f"'{agent}' is no agent", n.agent.span,
                           hint="name an agent of the mission: " + ", ".join(self.agents))
            return ast.BoolLit(False, n.span)
        if agent == here:
            return ast.ModeIn(n.modes, n.span)
        numbers = modes_in(n.modes, self.modes[agent], self.rep, f" of agent {agent}")
        self.read_modes.add(agent)
        var = ast.Name(ast.Ident(f"{agent}_mode", n.agent.span), n.agent.span)
        out: Any = ast.BoolLit(False, n.span)
        for k in numbers:
            test = ast.Binary("==", var, ast.Num(k, str(k), n.span), n.span)
            out = test if isinstance(out, ast.BoolLit) else ast.Binary("||", out, test, n.span)
        return out

    def _field(self, n: ast.FieldRef, here: str | None) -> Any:
        agent = n.base.text
        if n.field.text == "mode":
            if agent == here:
                return ast.ModeRef(n.span)
            self.read_modes.add(agent)
            return ast.Name(ast.Ident(f"{agent}_mode", n.span), n.span)
        if n.field.text not in self.vars[agent]:
            self.rep.error(codes.E253, f"agent {agent} has no variable '{n.field.text}'",
                           n.field.span)
            return ast.Num(0, "0", n.span)
        if agent == here:
            return ast.Name(ast.Ident(n.field.text, n.field.span), n.span)
        if here is not None:
            self.rep.error(codes.E254, f"agent {here} reads {agent}.{n.field.text}, a variable "
                           f"of agent {agent} that only it sees", n.span,
                           hint=f"declare '{n.field.text}' as a shared variable outside the "
                           "agents, or read the other agent's mode ('"
                           f"{agent}.mode == ...')")
            return ast.Num(0, "0", n.span)
        return ast.Name(ast.Ident(f"{agent}_{n.field.text}", n.span), n.span)


def _mode_var(agent: ast.AgentDecl, numbers: dict[str, int], name: str) -> ast.VarDecl:
    initial = next((d.name.text for d in agent.decls if isinstance(d, ast.ModeDecl)
                    and d.initial), None)
    init = numbers.get(initial, 0) if initial is not None else 0
    lo, hi = (min(numbers.values()), max(numbers.values())) if numbers else (0, 0)
    s = agent.name.span

    def num(v: int) -> ast.Num:
        return ast.Num(v, str(v), s)

    return ast.VarDecl(ast.Ident(name, s), ast.RangeType(num(lo), num(hi), s), num(init),
                       False, s)


def split(module: ast.Module, rep: Reporter) -> tuple[
        ast.ComposeDecl | None, list[ast.AgentDecl], list[ast.Decl]]:
    """The composition statement, the agents and the mission's own declarations; E253 for
    what has no place in a composed mission."""
    compose = None
    agents: list[ast.AgentDecl] = []
    mission: list[ast.Decl] = []
    for d in module.decls:
        if isinstance(d, ast.ComposeDecl):
            if compose is not None:
                rep.error(codes.E253, "the composition is stated twice", d.span)
            compose = d
        elif isinstance(d, ast.AgentDecl):
            if any(a.name.text == d.name.text for a in agents):
                rep.error(codes.E253, f"agent {d.name.text} is declared twice", d.name.span)
            agents.append(d)
            for x in d.decls:
                if not isinstance(x, _AGENT_ITEMS):
                    rep.error(codes.E253, "an agent holds variables, modes, actions, hazards "
                              "and formulas; this belongs outside it", x.span)
        elif isinstance(d, _MISSION_ITEMS):
            mission.append(d)
        else:
            rep.error(codes.E253, "in a mission of several agents, modes, actions and hazards "
                      "belong to an agent", d.span, hint="move it into an 'agent NAME { ... }'")
    if not agents:
        rep.error(codes.E253, "a composition without agents", compose.span if compose else None,
                  hint="declare them: 'agent uav1 { ... }'")
    return compose, agents, mission


def composition_kind(compose: ast.ComposeDecl | None, agents: list[ast.AgentDecl],
                     rep: Reporter) -> tuple[Literal["interleaving", "timed"],
                                             Literal["nondet", "order", "weight", "uniform",
                                                     "fair"]]:
    """The composition and its rule for agents that may move at once: for an
    interleaving every agent that can move, `nondet` (min/max over who moves) or
    `uniform` (`compose interleaving uniform;`: each with equal probability) or `fair`
    (`compose interleaving fair;`: min/max over fair schedulers only)."""
    if compose is None:
        return "interleaving", "nondet"
    kind = compose.kind.text
    if kind not in ("interleaving", "timed"):
        rep.error(codes.E253, f"'{kind}' is no composition", compose.kind.span,
                  hint="write 'compose interleaving;' or 'compose timed;'")
        kind = "interleaving"
    ties = compose.ties.text if compose.ties is not None else "nondet"
    if ties not in ("nondet", "order", "weight"):
        rep.error(codes.E253, f"'{ties}' is no rule for ties", cast(ast.Ident, compose.ties).span,
                  hint="write 'ties order' (the agent declared first moves), 'ties weight' "
                  "(the larger weight moves) or 'ties nondet' (min/max over both)")
        ties = "nondet"
    if kind == "interleaving" and compose.ties is not None:
        rep.error(codes.E253, "ties are a rule of the timed composition", compose.ties.span)
    how = compose.scheduler
    if how is not None:
        if kind != "interleaving":
            rep.error(codes.E253, f"'{how.text}' is a rule of the interleaving, not of the "
                      "timed composition", how.span, hint="write 'compose interleaving "
                      f"{how.text};', or a rule for ties ('compose timed ties order;')")
        elif how.text in ("uniform", "fair"):
            ties = how.text
        else:
            rep.error(codes.E253, f"'{how.text}' is no rule of the interleaving", how.span,
                      hint="write 'compose interleaving;' (min and max over who moves next), "
                      "'compose interleaving fair;' (over fair schedulers) or 'compose "
                      "interleaving uniform;' (who moves next is uniform among the agents that "
                      "can move)")
    if kind == "timed":
        for a in agents:
            own = {d.name.text for d in a.decls if isinstance(d, ast.VarDecl)}
            if a.clock is None:
                rep.error(codes.E253, f"agent {a.name.text} has no clock, which a timed "
                          "composition needs", a.name.span,
                          hint=f"write 'agent {a.name.text} clock t {{ var t : [0..T] ... }}'")
            elif a.clock.text not in own:
                rep.error(codes.E253, f"the clock '{a.clock.text}' is no variable of agent "
                          f"{a.name.text}", a.clock.span)
    return cast(Any, kind), cast(Any, ties)


def agent_module(module: ast.Module, agent: ast.AgentDecl, names: _Names,
                 mission: list[ast.Decl]) -> ast.Module:
    """The agent's view as a module of its own."""
    here = agent.name.text
    names.read_modes = set()
    own = rewrite(agent.decls, names.fn(here))
    formulas, formula_reads = _mission_formulas(agent, names, mission)
    outer = [d for d in mission if isinstance(d, (ast.ConstDecl, ast.ParamDecl))]
    shared = [dataclasses.replace(d, writers=None) for d in mission if isinstance(d, ast.VarDecl)]
    reads = [_mode_var(names.agents[b], names.modes[b], f"{b}_mode")
             for b in sorted(names.read_modes | formula_reads)]
    machine = ast.MachineDecl(agent.name, agent.name.span)
    return ast.Module(machine, (*outer, *shared, *reads, *formulas, *own), module.span)


def _name_uses(node: Any) -> dict[str, Span]:
    """Every name an expression (or declarations) reads, at its first use."""
    out: dict[str, Span] = {}

    def go(n: Any) -> Any:
        if isinstance(n, ast.Name):
            out.setdefault(n.name.text, n.span)
        return None
    rewrite(node, go)
    return out


def _mission_formulas(agent: ast.AgentDecl, names: _Names, mission: list[ast.Decl]) -> tuple[
        list[ast.FormulaDecl], set[str]]:
    """The mission's formulas the agent uses (directly or through another), in the
    agent's view, and the other agents' modes they read. A formula is visible to an agent
    when it reads only constants, shared variables, the agent's own variables and other
    agents' modes (`uav2.mode`); one the agent uses that reads what the agent may not see
    (another agent's variable) is E254 at the use, naming the agent and the variable.
    The agent's own declaration of the same name hides the mission's."""
    here = agent.name.text
    mine = {d.name.text for d in agent.decls if isinstance(d, (ast.VarDecl, ast.FormulaDecl))}
    visible: dict[str, tuple[ast.FormulaDecl, set[str], set[str]]] = {}
    blocked: dict[str, str] = {}
    outer_rep, outer_reads = names.rep, names.read_modes
    for d in mission:
        if not isinstance(d, ast.FormulaDecl) or d.name.text in mine:
            continue
        names.rep, names.read_modes = Reporter(), set()
        new = rewrite(d, names.fn(here))
        errors = [x for x in names.rep.diagnostics if x.is_error]
        refs = set(_name_uses(d.value))
        through = next((r for r in sorted(refs) if r in blocked), None)
        if errors:
            blocked[d.name.text] = errors[0].message
        elif through is not None:
            blocked[d.name.text] = f"through formula '{through}': {blocked[through]}"
        else:
            visible[d.name.text] = (new, refs, names.read_modes)
    names.rep, names.read_modes = outer_rep, outer_reads
    uses = _name_uses(agent.decls)
    for name, span in uses.items():
        if name in blocked and name not in mine:
            names.rep.error(codes.E254, f"agent {here} uses the mission's formula '{name}', "
                            f"which it may not see: {blocked[name]}", span,
                            hint=f"give agent {here} its own formula over what it may read, or "
                            "share the variable (declare it outside the agents)")
    needed: set[str] = set()
    todo = [n for n in uses if n in visible]
    while todo:
        n = todo.pop()
        if n not in needed:
            needed.add(n)
            todo += [r for r in visible[n][1] if r in visible]
    reads: set[str] = set()
    out = []
    for name, (decl, _, modes) in visible.items():
        if name in needed:
            out.append(decl)
            reads |= modes
    return out, reads


def mission_module(module: ast.Module, agents: list[ast.AgentDecl], names: _Names,
                   mission: list[ast.Decl]) -> ast.Module:
    """The mission's own module: every agent's state by its mission names."""
    state: list[ast.Decl] = []
    for a in agents:
        state.append(_mode_var(a, names.modes[a.name.text], f"{a.name.text}_mode"))
        for d in a.decls:
            if isinstance(d, ast.VarDecl):
                state.append(dataclasses.replace(
                    d, name=ast.Ident(f"{a.name.text}_{d.name.text}", d.name.span)))

    def reward_action(n: Any) -> Any:
        if isinstance(n, ast.RewardItem) and n.agent is not None and n.action is not None:
            ident = ast.Ident(f"{n.agent.text}_{n.action.text}", n.action.span)
            return dataclasses.replace(n, action=ident, agent=None,
                                       guard=rewrite(n.guard, names.fn(None)),
                                       value=rewrite(n.value, names.fn(None)))
        return None

    decls = rewrite(tuple(mission), reward_action)
    decls = rewrite(decls, names.fn(None))
    s = module.machine.span if module.machine else module.span
    dummy = ast.ModeDecl(ast.Ident(MISSION_MODE, s), 0, None, True, False, s)
    return ast.Module(module.machine, (*state, dummy, *decls), module.span)


def mission_actions(agents: list[ast.AgentDecl]) -> dict[str, Span]:
    """The actions a mission's action rewards may name: `agent_Action` and each sync."""
    out: dict[str, Span] = {}
    for a in agents:
        for d in a.decls:
            if isinstance(d, ast.ActionDecl):
                name = d.name.text if d.sync else f"{a.name.text}_{d.name.text}"
                out.setdefault(name, d.name.span)
    return out


def explained(d: Diagnostic, rep: Reporter) -> bool:
    """An agent's "not declared" (E203) where E254 already says the mission's formula of
    that name is one the agent may not see."""
    return d.code == codes.E203 and any(
        x.code == codes.E254 and x.span == d.span for x in rep.diagnostics)


def in_agent(d: Diagnostic, agent: ast.AgentDecl) -> Diagnostic | None:
    """A diagnostic of an agent's view: about the agent's own text, with its name; None
    for one about the mission's declarations (the mission's module reports those)."""
    if d.span is None or not (agent.span.start <= d.span.start < agent.span.end):
        return None
    return dataclasses.replace(d, message=f"agent {agent.name.text}: {d.message}")


def writers(mission: list[ast.Decl], agents: list[ast.AgentDecl],
            rep: Reporter) -> tuple[tuple[str, tuple[str, ...]], ...]:
    names = [a.name.text for a in agents]
    out = []
    for d in mission:
        if not isinstance(d, ast.VarDecl):
            continue
        if d.writers is None:
            out.append((d.name.text, tuple(names)))
            continue
        for w in d.writers:
            if w.text not in names:
                rep.error(codes.E253, f"'{w.text}' is no agent", w.span)
        out.append((d.name.text, tuple(w.text for w in d.writers)))
    return tuple(out)
