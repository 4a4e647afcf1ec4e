"""The checks of a composed mission: every single-agent rule on each agent (the weight
proof among them, with its witness, per agent), and the rules of composition itself:
who may write a shared variable (E255), a synchronised action's partners (E312), the
variables two agents would write in the same step (E311) and, under `ties weight`, two
agents' weights that tie at the same time (E314, afsmc.check.agent_ties)."""

from __future__ import annotations

import dataclasses
from collections.abc import Callable

from afsmc.check.agent_ties import check_weight_ties
from afsmc.diagnostics import Diagnostic, Related, Reporter, codes
from afsmc.model import ir

Run = Callable[..., list[Diagnostic]]


def check_composition(model: ir.Model, used_names: frozenset[str], run: Run) -> list[Diagnostic]:
    comp = model.composition
    assert comp is not None
    rep = Reporter()
    for agent in comp.agents:
        for d in run(agent.model, used_names=used_names):
            if d.span is None or not agent.span.start <= d.span.start < agent.span.end:
                continue  # about the mission's declarations, which every agent sees
            if d.code == codes.W602:
                continue  # an agent that never ends (a server) is no fault in a mission
            if d.code == codes.W303 and f"variable {agent.clock} " in d.message:
                continue  # its clock: the timed composition reads it
            if d.code == codes.W302 and _waits(agent, d):
                continue  # a mode of synchronised actions only: the agent waits there
            code = codes.E313 if d.code == codes.E301 else d.code
            rep.extend([dataclasses.replace(d, code=code,
                                            message=f"agent {agent.name}: {d.message}")])
    check_writers(comp, rep)
    check_syncs(comp, rep)
    if not any(d.is_error for d in rep.sorted()):
        check_weight_ties(model, comp, rep)
    return rep.sorted()


def _waits(agent: ir.Agent, d: Diagnostic) -> bool:
    """The diagnostic is about a mode whose actions are all synchronised."""
    mode = next((m for m in agent.model.modes if d.span is not None and m.span == d.span), None)
    return mode is not None and all(a.name in agent.syncs
                                    for a in agent.model.actions_in(mode.number))


def _writes(agent: ir.Agent, action: ir.Action | ir.Hazard) -> list[ir.Update]:
    shared = {v.name for v in agent.model.variables} - set(agent.own)
    return [u for o in action.outcomes for u in o.updates if u.var in shared]


def check_writers(comp: ir.Composition, rep: Reporter) -> None:
    """E255: an agent writes only the shared variables it is listed as a writer of (and
    never another agent's mode, which it sees as a variable)."""
    allowed = dict(comp.writers)
    for agent in comp.agents:
        acts: list[ir.Action | ir.Hazard] = [*agent.model.actions, *agent.model.hazards]
        for a in acts:
            for u in _writes(agent, a):
                who = allowed.get(u.var)
                if who is None or agent.name not in who:
                    whom = ", ".join(who) if who else "no agent"
                    rep.error(codes.E255, f"agent {agent.name} writes '{u.var}', which only "
                              f"{whom} may write", u.span,
                              hint=f"add {agent.name} to its 'written by' list, or let "
                              f"{whom} write it")


def check_syncs(comp: ir.Composition, rep: Reporter) -> None:
    """E312: a `sync action` some other agent also declares; E311: no two partners of one
    synchronised action write the same shared variable."""
    by_name: dict[str, list[tuple[ir.Agent, ir.Action]]] = {}
    for agent in comp.agents:
        for name in agent.syncs:
            by_name.setdefault(name, []).append((agent, agent.model.action(name)))
    for name, takers in by_name.items():
        if len(takers) == 1:
            agent, action = takers[0]
            others = [a.name for a in comp.agents if a is not agent]
            rep.error(codes.E312, f"agent {agent.name}: the synchronised action {name} has no "
                      "partner: no other agent declares 'sync action " + name + "'",
                      action.name_span,
                      hint=(f"declare 'sync action {name}' in {' or '.join(others)}, or make "
                            "it an ordinary action") if others else "make it an ordinary action")
            continue
        seen: dict[str, tuple[ir.Agent, ir.Update]] = {}
        for agent, action in takers:
            for u in _writes(agent, action):
                first = seen.get(u.var)
                if first is not None and first[0] is not agent:
                    rep.error(codes.E311, f"agents {first[0].name} and {agent.name} both write "
                              f"'{u.var}' when they take {name} together", u.span,
                              hint=f"let one of them write '{u.var}'",
                              related=[Related(f"agent {first[0].name} writes it here",
                                               first[1].span)])
                else:
                    seen.setdefault(u.var, (agent, u))
