"""Actions and hazards: their mode sets, guards and weights, outcomes and updates
(E235-E239), and weights that refer to each other in a cycle (E240).

A preemptive hazard (`hazard H in ... when C`) becomes an action of kind "preemptive"; a
probabilistic one (`hazard H in ... with p`) an `ir.Hazard`, a branch of every action of
its modes.
"""

from __future__ import annotations

from afsmc.diagnostics import Related, Reporter, Span, codes
from afsmc.model import expr as E
from afsmc.model import ir
from afsmc.model.expr import Type
from afsmc.model.names import did_you_mean
from afsmc.resolve.base import Ctx, ResolverBase, a
from afsmc.syntax import ast

_UPDATE = Ctx("an update", intervals=True)


def _one() -> E.Expr:
    return E.Lit(1, Type.INT, None)


class _Assignments:
    """The updates of one outcome: each variable is assigned at most once (E236)."""

    def __init__(self, rep: Reporter):
        self.rep = rep
        self.out: list[ir.Update] = []
        self.seen: dict[str, Span] = {}

    def add(self, var: str, value: E.Expr, span: Span, display: str) -> None:
        if var in self.seen:
            self.rep.error(codes.E236, f"'{display}' is assigned twice in one outcome", span,
                           related=[Related("first assigned here", self.seen[var])])
            return
        self.seen[var] = span
        self.out.append(ir.Update(var, value, span))


class ActionsMixin(ResolverBase):
    def _action(self, d: ast.ActionDecl) -> ir.Action:
        modes = self._mode_set(d.modes, f"action {d.name.text}")
        guard = self._bool(d.guard, Ctx("a guard")) if d.guard else E.TRUE
        weight = (self._num(d.weight, Ctx("a weight", weights=True)) if d.weight else _one())
        outcomes = self._outcomes(d.body, f"action {d.name.text}")
        return ir.Action(d.name.text, modes, guard, weight, outcomes, d.span, d.name.span,
                         d.weight.span if d.weight else None, d.guard.span if d.guard else None)

    def _preemptive(self, d: ast.HazardDecl) -> ir.Action:
        modes = self._mode_set(d.modes, f"hazard {d.name.text}")
        cond = self._bool(d.trigger, Ctx("a hazard's condition"))
        weight = (self._num(d.weight, Ctx("a weight", weights=True)) if d.weight else _one())
        outcomes = self._outcomes(d.body, f"hazard {d.name.text}")
        return ir.Action(d.name.text, modes, cond, weight, outcomes, d.span, d.name.span,
                         d.weight.span if d.weight else None, d.trigger.span, kind="preemptive")

    def _hazard(self, d: ast.HazardDecl) -> ir.Hazard:
        modes = self._mode_set(d.modes, f"hazard {d.name.text}")
        prob = self._num(d.trigger, Ctx("a hazard's probability", probabilities=True))
        if d.weight is not None:
            self.rep.error(codes.E235, "a probabilistic hazard has no weight: it can happen "
                           "during any action", d.weight.span)
        outcomes = self._outcomes(d.body, f"hazard {d.name.text}")
        return ir.Hazard(d.name.text, modes, prob, outcomes, d.span, d.name.span)

    def _outcomes(self, body: ast.Body, owner: str) -> tuple[ir.Outcome, ...]:
        out = []
        for o in body.outcomes:
            prob = _one() if o.prob is None else self._num(o.prob, Ctx("a probability", probabilities=True))
            out.append(ir.Outcome(prob, self._updates(o.updates), o.span))
        if not out:  # `{}`: stay where you are
            out.append(ir.Outcome(_one(), (), body.span))
        return tuple(out)

    def _updates(self, updates: tuple[ast.Update, ...]) -> tuple[ir.Update, ...]:
        assigned = _Assignments(self.rep)
        for u in updates:
            if isinstance(u, ast.Goto):
                mode = self.modes.get(u.mode.text)
                if mode is None:
                    self.rep.error(codes.E215, f"'{u.mode.text}' is not a mode", u.mode.span,
                                   hint=did_you_mean(u.mode.text, self.modes))
                    continue
                assigned.add("mode", E.ModeVal(mode.name, mode.number, u.mode.span), u.span, "mode")
            elif u.target.field is None and u.target.name.text in self.tuples:
                self._tuple_update(u, assigned)
            else:
                self._var_update(u, assigned)
        return tuple(assigned.out)

    def _tuple_update(self, u: ast.Assign, assigned: _Assignments) -> None:
        """`pos := (1, 2)` or `pos := other`: an update of each field."""
        t = u.target
        fields = self.tuples[t.name.text]
        if any(base == t.name.text for base, _ in self.dropped_fields):
            return  # its shape is unknown after an E201 on one of its fields
        if u.op != ":=":
            self.rep.error(codes.E237, f"'{u.op}' needs a number; '{t.name.text}' is a tuple", u.span)
            return
        values = self._tuple_value(u.value, fields)
        if values is None:
            self.rep.error(codes.E237, f"assign '{t.name.text}' a tuple of {len(fields)} values "
                           f"or another tuple with fields {', '.join(fields)}", u.value.span)
            return
        for fname, v in zip(fields, values, strict=True):
            self._assign(assigned, f"{t.name.text}_{fname}", f"{t.name.text}.{fname}", v,
                         u.span, u.value.span)

    def _var_update(self, u: ast.Assign, assigned: _Assignments) -> None:
        """`x := e`, `x += e`, `pos.x := e`."""
        t = u.target
        flat = t.name.text if t.field is None else f"{t.name.text}_{t.field.text}"
        if flat not in self.vars:
            self._not_assignable(t)
            return
        var = self.vars[flat]
        if isinstance(u.value, ast.TupleLit):
            self.rep.error(codes.E237, f"'{var.display}' is not a tuple", u.value.span)
            return
        value = self._expr(u.value, _UPDATE)
        if u.op != ":=":
            if var.type is not Type.INT:
                self.rep.error(codes.E237, f"'{u.op}' needs an integer; '{var.display}' is a bool",
                               u.span)
                return
            value = E.Binary(u.op[0], E.VarRef(flat, Type.INT, t.span), value,
                             value.type if value.type.numeric else Type.INT, u.span)
        self._assign(assigned, flat, var.display, value, u.span, u.value.span)

    def _not_assignable(self, t: ast.LValue) -> None:
        """Why the target of an update is no variable (or nothing, after its own error)."""
        kind = self.value_names.get(t.name.text, (None, None))[0]
        if kind is None or (t.field is not None and t.name.text not in self.tuples):
            self._undefined(t.name, _UPDATE)
        elif t.field is not None and (t.name.text, t.field.text) in self.dropped_fields:
            pass
        elif t.field is not None:
            self.rep.error(codes.E223, f"'{t.name.text}' has no field '{t.field.text}'",
                           t.field.span)
        elif kind != "variable":
            self.rep.error(codes.E238, f"'{t.text}' is {a(kind)}; only variables can be assigned",
                           t.span)

    def _assign(self, assigned: _Assignments, flat: str, display: str, value: E.Expr,
                span: Span, vspan: Span) -> None:
        var = self.vars[flat]
        if var.type is Type.BOOL and value.type is not Type.BOOL:
            self.rep.error(codes.E239, f"'{display}' is a bool; cannot assign {a(value.type.value)}", vspan)
            return
        if var.type is Type.INT and value.type is Type.DOUBLE:
            self.rep.error(codes.E239, f"'{display}' is an int; cannot assign a double", vspan,
                           hint="round it with floor(...) or ceil(...)")
            return
        if var.type is Type.INT and not value.type.numeric:
            self.rep.error(codes.E239, f"'{display}' is an int; cannot assign {a(value.type.value)}", vspan)
            return
        assigned.add(flat, value, span, display)

    def _tuple_value(self, value: ast.Expr | ast.TupleLit,
                     fields: tuple[str, ...]) -> list[E.Expr] | None:
        if isinstance(value, ast.TupleLit):
            if len(value.items) != len(fields):
                return None
            return [self._expr(v, _UPDATE) for v in value.items]
        if isinstance(value, ast.Name) and self.tuples.get(value.name.text) == fields:
            src = value.name.text
            return [E.VarRef(f"{src}_{f}", self.vars[f"{src}_{f}"].type, value.span)
                    for f in fields if f"{src}_{f}" in self.vars]
        if len(fields) == 1 and not (isinstance(value, ast.Name) and value.name.text in
                                     self.tuples):
            return [self._expr(value, _UPDATE)]  # one field: `p := 2`, `p := (2)`
        return None

    def _check_weight_cycles(self, actions: list[ir.Action]) -> None:
        deps = {x.name: {n.action for n in E.walk(x.weight) if isinstance(n, E.WeightRef)}
                for x in actions}
        spans = {x.name: x.weight_span or x.name_span for x in actions}
        state: dict[str, int] = {}  # 1: being visited, 2: done

        def visit(n: str, path: list[str]) -> None:
            state[n] = 1
            for m in sorted(deps.get(n, ())):
                if state.get(m) == 1:
                    cycle = [*path[path.index(m):], m] if m in path else [n, m]
                    self.rep.error(codes.E240, "weights refer to each other in a cycle: "
                                   + " -> ".join(f"w({x})" for x in cycle), spans[n])
                elif m not in state:
                    visit(m, [*path, m])
            state[n] = 2

        for x in actions:
            if x.name not in state:
                visit(x.name, [x.name])
