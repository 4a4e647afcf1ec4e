"""Folded expressions of the lowered model -> closures over a frame of states, each
distinct subexpression evaluated once per frame (for afsmc.verify.explore).

The explorer evaluates every command of a mode over the same states: the floor/ceil
variants of an action share their guard and probabilities, and the formulas the lowering
inlined (`east`, `row_end`, `next_x` of the UAV) recur in many guards and updates. A
subexpression is interned by its structure, and its value kept in the frame's memo
(the key MEMO), so each is computed once per frame. The semantics are those of
:mod:`afsmc.sim.compile` and :mod:`afsmc.model.evaluate` (PRISM's): `/` is real division,
doubles compare with a tolerance of 1e-12, `mod` is Storm's.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np

from afsmc.model import expr as E
from afsmc.model.evaluate import storm_mod
from afsmc.model.expr import Type
from afsmc.sim.compile import SimError

Frame = dict[str, Any]  # variable name (and "mode") -> array; MEMO -> the memo
Fn = Callable[[Frame], Any]
MEMO = "#memo"

_SIMPLE: dict[str, Callable[[Any, Any], Any]] = {
    "+": np.add, "-": np.subtract, "*": np.multiply, "<": np.less, "<=": np.less_equal,
    ">": np.greater, ">=": np.greater_equal, "&&": np.logical_and, "||": np.logical_or,
}


def frame(values: dict[str, Any]) -> Frame:
    """A frame of these values, with an empty memo."""
    return values | {MEMO: {}}


class Compiler:
    """Compiles folded expressions, sharing one numbering of subexpressions."""

    def __init__(self) -> None:
        self.ids: dict[E.Expr, int] = {}

    def __call__(self, e: E.Expr) -> Fn:
        if isinstance(e, E.Lit):
            v = e.value
            return lambda fr: v
        if isinstance(e, E.VarRef):
            name = e.name
            return lambda fr: fr[name]
        if isinstance(e, E.CurrentMode):
            return lambda fr: fr["mode"]
        i = self.ids.setdefault(e, len(self.ids))
        inner = self._op(e)

        def cached(fr: Frame) -> Any:
            memo = fr[MEMO]
            if i in memo:
                return memo[i]
            v = memo[i] = inner(fr)
            return v

        return cached

    def key(self, e: E.Expr) -> int | None:
        """The number of a compiled subexpression (None for a literal or a variable)."""
        return self.ids.get(e)

    def _op(self, e: E.Expr) -> Fn:
        if isinstance(e, E.Unary):
            f = self(e.operand)
            if e.op == "!":
                return lambda fr: np.logical_not(f(fr))
            return lambda fr: np.negative(f(fr))
        if isinstance(e, E.Binary):
            return self._binary(e)
        if isinstance(e, E.Ite):
            c, a, b = self(e.cond), self(e.then), self(e.other)
            return lambda fr: np.where(c(fr), a(fr), b(fr))
        if isinstance(e, E.Call):
            return self._call(e)
        raise SimError(f"cannot evaluate the expression {type(e).__name__}")

    def _binary(self, e: E.Binary) -> Fn:
        f, g = self(e.left), self(e.right)
        op = e.op
        if op in ("==", "!=") and Type.DOUBLE in (e.left.type, e.right.type):
            if op == "==":
                return lambda fr: np.abs(f(fr) - g(fr)) <= 1e-12
            return lambda fr: np.abs(f(fr) - g(fr)) > 1e-12
        if op == "==":
            return lambda fr: np.equal(f(fr), g(fr))
        if op == "!=":
            return lambda fr: np.not_equal(f(fr), g(fr))
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
        raise SimError(f"unknown operator {op}")

    def _call(self, e: E.Call) -> Fn:
        fs = [self(a) for a in e.args]
        name = e.func
        if name in ("min", "max"):
            h = np.minimum if name == "min" else np.maximum

            def minmax(fr: Frame) -> Any:
                out = fs[0](fr)
                for r in fs[1:]:
                    out = h(out, r(fr))
                return out
            return minmax
        if name in ("floor", "ceil"):
            h1 = np.floor if name == "floor" else np.ceil
            return lambda fr: np.asarray(h1(fs[0](fr))).astype(np.int64)
        if name == "pow":
            a, b = fs
            if e.type is Type.INT:
                def ipow(fr: Frame) -> Any:
                    k = np.asarray(b(fr))
                    if np.any(k < 0):
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
