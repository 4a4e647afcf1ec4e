"""Expressions of the lowered model -> closures over numpy arrays.

Before compiling, an expression is folded: constants become literals, formulas, labels
and `w(a)` are inlined, and inside one mode's partition of the runs the current mode
is a known number, so mode tests (and most of the priority conditions the lowering put
into the guards) disappear. What is left becomes a closure per node (no text is generated or executed),
each calling the vector form of its operator from :mod:`afsmc.model.kernel`, where every
operator's semantics is stated (a division by zero is NaN in the runs concerned, as in the
checks' enumeration).
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np

from afsmc.model import expr as E
from afsmc.model import kernel
from afsmc.model.evaluate import Env, EvalError, evaluate
from afsmc.model.expr import Type

Frame = Mapping[str, Any]  # flat variable name (and "mode") -> array of the runs
Fn = Callable[[Frame], Any]


class SimError(Exception):
    """The model cannot be simulated as written (e.g. division by zero in a run)."""


@dataclass(frozen=True)
class Scope:
    consts: Mapping[str, Any]
    formulas: Mapping[str, E.Expr]
    labels: Mapping[str, E.Expr]
    weights: Mapping[str, E.Expr]  # action -> effective weight w(s, a)
    mode: int | None = None  # known inside one mode's partition
    # constants with a value per run (interval probabilities drawn once per run): read
    # from the runs' frame, as a variable is
    per_run: frozenset[str] = frozenset()


def fold(e: E.Expr, sc: Scope) -> E.Expr:
    if isinstance(e, E.ConstRef):
        if e.name in sc.per_run:
            return E.VarRef(e.name, e.type, e.span)
        return E.lit(sc.consts[e.name])
    if isinstance(e, E.ModeVal):
        return E.Lit(e.number, Type.INT)
    if isinstance(e, E.CurrentMode):
        return E.Lit(sc.mode, Type.INT) if sc.mode is not None else e
    if isinstance(e, E.FormulaRef):
        return fold(sc.formulas[e.name], sc)
    if isinstance(e, E.LabelRef):
        return fold(sc.labels[e.name], sc)
    if isinstance(e, E.WeightRef):
        return fold(sc.weights[e.action], sc)
    if isinstance(e, E.Unary):
        x = fold(e.operand, sc)
        return _lit(E.Unary(e.op, x, e.type)) if isinstance(x, E.Lit) else E.Unary(e.op, x, e.type)
    if isinstance(e, E.Binary):
        a = fold(e.left, sc)
        if e.op in ("&&", "||", "=>") and isinstance(a, E.Lit):
            if e.op == "&&":
                return fold(e.right, sc) if a.value else E.FALSE
            if e.op == "||":
                return E.TRUE if a.value else fold(e.right, sc)
            return fold(e.right, sc) if a.value else E.TRUE
        b = fold(e.right, sc)
        if e.op in ("&&", "||") and isinstance(b, E.Lit):
            if e.op == "&&":
                return a if b.value else E.FALSE
            return E.TRUE if b.value else a
        out = E.Binary(e.op, a, b, e.type)
        return _lit(out) if isinstance(a, E.Lit) and isinstance(b, E.Lit) else out
    if isinstance(e, E.Ite):
        c = fold(e.cond, sc)
        if isinstance(c, E.Lit):
            return fold(e.then if c.value else e.other, sc)
        return E.Ite(c, fold(e.then, sc), fold(e.other, sc), e.type)
    if isinstance(e, E.Call):
        args = tuple(fold(a, sc) for a in e.args)
        out2 = E.Call(e.func, args, e.type)
        return _lit(out2) if all(isinstance(a, E.Lit) for a in args) else out2
    return e


def _lit(e: E.Expr) -> E.Expr:
    """`e`'s value as a literal; `e` itself where it is undefined (`1 / 0` under a `?:` that
    never takes it, which the resolver accepts): its closure computes NaN, as every
    undefined value is in the runs (afsmc.model.kernel)."""
    try:
        v = evaluate(e, Env())
    except EvalError:
        return e
    if isinstance(v, np.generic):
        v = v.item()
    if e.type is Type.BOOL:
        return E.lit(bool(v))
    if e.type is Type.INT and float(v).is_integer():
        return E.Lit(int(v), Type.INT)
    return E.Lit(float(v), Type.DOUBLE)


def static(e: E.Expr) -> Any:
    """The value of a folded literal, else None."""
    return e.value if isinstance(e, E.Lit) else None


def compile_expr(e: E.Expr) -> Fn:
    """A closure evaluating a folded expression over a frame of run arrays."""
    if isinstance(e, E.Lit):
        v = e.value
        return lambda fr: v
    if isinstance(e, E.VarRef):
        name = e.name
        return lambda fr: fr[name]
    if isinstance(e, E.CurrentMode):
        return lambda fr: fr["mode"]
    if isinstance(e, E.Unary):
        f = compile_expr(e.operand)
        h = known_op(lambda: kernel.unary(e.op)).vector
        return lambda fr: h(f(fr))
    if isinstance(e, E.Binary):
        return _binary(e)
    if isinstance(e, E.Ite):
        c, a, b = compile_expr(e.cond), compile_expr(e.then), compile_expr(e.other)
        ite = kernel.ite_vector
        return lambda fr: ite(c(fr), a(fr), b(fr))
    if isinstance(e, E.Call):
        return _call(e)
    raise SimError(f"cannot simulate the expression {type(e).__name__}")


def _binary(e: E.Binary) -> Fn:
    f, g = compile_expr(e.left), compile_expr(e.right)
    h = known_op(lambda: kernel.binary(e.op)).vector
    return lambda fr: h(f(fr), g(fr))


def _call(e: E.Call) -> Fn:
    fs = [compile_expr(a) for a in e.args]
    h = known_op(lambda: kernel.call(e.func, e.type)).vector
    if len(fs) == 1:
        f0 = fs[0]
        return lambda fr: h(f0(fr))
    if len(fs) == 2:
        a, b = fs
        return lambda fr: h(a(fr), b(fr))
    return lambda fr: h(*(f(fr) for f in fs))


def known_op(find: Callable[[], kernel.Op]) -> kernel.Op:
    """The kernel's operator, or SimError for one it does not know."""
    try:
        return find()
    except kernel.EvalError as exc:
        raise SimError(f"cannot simulate: {exc}") from None


def reads(e: E.Expr) -> set[str]:
    """Variables (and "mode") a folded expression reads."""
    out = E.vars_read(e)
    if E.reads_mode(e):
        out.add("mode")
    return out
