"""Expressions of the lowered model -> closures over numpy arrays.

Before compiling, an expression is folded: constants become literals, formulas, labels
and `w(a)` are inlined, and inside one mode's partition of the runs the current mode
is a known number, so mode tests (and most of the priority conditions the lowering put
into the guards) disappear. What is left is evaluated with the same semantics as
`afsmc.model.evaluate` (PRISM's: `/` is real division, doubles compare with 1e-12).
No text is generated or executed: a closure per node.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np

from afsmc.model import expr as E
from afsmc.model.evaluate import Env, EvalError, evaluate, storm_mod
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
    try:
        v = evaluate(e, Env())
    except EvalError as exc:
        raise SimError(str(exc)) from None
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
        if e.op == "!":
            return lambda fr: np.logical_not(f(fr))
        return lambda fr: -f(fr)
    if isinstance(e, E.Binary):
        return _binary(e)
    if isinstance(e, E.Ite):
        c, a, b = compile_expr(e.cond), compile_expr(e.then), compile_expr(e.other)
        return lambda fr: np.where(c(fr), a(fr), b(fr))
    if isinstance(e, E.Call):
        return _call(e)
    raise SimError(f"cannot simulate the expression {type(e).__name__}")


_SIMPLE: dict[str, Callable[[Any, Any], Any]] = {
    "+": np.add, "-": np.subtract, "*": np.multiply, "<": np.less, "<=": np.less_equal,
    ">": np.greater, ">=": np.greater_equal, "&&": np.logical_and, "||": np.logical_or,
}


def _binary(e: E.Binary) -> Fn:
    f, g = compile_expr(e.left), compile_expr(e.right)
    op = e.op
    if op in _SIMPLE:
        h = _SIMPLE[op]
        return lambda fr: h(f(fr), g(fr))
    if op == "=>":
        return lambda fr: np.logical_or(np.logical_not(f(fr)), g(fr))
    if op == "/":
        def div(fr: Frame) -> Any:
            d = g(fr)
            if np.any(np.asarray(d) == 0):
                raise SimError("division by zero")
            return np.true_divide(f(fr), d)
        return div
    if op in ("==", "!="):
        floating = Type.DOUBLE in (e.left.type, e.right.type)
        if floating:  # doubles compare with a tolerance, as evaluate() and Storm do
            if op == "==":
                return lambda fr: np.abs(f(fr) - g(fr)) <= 1e-12
            return lambda fr: np.abs(f(fr) - g(fr)) > 1e-12
        return (lambda fr: np.equal(f(fr), g(fr))) if op == "==" else (
            lambda fr: np.not_equal(f(fr), g(fr)))
    raise SimError(f"unknown operator {op}")


def _call(e: E.Call) -> Fn:
    fs = [compile_expr(a) for a in e.args]
    name = e.func
    if name in ("min", "max"):
        h = np.minimum if name == "min" else np.maximum
        first, rest = fs[0], fs[1:]

        def fold_minmax(fr: Frame) -> Any:
            out = first(fr)
            for r in rest:
                out = h(out, r(fr))
            return out
        return fold_minmax
    if name in ("floor", "ceil"):
        h1 = np.floor if name == "floor" else np.ceil
        f0 = fs[0]
        return lambda fr: np.asarray(h1(f0(fr))).astype(np.int64)
    if name == "pow":
        a, b = fs
        if e.type is Type.INT:
            def ipow(fr: Frame) -> Any:
                k = np.asarray(b(fr))
                if np.any(k < 0):  # a fraction, as Storm and evaluate() compute it
                    return np.power(np.asarray(a(fr), dtype=float), k)
                return np.power(np.asarray(a(fr), dtype=np.int64), k.astype(np.int64))
            return ipow
        return lambda fr: np.power(np.asarray(a(fr), dtype=float), b(fr))
    if name == "mod":
        a, b = fs

        def mod(fr: Frame) -> Any:
            d = b(fr)
            if np.any(np.asarray(d) == 0):
                raise SimError("mod by zero")
            return storm_mod(a(fr), d)
        return mod
    raise SimError(f"unknown function {name}")


def reads(e: E.Expr) -> set[str]:
    """Variables (and "mode") a folded expression reads."""
    out = E.vars_read(e)
    if E.reads_mode(e):
        out.add("mode")
    return out
