"""Agent templates instantiated: `agent Robot(id, grant) { ... }` declares an agent once,
`agents r1 = Robot(1, Grant1), r2 = Robot(2, Grant2);` makes one agent of it per instance
(docs/language.md, "Templates").

Each instance is the template's syntax tree with its parameters replaced by the
instance's arguments, standing where the `agents` declaration stands, so that the rest of
the composed mission's resolution (afsmc.resolve.compose) takes it as if written out. A
parameter stands for what its argument is: an expression where it is read (a constant,
a shared variable, the agent's index), and, when the argument is a name, that name
wherever a name stands (a variable it writes, a synchronised action's name, another
agent in `peer.mode`). The instance keeps the template's spans, so that a diagnostic
about its text points at the template's line; the resolver names the instance in it.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping
from typing import Any

from afsmc.diagnostics import Reporter, Span, codes
from afsmc.resolve.compose import rewrite
from afsmc.syntax import ast

# More agents than a family may make: each is a module of the PRISM output and a factor of
# the state space; a typo in N should not make a million agents.
MAX_FAMILY = 64


def expand(module: ast.Module, rep: Reporter,
           overrides: Mapping[str, str] | None = None) -> ast.Module:
    """The module with each template left out and each instance an agent of its own (an
    indexed family `agent r[1..N] : Robot;` the instances r1 .. rN; `overrides`: the
    `--const` values its bounds may read)."""
    templates: dict[str, ast.AgentDecl] = {}
    for d in module.decls:
        if isinstance(d, ast.AgentDecl) and d.params is not None:
            if d.name.text in templates:
                rep.error(codes.E253, f"the agent template {d.name.text} is declared twice",
                          d.name.span)
                continue
            templates[d.name.text] = d
            _check_params(d, rep)
    decls: list[ast.Decl] = []
    families: dict[str, tuple[str, ...]] = {}  # a family's name -> its members' names
    for d in module.decls:
        if isinstance(d, ast.FamilyDecl):
            name = d.name.text
            d = _family(d, module, templates, rep, overrides or {})
            if d.instances:
                families[name] = tuple(i.name.text for i in d.instances)
        if isinstance(d, ast.AgentsDecl):
            decls += [a for i in d.instances if (a := _instance(i, templates, rep)) is not None]
        elif not (isinstance(d, ast.AgentDecl) and d.params is not None):
            decls.append(d)
    if families:
        decls = list(rewrite(tuple(decls), _over_families(families, rep)))
    return dataclasses.replace(module, decls=tuple(decls))


# ---- expressions over a family's members ----------------------------------------------

AGGREGATES: dict[str, ast.BinOp] = {"count": "+", "all": "&&", "any": "||"}


def _over_families(families: dict[str, tuple[str, ...]], rep: Reporter) -> Any:
    """The rewriting of `count(e)`, `all(e)` and `any(e)` where `e` reads a family's
    members by the family's name (`count(r.mode == Done) >= 2`, `all(r.done == ORDERS)`,
    `any(r.mode in {Wait, Charging})`): `e` once per member, `r` replaced by the member's
    name, joined by `+` (each as 1 or 0), `&&` or `||`. The family's name read elsewhere
    is E253."""
    def go(n: Any) -> Any:
        if isinstance(n, ast.Call) and n.func.text in AGGREGATES:
            return _aggregate(n, families, rep, go)
        fam = _family_read(n, families)
        if fam is not None:
            rep.error(codes.E253, f"'{fam}' is a family of agents ({', '.join(families[fam])}): "
                      "its members are read one at a time, or all at once in count(...), "
                      "all(...) or any(...)", n.span,
                      hint=f"for example 'count({fam}.mode == Done) >= 2', or "
                      f"'{families[fam][0]}.mode'")
            return n
        return None
    return go


def _family_read(n: Any, families: dict[str, tuple[str, ...]]) -> str | None:
    """The family `n` reads by its name (`r.mode`, `r.x`, `r.mode in {...}`), if it does."""
    if isinstance(n, ast.FieldRef) and n.base.text in families:
        return n.base.text
    if isinstance(n, ast.ModeIn) and n.agent is not None and n.agent.text in families:
        return n.agent.text
    return None


def _aggregate(call: ast.Call, families: dict[str, tuple[str, ...]], rep: Reporter,
               go: Any) -> ast.Expr:
    f = call.func.text
    read: list[str] = []

    def find(n: Any) -> Any:
        fam = _family_read(n, families)
        if fam is not None and fam not in read:
            read.append(fam)
        return None
    if len(call.args) == 1:
        rewrite(call.args[0], find)
    if len(call.args) != 1 or len(read) != 1:
        what = ("one expression" if len(call.args) != 1 else
                "an expression that reads one family's members by the family's name")
        rep.error(codes.E253, f"{f}(...) takes {what}" + (
            f"; this one reads {', '.join(read)}" if len(read) > 1 else ""), call.span,
            hint=f"for example '{f}(" + (f"{next(iter(families))}" if families else "r")
            + ".mode == Done)'")
        return call
    members = families[read[0]]

    def member(name: str) -> ast.Expr:
        def put(n: Any) -> Any:
            if _family_read(n, families) == read[0]:
                field = "base" if isinstance(n, ast.FieldRef) else "agent"
                return dataclasses.replace(n, **{field: ast.Ident(name, call.func.span)})
            return None
        e: ast.Expr = rewrite(rewrite(call.args[0], put), go)
        if f == "count":
            return ast.Ite(e, ast.Num(1, "1", call.span), ast.Num(0, "0", call.span), call.span)
        return e
    out = member(members[0])
    for name in members[1:]:
        out = ast.Binary(AGGREGATES[f], out, member(name), call.span)
    return out


def _family(d: ast.FamilyDecl, module: ast.Module, templates: dict[str, ast.AgentDecl],
            rep: Reporter, overrides: Mapping[str, str]) -> ast.AgentsDecl:
    """The family's instances as an `agents` declaration: r1 .. rN, each given its index
    if the template has a parameter."""
    lo, hi = (_value(e, module, overrides, d, rep) for e in (d.lo, d.hi))
    if lo is None or hi is None:
        return ast.AgentsDecl((), d.span)
    if not 0 <= lo <= hi or hi - lo + 1 > MAX_FAMILY:
        rep.error(codes.E253, f"the family {d.name.text}[{lo}..{hi}] must have from 1 to "
                  f"{MAX_FAMILY} agents, indices from 0 up", d.span,
                  hint=f"write 'agent {d.name.text}[1..N] : {d.template.text};' with N >= 1")
        return ast.AgentsDecl((), d.span)
    template = templates.get(d.template.text)
    params = () if template is None else template.params or ()
    if template is not None and len(params) > 1:
        rep.error(codes.E253, f"the family {d.name.text} gives each agent its index, but the "
                  f"template {d.template.text} takes {len(params)} parameters", d.span,
                  hint=f"give {d.template.text} one parameter (the index) or none, or "
                  "instantiate it with 'agents r1 = ..., r2 = ...;'")
        return ast.AgentsDecl((), d.span)
    return ast.AgentsDecl(tuple(
        ast.Instance(ast.Ident(f"{d.name.text}{i}", d.name.span), d.template,
                     (ast.Num(i, str(i), d.span),) if params else (), d.span)
        for i in range(lo, hi + 1)), d.span)


def _value(e: ast.Expr, module: ast.Module, overrides: Mapping[str, str],
           d: ast.FamilyDecl, rep: Reporter) -> int | None:
    """A family's bound: an integer from numbers, constants and params (`--const` given
    first) with + - *; None, reported, otherwise."""
    values: dict[str, ast.Expr | None] = {}
    for c in module.decls:
        if isinstance(c, ast.ConstDecl) and not isinstance(c.value, ast.Interval):
            values[c.name.text] = c.value
        elif isinstance(c, ast.ParamDecl):
            values[c.name.text] = c.default

    def go(x: ast.Expr, depth: int) -> int | None:
        if depth > 32:
            return None
        if isinstance(x, ast.Num) and isinstance(x.value, int):
            return x.value
        if isinstance(x, ast.Name):
            name = x.name.text
            if name in overrides:
                text = overrides[name].strip()
                return int(text) if text.lstrip("-").isdigit() else None
            got = values.get(name)
            return None if got is None else go(got, depth + 1)
        if isinstance(x, ast.Binary) and x.op in ("+", "-", "*"):
            a, b = go(x.left, depth + 1), go(x.right, depth + 1)
            if a is None or b is None:
                return None
            return a + b if x.op == "+" else a - b if x.op == "-" else a * b
        return None
    out = go(e, 0)
    if out is None:
        rep.error(codes.E253, f"the bounds of the family {d.name.text} must be integers from "
                  "numbers, constants and params with + - *", e.span,
                  hint=f"for example 'agent {d.name.text}[1..N] : {d.template.text};' with "
                  "'param int N = 4;'")
    return out


def _check_params(template: ast.AgentDecl, rep: Reporter) -> None:
    seen: set[str] = set()
    for p in template.params or ():
        if p.text in seen:
            rep.error(codes.E253, f"the template {template.name.text} has two parameters "
                      f"named '{p.text}'", p.span)
        seen.add(p.text)


def _instance(inst: ast.Instance, templates: dict[str, ast.AgentDecl],
              rep: Reporter) -> ast.AgentDecl | None:
    template = templates.get(inst.template.text)
    if template is None:
        known = ", ".join(sorted(templates)) or "none is declared"
        rep.error(codes.E253, f"'{inst.template.text}' is no agent template (templates: "
                  f"{known})", inst.template.span,
                  hint=f"declare it: 'agent {inst.template.text}(id) {{ ... }}'")
        return None
    params = template.params or ()
    if len(inst.args) != len(params):
        names = ", ".join(p.text for p in params)
        rep.error(codes.E253, f"agent {inst.name.text}: the template {template.name.text}"
                  f"({names}) takes {len(params)} argument{'' if len(params) == 1 else 's'}, "
                  f"given {len(inst.args)}", inst.span)
        return None
    args = {p.text: a for p, a in zip(params, inst.args, strict=True)}
    fn = _substitution(args, inst, template, rep)
    clock = rewrite(template.clock, fn) if template.clock is not None else None
    decls = rewrite(template.decls, fn)
    return ast.AgentDecl(inst.name, clock, decls, template.span)


def _substitution(args: dict[str, ast.Expr], inst: ast.Instance, template: ast.AgentDecl,
                  rep: Reporter) -> Any:
    """The rewriting of the template's tree for one instance (see the module's doc)."""
    reported: set[str] = set()

    def name_for(ident: ast.Ident) -> ast.Ident:
        arg = args[ident.text]
        if isinstance(arg, ast.Name):
            return ast.Ident(arg.name.text, ident.span)
        if ident.text not in reported:
            reported.add(ident.text)
            rep.error(codes.E253, f"agent {inst.name.text}: the parameter '{ident.text}' of "
                      f"template {template.name.text} stands where a name must (a variable "
                      "written, an action, a mode, an agent), but its argument is an "
                      "expression", ident.span,
                      hint=f"give '{ident.text}' a name in '{inst.name.text} = "
                      f"{template.name.text}(...)'")
        return ident

    def go(n: Any) -> Any:
        if isinstance(n, ast.Name) and n.name.text in args:
            return _at(args[n.name.text], n.span)
        if isinstance(n, ast.FieldRef) and n.base.text in args:
            return dataclasses.replace(n, base=name_for(n.base))
        if isinstance(n, ast.Ident) and n.text in args:
            return name_for(n)
        return None
    return go


def _at(expr: ast.Expr, span: Span) -> ast.Expr:
    """An argument as it stands in the template: every span of it at the use, so that a
    diagnostic about it points at the template's line."""
    def go(n: Any) -> Any:
        if isinstance(n, Span):
            return span
        return ast.Ident(n.text, span) if isinstance(n, ast.Ident) else None
    out: ast.Expr = rewrite(expr, go)
    return out
