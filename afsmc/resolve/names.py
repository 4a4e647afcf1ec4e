"""Names and scopes: declaring every name once (E201), keeping reserved and internal names
out (E202), and looking up the names an expression uses (E203, E223, E224, E227-E231).

Constants, variables, modes and formulas share one namespace (`value_names`); actions and
hazards, labels, reward structures and properties have one each.
"""

from __future__ import annotations

from afsmc.diagnostics import Related, Span, codes
from afsmc.model import expr as E
from afsmc.model.names import LABEL_RESERVED, QUOTED_RESERVED, RESERVED, did_you_mean
from afsmc.resolve.base import Ctx, ResolverBase, a
from afsmc.syntax import ast


class NamesMixin(ResolverBase):
    # ---- declaring -------------------------------------------------------------------
    def _declare_names(self, decls: tuple[ast.Decl, ...]) -> None:
        if self.m.machine is not None:  # PRISM's module
            self._check_reserved(self.m.machine.name, "machine")
        for d in decls:
            if isinstance(d, (ast.ConstDecl, ast.ParamDecl)):
                self._declare_value(d.name, "constant")
            elif isinstance(d, ast.VarDecl):
                self._declare_value(d.name, "variable")
            elif isinstance(d, ast.ModeDecl):
                self._declare_value(d.name, "mode")
            elif isinstance(d, ast.FormulaDecl):
                self._declare_value(d.name, "formula")
            elif isinstance(d, (ast.ActionDecl, ast.HazardDecl)):
                self._declare_in(self.action_names, d.name, "action")
                if isinstance(d, ast.HazardDecl) and d.kind == "probabilistic":
                    self.branch_hazards.add(d.name.text)
            elif isinstance(d, ast.LabelDecl):
                self._declare_in(self.label_names, d.name, "label")
            elif isinstance(d, ast.RewardsDecl):
                self._declare_in(self.reward_names, d.name, "reward structure")
        props: dict[str, Span] = {}
        for d in decls:
            if isinstance(d, ast.PropertyDecl):
                self._declare_in(props, d.name, "property")

    def _declare_value(self, name: ast.Ident, kind: str) -> None:
        if name.text in self.value_names:
            other_kind, other = self.value_names[name.text]
            self.rep.error(codes.E201, f"'{name.text}' is already declared as {a(other_kind)}", name.span,
                           related=[Related("first declared here", other)])
            return
        if kind != "mode":  # modes compile to numbers, never to identifiers
            self._check_reserved(name, kind)
        self.value_names[name.text] = (kind, name.span)

    def _declare_in(self, table: dict[str, Span], name: ast.Ident, kind: str) -> None:
        if name.text in table:
            self.rep.error(codes.E201, f"{kind} '{name.text}' is declared twice", name.span,
                           related=[Related("first declared here", table[name.text])])
            return
        reserved = {"action": RESERVED, "label": LABEL_RESERVED,
                    "reward structure": QUOTED_RESERVED}.get(kind, frozenset())
        self._check_reserved(name, kind, reserved)
        table[name.text] = name.span

    def _check_internal(self, name: ast.Ident, kind: str) -> None:
        # __afsmc...: the queries and names afsmc generates; any other __ name: Storm's
        # parsers refuse it ("illegal identifier").
        if name.text.startswith("__"):
            self.rep.error(codes.E202, f"'{name.text}' cannot name {a(kind)}: names that start "
                           "with __ are reserved for Storm and afsmc", name.span,
                           hint=f"choose another name, e.g. '{name.text.lstrip('_')}'"
                           if name.text.strip("_") else "choose another name")

    def _check_reserved(self, name: ast.Ident, kind: str, reserved: frozenset[str] = RESERVED) -> None:
        self._check_internal(name, kind)
        if name.text in reserved:
            self.rep.error(
                codes.E202, f"'{name.text}' cannot name {a(kind)}: it is reserved in PRISM or Storm",
                name.span, hint=f"choose another name, e.g. '{name.text}_{kind.split()[0]}'")

    def _check_action_vs_variable(self) -> None:
        """An action (or hazard) named like a variable: PRISM takes it, but Storm's symbolic
        engines (hybrid, dd; `auto` on a large model) cannot build it ("a meta variable
        already exists"), so the sparse engine would be the only one left."""
        for name, span in self.action_names.items():
            var = self.vars.get(name)
            if var is not None:
                self.rep.error(codes.E201, f"'{name}' names both an action and the variable "
                               f"{var.display}: Storm's symbolic engines need them distinct",
                               span, hint=f"rename the action, e.g. '{name}_act'",
                               related=[Related(f"{var.display} is declared here", var.span)])

    # ---- looking up ------------------------------------------------------------------
    def _undefined(self, name: ast.Ident, ctx: Ctx) -> None:
        candidates = list(self.value_names)
        self.rep.error(codes.E203, f"'{name.text}' is not declared", name.span,
                       hint=did_you_mean(name.text, candidates))

    def _name(self, ident: ast.Ident, ctx: Ctx, s: Span) -> E.Expr:
        n = ident.text
        kind = self.value_names.get(n, (None, None))[0]
        if kind is None:
            if n in self.action_names:
                self.rep.error(codes.E227, f"'{n}' is an action, not a value", s,
                               hint=f"its weight is written w({n})" if ctx.weights else None)
            else:
                self._undefined(ident, ctx)
            return self._placeholder(s)
        if kind in ("constant", "formula"):
            self.used.add(n)
        if kind == "constant":
            return self._constant_ref(n, ctx, s)
        if kind == "variable":
            if n in self.tuples:
                self.rep.error(codes.E230, f"'{n}' is a tuple; name a field, e.g. {n}.{self.tuples[n][0]}",
                               s)
                return self._placeholder(s)
            return self._var(n, ctx, s, n)
        if kind == "mode":
            mode = self.modes.get(n)
            return E.ModeVal(n, mode.number if mode else 0, s)
        # formula
        if ctx.constant_only:
            self.rep.error(codes.E231, f"{ctx.what} cannot use formula '{n}'", s)
            return self._placeholder(s)
        f = self._formula(n) if n in self.formula_decls else None
        if f is None:
            return self._placeholder(s)
        return E.FormulaRef(n, f.value.type, s)

    def _constant_ref(self, n: str, ctx: Ctx, s: Span) -> E.Expr:
        c = self.consts.get(n)
        if c is None:
            self.rep.error(codes.E228, f"constant '{n}' is used before its declaration", s)
            return self._placeholder(s)
        if c.is_interval and not ctx.intervals:
            self.rep.error(
                codes.E229, f"interval constant '{n}' can only be used in updates, not in {ctx.what}",
                s, hint="the floor/ceil choice is made per action; use a plain constant here")
        if c.is_prob_interval and not ctx.probabilities:
            self.rep.error(
                codes.E250, f"interval probability '{n}' can only be used in probabilities, "
                f"not in {ctx.what}", s,
                hint="its value is a parameter of the model; write it in an outcome's or a "
                "hazard's probability (P, 1 - P)")
        return E.ConstRef(n, c.type, s)

    def _field_ref(self, e: ast.FieldRef, ctx: Ctx) -> E.Expr:
        """`pos.x`: the variable `pos_x` of the tuple `pos`."""
        s = e.span
        if not ctx.state and self.value_names.get(e.base.text, (None,))[0] == "variable":
            # a constant: the tuples are not resolved yet, and no field could be used
            return self._stateless(ctx, s, f"{e.base.text}.{e.field.text}")
        if e.base.text not in self.tuples:
            if e.base.text in self.value_names:
                self.rep.error(codes.E223, f"'{e.base.text}' has no fields", e.span)
            else:
                self._undefined(e.base, ctx)
            return self._placeholder(s)
        if e.field.text not in self.tuples[e.base.text]:
            if (e.base.text, e.field.text) in self.dropped_fields:
                return self._placeholder(s)
            self.rep.error(codes.E223, f"'{e.base.text}' has no field '{e.field.text}'", e.field.span,
                           hint=did_you_mean(e.field.text, self.tuples[e.base.text]))
            return self._placeholder(s)
        return self._var(f"{e.base.text}_{e.field.text}", ctx, s,
                         f"{e.base.text}.{e.field.text}")

    def _stateless(self, ctx: Ctx, s: Span, display: str) -> E.Expr:
        """E224: a variable where only constants may stand."""
        self.rep.error(codes.E224, f"{ctx.what} cannot depend on variable '{display}'", s)
        return self._placeholder(s)

    def _var(self, flat: str, ctx: Ctx, s: Span, display: str) -> E.Expr:
        # Constants are resolved before the variables, and a variable with errors is left
        # out of `self.vars`: E224 is decided by the context alone.
        if not ctx.state:
            return self._stateless(ctx, s, display)
        v = self.vars.get(flat)
        if v is None:  # a variable with errors
            return self._placeholder(s)
        return E.VarRef(flat, v.type, s)
