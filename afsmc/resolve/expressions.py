"""Expressions and types: each AST expression built into a typed IR expression, its type
checked where it stands (E222, E224-E226, E232-E234), and a part that needs no state
folded to check that PRISM and Storm can hold its value (E245).

A sub-expression that was reported becomes a placeholder of the type expected there, so
that checking goes on and no error follows from the first one.
"""

from __future__ import annotations

from typing import Any

from afsmc.diagnostics import Reporter, codes
from afsmc.model import expr as E
from afsmc.model.evaluate import EvalError, RangeError, scalar
from afsmc.model.expr import Type
from afsmc.model.limits import NUMBERS_HINT, unrepresentable
from afsmc.model.names import did_you_mean
from afsmc.resolve.base import Ctx, ResolverBase, a
from afsmc.syntax import ast
from afsmc.syntax.errors.messages import NESTED_TEMPORAL, NOT_OPERATOR, OPERATORS
from afsmc.syntax.limits import clip

_ARITY = {"floor": 1, "ceil": 1, "pow": 2, "mod": 2}  # min and max take 2 or more


def _shown(v: int) -> str:
    """A huge integer, short: 1.00e300."""
    digits = str(abs(v))
    if len(digits) <= 24:
        return str(v)
    return f"{'-' if v < 0 else ''}{digits[0]}.{digits[1:3]}e{len(digits) - 1}"


class ExpressionsMixin(ResolverBase):
    def _bool(self, e: ast.Expr, ctx: Ctx) -> E.Expr:
        x = self._expr(e, ctx)
        if id(x) in self.placeholders:
            return E.TRUE
        if x.type is not Type.BOOL:
            self.rep.error(codes.E222, f"{ctx.what} must be true or false, not {a(x.type.value)}", e.span,
                           hint="compare it, e.g. 'x > 0'")
            return E.TRUE
        return x

    def _num(self, e: ast.Expr, ctx: Ctx) -> E.Expr:
        x = self._expr(e, ctx)
        if not x.type.numeric and id(x) not in self.placeholders:
            self.rep.error(codes.E222, f"{ctx.what} must be a number, not {a(x.type.value)}", e.span)
            return E.Lit(0, Type.INT, e.span)
        return x

    def _expr(self, e: ast.Expr, ctx: Ctx) -> E.Expr:
        x = self._build(e, ctx)
        if isinstance(x, (E.Unary, E.Binary, E.Call)) and x.type.numeric and self._state_free(x):
            # Storm folds such parts itself, and fails on an infinite or too large result.
            why: str | None
            try:
                v = scalar(x, self._const_env(), nodes=self._values)
                why = unrepresentable(v)
                if why is not None:
                    why = f"its value {_shown(v) + ' ' if isinstance(v, int) else ''}{why}"
            except RangeError as exc:
                why = str(exc)
            except (EvalError, ArithmeticError):
                return x  # e.g. 1/0 under a `?:` that never takes it
            if why is not None:
                self.rep.error(codes.E245, f"this expression cannot be compiled: {why}", e.span,
                               hint=NUMBERS_HINT)
                return E.Lit(0 if x.type is Type.INT else 0.0, x.type, e.span)
        return x

    def _state_free(self, x: E.Expr) -> bool:
        """E.state_free, remembered for the nodes built so far: each node of a long chain
        asks it, and walking the chain below every node would take quadratic time."""
        known = self._free.get(id(x))
        if known is not None and known[0] is x:
            return known[1]
        free = isinstance(x, (E.Lit, E.ConstRef, E.Unary, E.Binary, E.Ite, E.Call)) and all(
            self._state_free(c) if id(c) in self._free else E.state_free(c)
            for c in E.children(x))
        self._free[id(x)] = (x, free)
        return free

    def _build(self, e: ast.Expr, ctx: Ctx) -> E.Expr:
        s = e.span
        if isinstance(e, ast.Num):
            return self._number(e)
        if isinstance(e, ast.BoolLit):
            return E.Lit(e.value, Type.BOOL, s)
        if isinstance(e, ast.Name):
            return self._name(e.name, ctx, s)
        if isinstance(e, ast.FieldRef):
            return self._field_ref(e, ctx)
        if isinstance(e, ast.ModeRef):
            if not ctx.state:
                self.rep.error(codes.E224, f"{ctx.what} cannot depend on the mode", s)
                return E.Lit(0, Type.MODE, s)
            return E.CurrentMode(s)
        if isinstance(e, ast.ModeIn):
            if e.agent is not None:  # a composed mission rewrote every agent's
                self.rep.error(codes.E253, f"'{e.agent.text}.mode' is the mode of an agent, "
                               "and this machine has no agents", e.span,
                               hint="its own mode is 'mode in {...}'")
                return E.FALSE
            if not ctx.state:
                self.rep.error(codes.E224, f"{ctx.what} cannot depend on the mode", s)
                return E.FALSE
            return E.mode_in(set(self._mode_set_any(e.modes)),
                             {m.number: m.name for m in self.modes.values()})
        if isinstance(e, ast.LabelRef):
            return self._label_ref(e, ctx)
        if isinstance(e, ast.Call):
            return self._call(e, ctx)
        if isinstance(e, ast.Unary):
            if e.op == "!":
                return E.Unary("!", self._bool(e.operand, ctx), Type.BOOL, s)
            x = self._num(e.operand, ctx)
            return E.Unary("-", x, x.type, s)
        if isinstance(e, ast.Ite):
            c = self._bool(e.cond, ctx)
            then = self._expr(e.then, ctx)
            other = self._expr(e.other, ctx)
            return E.Ite(c, then, other, self._unify(then, other, e, "the two branches of '?:'"), s)
        assert isinstance(e, ast.Binary)
        return self._binary(e, ctx)

    def _number(self, e: ast.Num) -> E.Expr:
        t = Type.INT if isinstance(e.value, int) else Type.DOUBLE
        why = unrepresentable(e.value)
        if why is not None:
            self.rep.error(codes.E245, f"{clip(e.text)} " + (why if t is Type.INT else "is too large for a "
                                                   "double: it would be infinite"),
                           e.span, hint=NUMBERS_HINT)
            return E.Lit(0 if t is Type.INT else 0.0, t, e.span)
        return E.Lit(e.value, t, e.span)

    def _label_ref(self, e: ast.LabelRef, ctx: Ctx) -> E.Expr:
        s = e.span
        if not ctx.labels:
            self.rep.error(codes.E225, f"labels like \"{e.name}\" can only be used in properties", s,
                           hint="use a formula to share an expression")
            return E.FALSE
        if e.name not in self.label_names:
            self.rep.error(codes.E203, f"label \"{e.name}\" is not declared", s,
                           hint=did_you_mean(e.name, self.label_names))
            return E.FALSE
        return E.LabelRef(e.name, s)

    def _binary(self, e: ast.Binary, ctx: Ctx) -> E.Expr:
        s = e.span
        op = e.op
        if op in ("&&", "||", "=>"):
            return E.Binary(op, self._bool(e.left, ctx), self._bool(e.right, ctx), Type.BOOL, s)
        if op in ("+", "-", "*", "/"):
            x = self._num(e.left, ctx)
            y = self._num(e.right, ctx)
            t = Type.DOUBLE if op == "/" else self._unify(x, y, e, f"the operands of '{op}'")
            return E.Binary(op, x, y, t, s)
        x = self._expr(e.left, ctx)
        y = self._expr(e.right, ctx)
        if id(x) in self.placeholders or id(y) in self.placeholders:
            # an operand that has had its error (undeclared, no such field): no type error
            # that follows from its stand-in's type (`mode == Alpa` is not mode against int)
            return E.Binary(op, x, y, Type.BOOL, s)
        if op in ("==", "!="):
            if x.type.numeric != y.type.numeric or (not x.type.numeric and x.type is not y.type):
                self.rep.error(codes.E226, f"cannot compare {a(x.type.value)} with {a(y.type.value)}", s,
                               hint="modes compare with modes: 'mode == Search'"
                               if Type.MODE in (x.type, y.type) else None)
            return E.Binary(op, x, y, Type.BOOL, s)
        if not (x.type.numeric and y.type.numeric):
            bad = x if not x.type.numeric else y
            self.rep.error(codes.E226, f"'{op}' compares numbers, not {a(bad.type.value)}", bad.span or s)
        return E.Binary(op, x, y, Type.BOOL, s)

    def _unify(self, x: E.Expr, y: E.Expr, e: Any, what: str) -> Type:
        """The type of an expression whose value is `x`'s or `y`'s: a double if one is."""
        if x.type is y.type:
            return x.type
        if id(x) in self.placeholders or id(y) in self.placeholders:
            return y.type if id(x) in self.placeholders else x.type
        if x.type.numeric and y.type.numeric:
            return Type.DOUBLE
        self.rep.error(codes.E226, f"{what} have different types ({x.type.value}, {y.type.value})",
                       e.span)
        return x.type

    def _mode_set_any(self, ms: ast.ModeSet) -> tuple[int, ...]:
        """`mode in {...}`: unlike an action's mode set, final modes are fine here
        (`mode in {Done, Crashed}`)."""
        return modes_in(ms, {m.name: m.number for m in self.modes.values()}, self.rep)

    def _call(self, e: ast.Call, ctx: Ctx) -> E.Expr:
        f = e.func.text
        s = e.span
        if f == "w":
            return self._weight_ref(e, ctx)
        if f in ("F", "G", "X") and ctx.labels:
            # `P=? [ F F (x == 1) ]`: the inner operator reads as a call
            self.rep.error(codes.E115, NESTED_TEMPORAL, e.func.span,
                           hint=f"the {f} here stands inside another temporal operator's "
                                "formula; write one operator per property")
            return self._placeholder(s)
        if f == "not":  # `not (x == 1)` reads as a call
            self.rep.error(codes.E123, NOT_OPERATOR, e.func.span, hint=OPERATORS)
            return self._placeholder(s)
        if f not in E.FUNCTIONS:
            # count/all/any are over a family (afsmc.resolve.templates): left here, none is
            over = (f"{f}(...) ranges over a family's members, and no family is declared "
                    "('agent r[1..N] : Robot;')" if f in ("count", "all", "any") else None)
            self.rep.error(codes.E233, f"unknown function '{f}'", e.func.span,
                           hint=over or did_you_mean(f, [*E.FUNCTIONS, "w"]) or
                           "functions: " + ", ".join(sorted(E.FUNCTIONS)) + ", w(Action)")
            return self._placeholder(s)
        args = tuple(self._num(x, ctx) for x in e.args)
        arity = _ARITY.get(f)
        if (arity is not None and len(args) != arity) or (arity is None and len(args) < 2):
            want = f"{arity}" if arity else "at least 2"
            self.rep.error(codes.E234, f"{f} takes {want} argument(s), not {len(args)}", s)
            return self._placeholder(s)
        if f in ("floor", "ceil"):
            t = Type.INT
        elif f == "mod":
            for arg, written in zip(args, e.args, strict=True):
                if arg.type is not Type.INT:
                    self.rep.error(codes.E234, "mod takes integers", written.span)
            t = Type.INT
        else:
            t = Type.INT if all(arg.type is Type.INT for arg in args) else Type.DOUBLE
        return E.Call(f, args, t, s)

    def _weight_ref(self, e: ast.Call, ctx: Ctx) -> E.Expr:
        """`w(Action)`: another action's weight, only in a weight."""
        s = e.span
        if len(e.args) != 1 or not isinstance(e.args[0], ast.Name):
            self.rep.error(codes.E232, "w(...) takes one action name", s)
            return self._placeholder(s)
        target = e.args[0].name
        if not ctx.weights:
            self.rep.error(codes.E232, f"w({target.text}) can only be used in a weight", s)
            return self._placeholder(s)
        if target.text not in self.action_names:
            self.rep.error(codes.E203, f"'{target.text}' is not an action", target.span,
                           hint=did_you_mean(target.text, self.action_names))
            return self._placeholder(s)
        if target.text in self.branch_hazards:
            self.rep.error(codes.E248, f"'{target.text}' is a probabilistic hazard: it has no "
                           "weight, it is a branch of every action of its modes", target.span,
                           hint="w(...) names an action or a hazard with a condition (when)")
            return self._placeholder(s)
        return E.WeightRef(target.text, s)


def modes_in(ms: ast.ModeSet, by_name: dict[str, int], rep: Reporter,
             whose: str = "") -> tuple[int, ...]:
    """The numbers of the modes (`by_name`) a `mode in {...}` set names; E215 for a name
    or number that is no mode (`whose`: " of agent b", for another agent's modes)."""
    out: set[int] = set()
    for item in ms.items:
        if isinstance(item, ast.ModeName):
            if item.name.text in by_name:
                out.add(by_name[item.name.text])
            else:
                rep.error(codes.E215, f"'{item.name.text}' is not a mode{whose}", item.span,
                          hint=did_you_mean(item.name.text, by_name))
        elif isinstance(item, ast.ModeNumber):
            # as in an action's mode set: a number no mode has is a typo, not `false`
            if item.number in by_name.values():
                out.add(item.number)
            else:
                rep.error(codes.E215, f"no mode{whose} has number {item.number}", item.span)
        else:
            hit = {n for n in by_name.values() if item.lo <= n <= item.hi}
            if not hit:
                rep.error(codes.E215, f"no mode{whose} has a number in {item.lo}..{item.hi}",
                          item.span)
            out |= hit
    numbers = set(by_name.values())
    return tuple(sorted((numbers - out) if ms.every else (out & numbers)))
