"""E314: under `compose timed ties weight;` two agents whose current actions end at the
same time are ordered by their weights, so those weights must differ wherever both can
move at the same clock. The question is asked of the mission's state (every agent's mode,
own variables and the shared variables), exactly (afsmc.model.search), and a state where
they tie is the witness."""

from __future__ import annotations

from afsmc.diagnostics import Related, Reporter, codes
from afsmc.model import expr as E
from afsmc.model import ir
from afsmc.model.expr import Type
from afsmc.model.search import Undecided, find
from afsmc.model.semantics import effective_weight, fire_condition, inline


def _rename(agent: ir.Agent, e: E.Expr) -> E.Expr:
    """An expression of the agent's view in the mission's names (its mode `<agent>_mode`,
    its own variable `x` as `<agent>_x`)."""
    own = set(agent.own)

    def fn(n: E.Expr) -> E.Expr | None:
        if isinstance(n, E.CurrentMode):
            return E.VarRef(agent.mode_var, Type.INT)
        if isinstance(n, E.ModeVal):
            return E.Lit(n.number, Type.INT)
        if isinstance(n, E.VarRef) and n.name in own:
            return E.VarRef(agent.prefix + n.name, n.type)
        return None

    return E.transform(inline(e, agent.model), fn)


def _fires(agent: ir.Agent, action: ir.Action) -> E.Expr:
    """The agent's choice is `action` (it is enabled and beats its competitors)."""
    names = agent.model.mode_names
    return _rename(agent, E.disj(*(E.conj(E.mode_in({m}, names),
                                          fire_condition(agent.model, action, m))
                                   for m in action.modes)))


def _weight(agent: ir.Agent) -> E.Expr:
    """The weight of the agent's current action: the largest effective weight."""
    out: E.Expr | None = None
    for a in agent.model.actions:
        w = _rename(agent, effective_weight(agent.model, a))
        out = w if out is None else E.Call("max", (out, w), Type.DOUBLE)
    return E.Lit(0, Type.INT) if out is None else out


def check_weight_ties(model: ir.Model, comp: ir.Composition, rep: Reporter) -> None:
    if comp.kind != "timed" or comp.ties != "weight":
        return
    agents = comp.agents
    fires = {(a.name, x.name): _fires(a, x) for a in agents for x in a.model.actions}

    def joint(name: str) -> E.Expr:
        return E.conj(*(fires[(a.name, name)] for a in agents if name in a.syncs))

    def moves(a: ir.Agent) -> E.Expr:
        return E.disj(*(joint(x.name) if x.name in a.syncs else fires[(a.name, x.name)]
                        for x in a.model.actions))

    for i, a in enumerate(agents):
        for b in agents[i + 1:]:
            if a.clock is None or b.clock is None:
                continue
            together = [joint(s) for s in a.syncs if s in b.syncs]
            pred = E.conj(moves(a), moves(b), E.neg(E.disj(*together)),
                          E.Binary("==", E.VarRef(a.prefix + a.clock, Type.INT),
                                   E.VarRef(b.prefix + b.clock, Type.INT), Type.BOOL),
                          E.Binary("==", _weight(a), _weight(b), Type.BOOL))
            try:
                w = find(model, model.modes[0].number, pred)
            except Undecided:
                w = None
            if w is None:
                continue
            rep.error(codes.E314, f"agents {a.name} and {b.name} may both move at the same "
                      f"time with actions of equal weight, which 'ties weight' cannot order: "
                      f"{_state(comp, w.values)}", comp.span or a.name_span,
                      hint=f"give the actions of {a.name} and {b.name} different weights "
                      "where both may move at once, or write 'ties order'",
                      related=[Related(f"agent {a.name}", a.name_span),
                               Related(f"agent {b.name}", b.name_span)])


def _state(comp: ir.Composition, values: tuple[tuple[str, int | bool], ...]) -> str:
    """A witness in mission terms: the agents' modes by name, variables as agent.x."""
    out = []
    for name, v in values:
        agent = next((a for a in comp.agents if name == a.mode_var), None)
        if agent is not None:
            mode = next((m.name for m in agent.model.modes if m.number == v), str(v))
            out.append(f"{agent.name}.mode = {mode}")
            continue
        owner = next((a for a in comp.agents if name.startswith(a.prefix)
                      and name.removeprefix(a.prefix) in a.own), None)
        shown = f"{owner.name}.{name.removeprefix(owner.prefix)}" if owner else name
        out.append(f"{shown} = {str(v).lower() if isinstance(v, bool) else v}")
    return ", ".join(out)
