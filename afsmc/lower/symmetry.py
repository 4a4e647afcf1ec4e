"""Symmetry reduction of a composed mission (docs/language.md, "Symmetry"): agents that
are alike -- the same variables with the same ranges and initial values, the same modes
and actions -- and that the mission treats alike are kept in a canonical order, so that
the model holds one state for each set of their local states instead of one for each
ordering of it (up to n! fewer for n agents).

**When it applies.** For a group of alike agents, exchanging two neighbours of the group
(each `r1_x` read and written as `r2_x` and back, `r1_A` as `r2_A`) must map the
mission's commands onto themselves (as a multiset, `&&`, `||`, `+`, `*`, `==` and `!=`
read as commutative) and leave every label, reward structure and property as it is.
Neighbour exchanges generate every permutation of the group, so the mission and its
properties are then invariant under all of them, and the quotient by the permutations
is exact: each property has the same min and max on it (the quotient MDP is bisimilar
to the mission for every property the permutations leave alone). Otherwise the
reduction is refused and the reason names what breaks the symmetry (a property, a label,
a reward, or the commands: a synchronised action names its partner, `ties order`
prefers the agent declared first). `compose interleaving fair;` is refused too: its
fairness is per agent, and the quotient forgets which agent is which.

**How.** The members' local states (mode, then own variables, as one integer key) are
kept in non-decreasing order along the group. A move of the member in slot s that
changes its local state puts the new local state at the position p of the others it
exceeds, and shifts the members between s and p by one: every member's local variables
are written by that command, each as a choice over p. The states reachable so are
exactly the sorted representatives, the initial state being one (the members start
alike). The members' variables are written by another member's commands, so the PRISM
backend declares them global; a member may therefore not take part in a synchronised
action (PRISM forbids a synchronised command to write a global variable), which is
refused with its reason too.
"""

from __future__ import annotations

from collections import Counter
from dataclasses import dataclass, replace

from afsmc.diagnostics import Span
from afsmc.lower.compose import Network, Part, assemble
from afsmc.lower.lowering import Branch, Command, Lowered, SymmetryNote
from afsmc.lower.reduce import Reductions
from afsmc.model import expr as E
from afsmc.model import ir
from afsmc.model.expr import Type
from afsmc.model.semantics import inline

COMMUTATIVE = frozenset({"&&", "||", "+", "*", "==", "!="})


@dataclass(frozen=True)
class Group:
    """Alike agents, by their index in the network, and their local variables in the
    mission's names' suffixes ("mode" first)."""

    members: tuple[int, ...]
    local: tuple[str, ...]


@dataclass(frozen=True)
class Outcome:
    """The reduced model (or the model as it was) and, for each group, what was done or
    why not."""

    lowered: Lowered
    applied: tuple[str, ...]  # "r1, r2, r3, r4" per group reduced
    refused: str | None  # why not, naming what breaks the symmetry
    where: Span | None = None  # the property, label or reward that breaks it
    alike: bool = True  # some agents are alike (else there is nothing to reduce)


def decide(reductions: Reductions | None, hindrance: str | None) -> Reductions:
    """The symmetry reduction as every verifying front-end decides it (verify, sweep,
    report and the Python API, through afsmc.verify.check): `None` is the default, every
    reduction on and the symmetry "auto"; "auto" stays (tried, and applied where the
    mission and the properties checked treat the alike agents alike) unless something
    asked for stands in its way (`hindrance`, in words: an output that names the agents,
    which the canonical order turns into slots, or an engine that cannot build the reduced
    model); it is then "off", with that reason for the header. "on" (--symmetry) and "off"
    (--no-symmetry) are as asked."""
    r = Reductions(symmetry="auto") if reductions is None else reductions
    if r.symmetry != "auto" or hindrance is None:
        return r
    return replace(r, symmetry="off", symmetry_off=hindrance)


def symmetric(low: Lowered, options: Reductions) -> Lowered:
    """The lowered mission with the symmetry reduction as `options` decide: applied if it
    is tried and exact, else the mission as it was; `Lowered.symmetry` and the header's
    list of reductions say which, and why not where the mission has alike agents (or
    --symmetry asked for it)."""
    if options.symmetry == "off":
        net = low.network
        if options.symmetry_off is None or not isinstance(net, Network) \
                or not candidates(low, net):
            return low
        out = Outcome(low, (), options.symmetry_off)
    else:
        out = reduce_symmetric(low)
    if out.refused is None:
        groups = tuple(tuple(n.split(", ")) for n in out.applied)
        return replace(out.lowered, symmetry=SymmetryNote(groups))
    if not out.alike and options.symmetry == "auto":
        return low  # nothing to reduce, and nobody asked
    return replace(low, reductions=(*low.reductions, f"no symmetry: {out.refused}"),
                   symmetry=SymmetryNote((), out.refused, out.where))


def reduce_symmetric(low: Lowered) -> Outcome:
    net = low.network
    if not isinstance(net, Network):
        return Outcome(low, (), "the mission has one agent", alike=False)
    groups = candidates(low, net)
    if not groups:
        return Outcome(low, (), "no two agents are alike (the same variables, ranges, "
                       "initial values, modes and actions)", alike=False)
    if net.ties == "fair":
        return Outcome(low, (), "fairness ('compose interleaving fair') is per agent, and "
                       "the quotient does not keep which agent is which")
    for g in groups:
        why = breaks(low, net, g)
        if why is not None:
            return Outcome(low, (), *why)
    parts = list(net.parts)
    moved: set[str] = set()
    for g in groups:
        for slot, i in enumerate(g.members):
            parts[i] = _sorted_part(parts[i], net, g, slot, low.model)
        moved |= {net.parts[i].agent.prefix + v for i in g.members for v in g.local}
    new = replace(net, parts=tuple(parts), global_locals=frozenset(moved))
    names = tuple(", ".join(net.parts[i].agent.name for i in g.members) for g in groups)
    reduced = replace(low, commands=assemble(new), network=new,
                      reductions=(*low.reductions, *(f"symmetry ({n})" for n in names)))
    return Outcome(reduced, names, None)


# ---- which agents are alike --------------------------------------------------------


def _local(agent: ir.Agent) -> tuple[str, ...]:
    return ("mode", *agent.own)


def _var(model: ir.Model, agent: ir.Agent, local: str) -> ir.Variable:
    name = agent.mode_var if local == "mode" else agent.prefix + local
    return next(v for v in model.variables if v.name == name)


def _shape(low: Lowered, agent: ir.Agent) -> object:
    """What two alike agents share: their variables' names, types, ranges and initial
    values, their modes and their actions."""
    variables = tuple((v, (x.type, x.lo, x.hi, x.init))
                      for v in _local(agent) for x in (_var(low.model, agent, v),))
    modes = tuple((m.name, m.number, m.initial, m.final) for m in agent.model.modes)
    return (variables, modes, tuple(a.name for a in agent.model.actions), agent.syncs,
            agent.clock)


def candidates(low: Lowered, net: Network) -> list[Group]:
    """The groups of at least two alike agents, each in declaration order."""
    by_shape: dict[object, list[int]] = {}
    for i, part in enumerate(net.parts):
        by_shape.setdefault(_shape(low, part.agent), []).append(i)
    return [Group(tuple(m), _local(net.parts[m[0]].agent))
            for m in by_shape.values() if len(m) > 1]


# ---- whether the mission treats them alike -----------------------------------------


def _swap(net: Network, g: Group, a: int, b: int) -> tuple[dict[str, str], dict[str, str]]:
    """The variables' and actions' renaming that exchanges members a and b."""
    pa, pb = net.parts[a].agent, net.parts[b].agent
    names: dict[str, str] = {}
    for v in g.local:
        x, y = (pa.mode_var, pb.mode_var) if v == "mode" else (pa.prefix + v, pb.prefix + v)
        names[x], names[y] = y, x
    actions = {pa.prefix + act.name: pb.prefix + act.name for act in pa.model.actions}
    actions.update({v: k for k, v in actions.items()})
    return names, actions


def norm(e: E.Expr, names: dict[str, str], model: ir.Model) -> str:
    """The expression as text with the variables renamed, commutative operators' operands
    sorted (so that `r1_x == 1 && r2_x == 1` is its own image)."""
    e = inline(e, model)

    def go(n: E.Expr) -> str:
        if isinstance(n, E.VarRef):
            return names.get(n.name, n.name)
        if isinstance(n, E.Lit):
            return f"{n.value!r}:{n.type}"
        if isinstance(n, E.Binary):
            if n.op in COMMUTATIVE:
                return f"{n.op}(" + ",".join(sorted(go(x) for x in _flat(n, n.op))) + ")"
            return f"{n.op}({go(n.left)},{go(n.right)})"
        if isinstance(n, E.Unary):
            return f"{n.op}({go(n.operand)})"
        if isinstance(n, E.Ite):
            return f"ite({go(n.cond)},{go(n.then)},{go(n.other)})"
        if isinstance(n, E.Call):
            return f"{n.func}(" + ",".join(go(x) for x in n.args) + ")"
        if isinstance(n, E.WeightRef):
            return f"w:{names.get(n.action, n.action)}"
        return repr(replace(n, span=None))
    return go(e)


def _flat(e: E.Expr, op: str) -> list[E.Expr]:
    if isinstance(e, E.Binary) and e.op == op and op not in ("==", "!="):
        return _flat(e.left, op) + _flat(e.right, op)
    if isinstance(e, E.Binary) and e.op == op:
        return [e.left, e.right]
    return [e]


def _commands(low: Lowered, names: dict[str, str], actions: dict[str, str]) -> Counter[str]:
    out: Counter[str] = Counter()
    for c in low.commands:
        branches = sorted(
            norm(b.prob, names, low.model) + "|" + ";".join(sorted(
                f"{names.get(v, v)}:={norm(x, names, low.model)}" for v, x in b.updates))
            for b in c.branches)
        out[f"{actions.get(c.action, c.action)}|{c.kind}|{norm(c.guard, names, low.model)}|"
            + "/".join(branches)] += 1
    return out


def _rewards(low: Lowered, r: ir.RewardStruct, names: dict[str, str],
             actions: dict[str, str]) -> Counter[str]:
    return Counter(f"{actions.get(it.action or '', it.action)}|{norm(it.guard, names, low.model)}"
                   f"|{norm(it.value, names, low.model)}" for it in r.items)


def _property(low: Lowered, p: ir.Property, names: dict[str, str]) -> tuple[str, ...]:
    path = p.path
    parts = [path.target, path.bound] + ([path.left] if isinstance(path, ir.Path) else [])
    return tuple(norm(x, names, low.model) if x is not None else "" for x in parts)


def breaks(low: Lowered, net: Network, g: Group) -> tuple[str, Span | None] | None:
    """Why exchanging members of `g` changes the mission or what it asks (and where that
    is declared), or None."""
    agents = [net.parts[i].agent for i in g.members]
    who = ", ".join(a.name for a in agents)
    if agents[0].syncs:
        return (f"the agents {who} take part in synchronised actions "
                f"({', '.join(agents[0].syncs)}), which name each agent's partner", None)
    same: dict[str, str] = {}
    pairs = [(a, b, _swap(net, g, a, b)) for a, b in zip(g.members, g.members[1:],
                                                         strict=False)]
    # what is asked first: a property that reads one agent also keeps that agent's
    # variables live where the others' are reset, so the commands would differ too
    for a, b, (names, actions) in pairs:
        pair = f"{net.parts[a].agent.name} and {net.parts[b].agent.name}"
        for lb in low.model.labels:
            if norm(lb.value, names, low.model) != norm(lb.value, same, low.model):
                return f"the label {lb.name} tells {pair} apart", lb.span
        for r in low.model.rewards:
            if _rewards(low, r, names, actions) != _rewards(low, r, same, same):
                return f"the reward structure {r.name} tells {pair} apart", r.span
        for p in low.model.properties:
            if _property(low, p, names) != _property(low, p, same):
                return f"the property {p.name} tells {pair} apart", p.span
    base = _commands(low, same, same)
    for a, b, (names, actions) in pairs:
        if _commands(low, names, actions) != base:
            pair = f"{net.parts[a].agent.name} and {net.parts[b].agent.name}"
            why = ("agents that may move at once move in declaration order ('ties order')"
                   if net.kind == "timed" and net.ties == "order" else
                   "their moves read or are read differently (a guard, an update or another "
                   "agent names one of them)")
            return f"the mission does not treat {pair} alike: {why}", None
    return None


# ---- the canonical order -----------------------------------------------------------


def _key(model: ir.Model, agent: ir.Agent, local: tuple[str, ...],
         values: dict[str, E.Expr]) -> E.Expr:
    """The member's local state as one integer, the first variable most significant."""
    key: E.Expr = E.Lit(0, Type.INT)
    for v in local:
        x = _var(model, agent, v)
        size = 2 if x.type is Type.BOOL else int(x.hi) - int(x.lo) + 1
        val = values[v]
        digit = (E.Ite(val, E.Lit(1, Type.INT), E.Lit(0, Type.INT), Type.INT)
                 if x.type is Type.BOOL else E.Binary("-", val, E.Lit(int(x.lo), Type.INT),
                                                      Type.INT))
        key = E.Binary("+", E.Binary("*", key, E.Lit(size, Type.INT), Type.INT), digit, Type.INT)
    return key


def _sorted_part(part: Part, net: Network, g: Group, slot: int, model: ir.Model) -> Part:
    local = tuple(_sorted_command(c, net, g, slot, model) for c in part.local)
    return replace(part, local=local)


def _sorted_command(cmd: Command, net: Network, g: Group, slot: int,
                    model: ir.Model) -> Command:
    agents = [net.parts[i].agent for i in g.members]
    mine = {(agents[slot].mode_var if v == "mode" else agents[slot].prefix + v): v
            for v in g.local}
    branches = []
    for b in cmd.branches:
        if not any(v in mine for v, _ in b.updates):
            branches.append(b)  # the member's local state is unchanged: so is the order
            continue
        branches.append(replace(b, updates=_shifted(b, agents, g, slot, model, mine)))
    return replace(cmd, branches=tuple(branches))


def _shifted(b: Branch, agents: list[ir.Agent], g: Group, slot: int, model: ir.Model,
             mine: dict[str, str]) -> tuple[tuple[str, E.Expr], ...]:
    """The branch's updates with the moved member put in its place in the order."""
    def cur(agent: ir.Agent, v: str) -> E.Expr:
        x = _var(model, agent, v)
        return E.VarRef(x.name, x.type)

    new = {v: cur(agents[slot], v) for v in g.local}
    new.update({mine[v]: x for v, x in b.updates if v in mine})
    key_new = _key(model, agents[slot], g.local, new)
    others = [agents[m] for m in range(len(agents)) if m != slot]

    def below(other: ir.Agent) -> E.Expr:
        """The other member's local state comes before the moved one's new state."""
        key = _key(model, other, g.local, {v: cur(other, v) for v in g.local})
        return E.Binary("<", key, key_new, Type.BOOL)

    # The others are in order, so the new state's place p (how many of them come before
    # it) exceeds m exactly when the m-th of them comes before it.
    ups = [(v, x) for v, x in b.updates if v not in mine]
    n = len(agents)
    for m in range(n):
        for v in g.local:
            x = _var(model, agents[m], v)
            value: E.Expr = new[v]
            if m >= 1:  # p <= m: the new state here if p == m, else the (m-1)-th other
                value = E.Ite(below(others[m - 1]), value, cur(others[m - 1], v), x.type)
            if m <= n - 2:  # p > m: the m-th other
                value = E.Ite(below(others[m]), cur(others[m], v), value, x.type)
            ups.append((x.name, value))
    return tuple(ups)
