"""JANI backend of a composed mission: an automata network, one automaton per agent, with
the composition as sync vectors (an agent's own action alone, a synchronised action with
every partner). The variables are all global, as in the single-agent model, so that a
guard may read another agent's mode; labels and state rewards are the first automaton's
location's transient values, the action rewards of a synchronised action are on its
first partner's destinations (so that the joint move earns them once).

**One automaton per agent, not per template.** JANI allows one automaton to be named by
several `system.elements`, each with its own copy of the automaton's local variables,
which would write a template once. Storm 2 does not give each element its copy: its
sparse builder builds such a network as if the elements shared their locals (a wrong
model, silently) and its flattening refuses it ("Cannot add variable with name ...,
because a variable with that name already exists"); tests/unit/backends/
test_jani_template_automata.py pins this on a hand-written pair. So every instance is an
automaton of its own, which the file's metadata says."""

from __future__ import annotations

from typing import Any

from afsmc.backends.jani import (
    LOCATION,
    Json,
    _Exprs,
    _location,
    _Names,
    _properties,
    _reward_sum,
    _variables,
    _where,
    header,
)
from afsmc.lower.compose import Network
from afsmc.lower.lowering import Command, Lowered
from afsmc.model import expr as E
from afsmc.model import ir


def _edge(cmd: Command, extra: E.Expr, label: str | None, rewarded: bool, low: Lowered,
          names: _Names, ex: _Exprs) -> Json:
    edge: Json = {"location": LOCATION}
    rewards: list[Json] = []
    if label is not None:
        edge["action"] = label
        for r in low.model.rewards if rewarded else ():
            items = [it for it in r.items if it.action == label]
            if items:
                rewards.append({"ref": names.rewards[r.name], "value": _reward_sum(items, ex)})
    edge["guard"] = {"exp": ex(E.conj(cmd.guard, extra))}
    edge["destinations"] = [
        {"location": LOCATION, "probability": {"exp": ex(b.prob)},
         "assignments": [{"ref": var, "value": ex(val)} for var, val in b.updates] + rewards}
        for b in cmd.branches]
    comment = f"{label or 'no agent can move'}: {_where(cmd.span)}"
    if cmd.choice:
        comment += " (" + ", ".join(f"{c}={end}" for c, end in cmd.choice) + ")"
    edge["comment"] = comment
    return edge


def emit_network(low: Lowered) -> dict[str, Any]:
    net = low.network
    assert isinstance(net, Network)
    model = low.model
    names = _Names(low)
    ex = _Exprs(low, names)
    automata = []
    actions: list[str] = []
    syncs = []
    n = len(net.parts)
    leads = {name: next(i for i, q in enumerate(net.parts) if any(s == name for s, _ in q.sync))
             for part in net.parts for name, _ in part.sync}
    for i, part in enumerate(net.parts):
        timing = dict(part.sync_timing)
        edges = []
        for cmd in part.local:
            edges.append(_edge(cmd, part.timing, cmd.action, True, low, names, ex))
            if cmd.action not in actions:
                actions.append(cmd.action)
                syncs.append({"synchronise": [cmd.action if j == i else None for j in range(n)],
                              "result": cmd.action})
        for name, cmds in part.sync:
            lead = leads[name] == i
            edges += [_edge(c, timing[name] if lead else E.TRUE, name, lead, low, names, ex)
                      for c in cmds]
        if i == 0:
            edges.append(_edge(net.stay, E.TRUE, None, False, low, names, ex))
        loc = _location(low, names, ex) if i == 0 else {"name": LOCATION}
        automata.append({"name": part.agent.name, "locations": [loc],
                         "initial-locations": [LOCATION], "edges": edges})
    for name in sorted(leads):
        takers = [j for j, q in enumerate(net.parts) if any(s == name for s, _ in q.sync)]
        if len(takers) < 2:
            continue
        actions.append(name)
        syncs.append({"synchronise": [name if j in takers else None for j in range(n)],
                      "result": name})
    how = ir.composition_text(net.kind, net.ties) + ", one automaton per agent"
    sym = low.symmetry
    if sym is not None:  # as the PRISM header's list of reductions says it
        how += "; " + (f"no symmetry: {sym.reason}" if sym.reason is not None else
                       "; ".join(f"symmetry ({', '.join(g)})" for g in sym.groups))
    return {
        **header(low, f"mission {model.name}, {how}", actions),
        "variables": _variables(low, names),
        "properties": _properties(low, names, ex),
        "automata": automata,
        "system": {"elements": [{"automaton": part.agent.name} for part in net.parts],
                   "syncs": syncs},
    }
