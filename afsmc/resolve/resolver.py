"""AST -> IR: resolve names, type-check, number modes, instantiate constants.

Everything wrong is reported (not just the first problem): a failed sub-expression
becomes a placeholder of the expected type so that checking can go on. The work is split
by concern into mixins (see afsmc.resolve.base); this module runs them in order.
"""

from __future__ import annotations

import dataclasses
import os
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field

from afsmc.diagnostics import CompileError, Diagnostic, Reporter, codes
from afsmc.model import expr as E
from afsmc.model import ir
from afsmc.model.names import safe_identifier
from afsmc.resolve import compose, templates
from afsmc.resolve.actions import ActionsMixin
from afsmc.resolve.constants import ConstantsMixin
from afsmc.resolve.declarations import DeclarationsMixin
from afsmc.resolve.expressions import ExpressionsMixin
from afsmc.resolve.names import NamesMixin
from afsmc.resolve.properties import PropertiesMixin
from afsmc.syntax import ast


@dataclass(frozen=True)
class Resolved:
    """The resolved model, and what resolving learnt that the IR does not hold."""

    model: ir.Model
    warnings: tuple[Diagnostic, ...]  # sorted; errors raise CompileError instead
    # Constants and formulas the source refers to anywhere, also where the IR keeps no
    # reference (a constant's value, a variable's range): W303/W304 spare them.
    used_names: frozenset[str]
    # With `open_params`: each param without a value, and the E206 it would have been.
    open_params: Mapping[str, Diagnostic]
    # With `open_params`: each constant whose value reads such params (through other
    # constants too), and their names.
    open_reads: Mapping[str, frozenset[str]]
    # The names the model's properties may read, for properties that come later: the
    # ad-hoc ones of `verify --formula` (PropertyScope.resolve).
    scope: PropertyScope | None = field(default=None, compare=False, repr=False)


@dataclass(frozen=True)
class Adhoc:
    """Properties resolved against a resolved model (PropertyScope.resolve): each as the
    model's own would be, the diagnostics of resolving them (errors among them), and the
    names of the model's variables, constants and formulas they read."""

    properties: tuple[ir.Property, ...]
    diagnostics: tuple[Diagnostic, ...]
    reads: frozenset[str]


class PropertyScope:
    """The resolver of a model's own properties, kept after resolving the model: further
    properties (`verify --formula`) are resolved against the model itself, with what its
    declarations mean, instead of being added to its text and the whole file resolved
    again. For a composed mission, the mission's module, with the agents' names
    (`uav1.mode`) rewritten as its own properties are."""

    def __init__(self, resolver: _Resolver, names: compose._Names | None = None) -> None:
        self._resolver = resolver
        self._names = names

    def resolve(self, queries: Sequence[tuple[str, ast.PQuery | ast.RQuery]]) -> Adhoc:
        """`queries`: (name, query as parsed, e.g. by afsmc.syntax.parser.parse_property).
        The names must be new: neither a property's nor a query's of the model. The
        diagnostics come query by query, each query's sorted."""
        r = self._resolver
        before = set(r.used)
        props, diags = [], []
        for name, q in queries:
            r.rep = Reporter()
            if self._names is not None:
                self._names.rep = r.rep  # E253, E254: which agent's name it is
                q = compose.rewrite(q, self._names.fn(None))
            props.append(r._property(ast.PropertyDecl(ast.Ident(name, q.span), q, q.span)))
            diags += r.rep.sorted()
        reads = set(r.used) - before
        r.used = before  # the model's own, for the next call
        for p in props:
            for e in (getattr(p.path, "target", None), getattr(p.path, "left", None),
                      getattr(p.path, "bound", None)):
                if e is not None:
                    reads.update(n.name for n in E.walk(e)
                                 if isinstance(n, E.VarRef | E.ConstRef | E.FormulaRef))
        return Adhoc(tuple(props), tuple(diags), frozenset(reads))


def resolve(module: ast.Module, overrides: Mapping[str, str] | None = None, *,
            open_params: bool = False) -> Resolved:
    """The module resolved, or CompileError with every error found.

    `open_params`: a param with no value is no error but a stand-in (for sim-check, which
    needs only the values of the simulated constants); `Resolved.open_params` and
    `Resolved.open_reads` say which params and which constants that concerns."""
    if compose.is_composed(module):
        return _resolve_composed(module, overrides, open_params)
    r = _Resolver(module, dict(overrides or {}), open_params)
    model = r.run()
    if r.rep.has_errors:
        raise CompileError(r.rep.sorted())
    return Resolved(model, tuple(d for d in r.rep.sorted() if not d.is_error),
                    frozenset(r.used), dict(r.open_errors), dict(r.open_reads),
                    PropertyScope(r))


def _resolve_composed(module: ast.Module, overrides: Mapping[str, str] | None,
                      open_params: bool) -> Resolved:
    """A mission of several agents: each agent's view and the mission's own module,
    resolved as single machines (afsmc.resolve.compose says how they are made)."""
    rep = Reporter()
    module = templates.expand(module, rep, overrides)
    if rep.has_errors:  # an instance not made: what names it would be errors of its own
        raise CompileError(rep.sorted())
    kw, agents, mission = compose.split(module, rep)
    kind, ties = compose.composition_kind(kw, agents, rep)
    names = compose._Names(agents, rep)
    views: list[ir.Agent] = []
    used: set[str] = set()
    # An agent's errors about no text of its own (no modes at all: E213 on the whole
    # file), reported at the agent's name unless the mission's module reports errors.
    unplaced: list[Diagnostic] = []
    for a in agents:
        view = compose.agent_module(module, a, names, mission)
        r = _Resolver(view, dict(overrides or {}), open_params)
        model = r.run()
        kept = False
        for d in r.rep.sorted():
            mine = compose.in_agent(d, a)
            if mine is not None and not compose.explained(mine, rep):
                rep.extend([mine])
                kept = kept or mine.is_error
        if r.rep.has_errors and not kept:
            unplaced += [dataclasses.replace(d, span=a.name.span, related=(),
                                             message=f"agent {a.name.text}: {d.message}")
                         for d in r.rep.sorted() if d.is_error]
        used |= r.used
        own = tuple(d.name.text for d in a.decls if isinstance(d, ast.VarDecl))
        own_flat = tuple(v.name for v in model.variables if v.display.split(".")[0] in own)
        syncs = tuple(d.name.text for d in a.decls if isinstance(d, ast.ActionDecl) and d.sync)
        views.append(ir.Agent(a.name.text, model, own_flat, syncs,
                              a.clock.text if a.clock else None, a.span, a.name.span))
    shared = compose.writers(mission, agents, rep)
    r = _Resolver(compose.mission_module(module, agents, names, mission),
                  dict(overrides or {}), open_params)
    r.action_names.update(compose.mission_actions(agents))
    model = r.run()
    rep.extend(r.rep.diagnostics)
    used |= r.used
    if ties == "uniform" and model.interval_constants and kw is not None:
        name = model.interval_constants[0].name
        rep.error(codes.E253, f"the interval constant {name}'s floor or ceil would be a "
                  "choice, which 'compose interleaving uniform' (a DTMC) does not have",
                  kw.span, hint=f"give {name} one value, or write 'compose interleaving;' (min "
                  "and max over who moves next and the interval's ends)")
    if not rep.has_errors:
        rep.extend(unplaced)
    if rep.has_errors:
        raise CompileError(rep.sorted())
    warnings = [d for d in rep.sorted() if not d.is_error]
    comp = ir.Composition(kind, ties, tuple(views), shared, kw.span if kw else None)
    model = dataclasses.replace(model, actions=(), hazards=(), composition=comp)
    return Resolved(model, tuple(warnings), frozenset(used), dict(r.open_errors),
                    dict(r.open_reads), PropertyScope(r, names))


class _Resolver(NamesMixin, ConstantsMixin, DeclarationsMixin, ExpressionsMixin, ActionsMixin,
                PropertiesMixin):
    def run(self) -> ir.Model:
        """Resolve the declarations in the order they can refer to each other: constants
        (in file order), modes, variables, formulas, actions and hazards, labels, rewards,
        properties."""
        decls = self.m.decls
        self._declare_names(decls)
        for d in decls:
            if isinstance(d, (ast.ConstDecl, ast.ParamDecl)):
                self._constant(d)
        self._check_overrides()
        self._modes([d for d in decls if isinstance(d, ast.ModeDecl)])
        for d in decls:
            if isinstance(d, ast.VarDecl):
                self._variable(d)
        self._check_action_vs_variable()
        self.formula_decls = {d.name.text: d for d in decls if isinstance(d, ast.FormulaDecl)}
        for d in decls:
            if isinstance(d, ast.FormulaDecl):
                self._formula(d.name.text)
        actions = [self._action(d) for d in decls if isinstance(d, ast.ActionDecl)]
        hazards: list[ir.Hazard] = []
        for d in decls:
            if isinstance(d, ast.HazardDecl):
                if d.kind == "preemptive":
                    actions.append(self._preemptive(d))
                else:
                    hazards.append(self._hazard(d))
        labels = [self._label_decl(d) for d in decls if isinstance(d, ast.LabelDecl)]
        rewards = [self._rewards(d) for d in decls if isinstance(d, ast.RewardsDecl)]
        self.reward_structs = {r.name: r for r in rewards}
        props = [self._property(d) for d in decls if isinstance(d, ast.PropertyDecl)]
        self._check_query_names(props)
        self._check_weight_cycles(actions)
        name = self.m.machine.name.text if self.m.machine else _stem(self.src.path)
        return ir.Model(
            name=name, source=self.src, constants=tuple(self.consts.values()),
            variables=tuple(self.vars.values()),
            modes=tuple(sorted(self.modes.values(), key=lambda m: m.number)),
            actions=tuple(actions), hazards=tuple(hazards),
            formulas=tuple(self.formulas[n] for n in self.formula_decls if n in self.formulas),
            labels=tuple(labels), rewards=tuple(rewards), properties=tuple(props))


def _stem(path: str) -> str:
    """The machine's name when the file declares none: the file's, as an identifier."""
    base = os.path.basename(path)
    return safe_identifier(base.rsplit(".", 1)[0] or "machine")
