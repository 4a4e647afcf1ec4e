"""PRISM backend of a composed mission: one module per agent, the shared variables
global, a synchronised action one label that its partners' modules share (PRISM's
parallel composition then takes them together: the product the lowering describes)."""

from __future__ import annotations

import os
import re

from afsmc import __version__
from afsmc.backends.prism import (
    PrismOutput,
    PrismPrinter,
    _constants,
    pnum,
    prange,
    properties,
    where,
)
from afsmc.lower.compose import Network
from afsmc.lower.lowering import Command, Lowered
from afsmc.model import expr as E
from afsmc.model import ir
from afsmc.model.pretty import number


def _variable(v: ir.Variable, head: str) -> str:
    note = f" // {v.display}, {where(v.span)}" + (", clamped" if v.clamp else "")
    if v.type is E.Type.BOOL:
        return f"{head}{v.name} : bool init {number(bool(v.init))};{note}"
    return f"{head}{v.name} : {prange(v.lo, v.hi)} init {pnum(v.init)};{note}"


def _command(p: PrismPrinter, label: str, cmd: Command, extra: E.Expr) -> list[str]:
    out = []
    if cmd.choice:
        out.append("  // " + ", ".join(f"{c}={end}" for c, end in cmd.choice))
    out.append(f"  [{label}] {p(E.conj(cmd.guard, extra))} ->")
    branches = []
    for b in cmd.branches:
        ups = " & ".join(f"({var}'={p(val)})" for var, val in b.updates) or "true"
        branches.append(f"{p.show(b.prob, 8)} : {ups}")
    out.append("    " + "\n  + ".join(branches) + ";")
    return out


def _module(p: PrismPrinter, low: Lowered, net: Network, i: int) -> list[str]:
    part = net.parts[i]
    agent = part.agent
    model = low.model
    out = ["", f"module {agent.name} // {where(agent.span)}"]
    modes = ", ".join(f"{m.name}={m.number}" for m in agent.model.modes)
    out.append(f"  // modes: {modes}")
    mine = {agent.mode_var, *(agent.prefix + v for v in agent.own)} - net.global_locals
    for v in model.variables:
        if v.name in mine:
            out.append(_variable(v, "  "))
    for cmd in part.local:
        out.append("")
        out.append(f"  // action {cmd.action.removeprefix(agent.prefix)}: {where(cmd.span)}")
        out += _command(p, cmd.action, cmd, part.timing)
    timing = dict(part.sync_timing)
    for name, cmds in part.sync:
        out.append("")
        out.append(f"  // synchronised action {name}")
        # the timing of the joint move stands in its first partner's guard
        lead = next(q.agent.name for q in net.parts if any(n == name for n, _ in q.sync))
        for cmd in cmds:
            out += _command(p, name, cmd, timing[name] if lead == agent.name else E.TRUE)
    if i == 0:
        out.append("")
        out.append("  // no agent can move: the mission stays where it is")
        out += _command(p, "", net.stay, E.TRUE)
    out.append("endmodule")
    return out


def _names(net: Network, base: int, i: int) -> dict[str, str]:
    """What renames agent `base`'s module into agent `i`'s: its variables and its own
    actions' labels (a synchronised action's label, in declaration order)."""
    a, b = net.parts[base], net.parts[i]
    names = {a.agent.mode_var: b.agent.mode_var}
    names.update({a.agent.prefix + v: b.agent.prefix + v for v in a.agent.own})
    names.update({c.action: c.action.replace(a.agent.prefix, b.agent.prefix, 1)
                  for c in a.local})
    if len(a.sync) == len(b.sync):
        names.update({x: y for (x, _), (y, _) in zip(a.sync, b.sync, strict=True) if x != y})
    return names


def _body(lines: list[str]) -> list[str]:
    """A module's lines without its header and comments: what a renaming must reproduce."""
    out = [re.sub(r"\s*//.*$", "", line) for line in lines[2:]]
    return [line for line in out if line.strip()]


def _renaming(net: Network, modules: list[list[str]], i: int) -> list[str] | None:
    """Agent `i`'s module as PRISM's module renaming of an earlier instance of its
    template, if renaming that one's variables and labels gives exactly its text (the
    first module, which also holds the mission's self-loop, is never renamed)."""
    agent = net.parts[i].agent
    for base in range(1, i):
        if net.parts[base].agent.own != agent.own:
            continue
        names = _names(net, base, i)
        if any(v in names.values() for v in _words(modules[base])):
            continue  # the base reads the agent's own names: no renaming maps onto them
        renamed = _renamed(_body(modules[base]), names)
        if renamed == _body(modules[i]) and not _renaming(net, modules, base):
            pairs = ", ".join(f"{x}={y}" for x, y in names.items())
            return ["", f"// {agent.name}: {net.parts[base].agent.name} with its names "
                    f"renamed ({where(agent.span)})",
                    f"module {agent.name} = {net.parts[base].agent.name} [{pairs}] endmodule"]
    return None


def _renamed(lines: list[str], names: dict[str, str]) -> list[str]:
    pattern = re.compile(r"\b(" + "|".join(map(re.escape, names)) + r")\b")
    return [pattern.sub(lambda m: names[m.group(1)], line) for line in lines]


def _words(lines: list[str]) -> set[str]:
    return {w for line in _body(lines) for w in re.findall(r"\w+", line)}


def emit_network(low: Lowered) -> PrismOutput:
    net = low.network
    assert isinstance(net, Network)
    model = low.model
    p = PrismPrinter({}, low)
    agents = ", ".join(part.agent.name for part in net.parts)
    how = ir.composition_text(net.kind, net.ties)
    out = [f"// Generated by afsmc {__version__} from {os.path.basename(model.source.path)} "
           f"(mission {model.name}: agents {agents}; {how}). Do not edit: edit the .afsm file."]
    if model.is_nondeterministic:
        how = {"nondet": "a nondeterministic floor/ceil choice (min/max bounds)",
               "uniform": "a uniform random floor/ceil choice",
               "lo": "their floor", "hi": "their ceiling"}[low.resolution]
        out.append(f"// Interval constants are resolved by {how}.")
    if low.reductions:
        out.append(f"// Exact reductions: {', '.join(low.reductions)} "
                   "(afsmc compile --no-reduce: none"
                   + ("; --no-symmetry: the agents as they are" if low.symmetry is not None
                      and low.symmetry.reason is None else "") + ").")
    out += [low.kind, ""]
    out += _constants(low)
    if model.formulas:
        out += ["", "// ---- formulas"]
    for f in model.formulas:
        out.append(f"formula {f.name} = {p(f.value)}; // {where(f.span)}")
    owned = {part.agent.mode_var for part in net.parts} | {
        part.agent.prefix + v for part in net.parts for v in part.agent.own}
    shared = [v for v in model.variables if v.name not in owned or v.name in net.global_locals]
    if shared:
        out += ["", "// ---- shared variables"]
    out += [_variable(v, "global ") for v in shared]
    modules = [_module(p, low, net, i) for i in range(len(net.parts))]
    for i, lines in enumerate(modules):
        out += _renaming(net, modules, i) or lines
    if model.labels:
        out.append("")
    for lb in model.labels:
        out.append(f'label "{lb.name}" = {p(lb.value)}; // {where(lb.span)}')
    labels = {c.action for c in low.commands if not c.silent}
    for r in model.rewards:
        out += ["", f'rewards "{r.name}" // {where(r.span)}']
        for it in r.items:
            if it.action is not None and it.action not in labels:
                continue  # an action that never fires earns nothing
            act = f"[{it.action}] " if it.action else ""
            out.append(f"  {act}{p(it.guard)} : {p(it.value)};")
        out.append("  true : 0; // an item for an empty structure; adds nothing")
        out.append("endrewards")
    out.append("")
    names, props = properties(low, p)
    return PrismOutput("\n".join(out), "\n".join(props) + "\n" if props else "", tuple(names))
