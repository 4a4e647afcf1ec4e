"""A composed mission's commands and states in mission terms, for its strategies and
witness paths (afsmc.verify.outcome.strategy, afsmc.verify.outcome.witness): which agent moved (or which
agents, in a synchronised action), by which of its actions, and each agent's mode
("uav2: Search")."""

from __future__ import annotations

from collections.abc import Mapping

from afsmc.lower.lowering import Command, Lowered
from afsmc.model import ir


def agents(low: Lowered) -> tuple[ir.Agent, ...]:
    comp = low.model.composition
    return () if comp is None else comp.agents


def mover(low: Lowered, cmd: Command) -> tuple[tuple[ir.Agent, ...], str]:
    """The agents a command moves and its action's name in them: an agent's own action
    (`uav1_Look` -> uav1, "Look"), or a synchronised one (its partners, its name)."""
    for a in agents(low):
        local = cmd.action.removeprefix(a.prefix)
        if cmd.action.startswith(a.prefix) and local not in a.syncs and any(
                x.name == local for x in a.model.actions):
            return (a,), local
    return tuple(a for a in agents(low) if cmd.action in a.syncs), cmd.action


def action_text(low: Lowered, cmd: Command) -> str:
    """"uav1: Look" for an agent's own action, "Launch (uav1, uav2)" for a synchronised
    one."""
    who, action = mover(low, cmd)
    if len(who) == 1:
        return f"{who[0].name}: {action}"
    return f"{action} ({', '.join(a.name for a in who)})"


def mode_name(agent: ir.Agent, number: int) -> str:
    return next((m.name for m in agent.model.modes if m.number == number), str(number))


def modes_text(low: Lowered, values: Mapping[str, int],
               only: tuple[ir.Agent, ...] | None = None) -> str:
    """Each agent's mode in a state ("uav1: Search, uav2: Home"); `only`: those agents."""
    return ", ".join(f"{a.name}: {mode_name(a, values[a.mode_var])}"
                     for a in (agents(low) if only is None else only) if a.mode_var in values)


def range_text(agent: ir.Agent, lo: int, hi: int) -> str:
    """An agent's modes over a range of mode numbers ("uav2: Search" or "uav2: Search,
    Approach")."""
    names = [m.name for m in agent.model.modes if lo <= m.number <= hi]
    return f"{agent.name}: {', '.join(names)}"


def displays(low: Lowered) -> dict[str, str]:
    """Each mission variable's name for people: an agent's own `uav1_t` is `uav1.t`, its
    mode `uav1.mode`; a shared variable keeps its name."""
    out = {v.name: v.display for v in low.model.variables}
    for a in agents(low):
        out[a.mode_var] = f"{a.name}.mode"
        for v in a.model.variables:
            if v.name in a.own:
                out[a.prefix + v.name] = f"{a.name}.{v.display}"
    return out


def choice_owners(low: Lowered, cmd: Command) -> tuple[str, ...]:
    """For a synchronised action's command, the agent that took each of its interval
    ends (its `choice` is its partners' in declaration order); () for any other."""
    net = low.network
    who, _ = mover(low, cmd)
    if net is None or len(who) < 2:
        return ()
    out: list[str] = []
    for part in net.parts:
        cmds = dict(part.sync).get(cmd.action, ())
        if part.agent in who and cmds:
            out += [part.agent.name] * len(cmds[0].choice)
    return tuple(out) if len(out) == len(cmd.choice) else ()
