"""Folded expressions of the lowered model -> closures over a frame of states, each
distinct subexpression evaluated once per frame (for afsmc.verify.explorer.explore).

The explorer evaluates every command of a mode over the same states: the floor/ceil
variants of an action share their guard and probabilities, and the formulas the lowering
inlined (`east`, `row_end`, `next_x` of the UAV) recur in many guards and updates. A
subexpression is interned by its structure, and its value kept in the frame's memo
(the key MEMO), so each is computed once per frame. Each node calls
the vector form of its operator from :mod:`afsmc.model.kernel`, where every operator's
semantics is stated, as the simulator's closures (:mod:`afsmc.sim.compile`) and the
checks' evaluation (:mod:`afsmc.model.evaluate`) do.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable
from typing import Any

from afsmc.model import expr as E
from afsmc.model import kernel
from afsmc.sim.compile import SimError, known_op

Frame = dict[str, Any]  # variable name (and "mode") -> array; MEMO -> the memo
Fn = Callable[[Frame], Any]
MEMO = "#memo"


def frame(values: dict[str, Any]) -> Frame:
    """A frame of these values, with an empty memo."""
    return values | {MEMO: {}}


class Compiler:
    """Compiles folded expressions, sharing one numbering of subexpressions.

    A subexpression is numbered by its structure: its class and fields, each compiled
    child standing for its own number (`_key`). Equal keys are equal expressions (the
    dataclasses' equality, by induction over the children), and a key is hashed in
    constant time, where hashing the expression itself walks its whole subtree: a chain
    nested thousands deep would cost the square of its depth."""

    def __init__(self) -> None:
        self.ids: dict[tuple[Any, ...], int] = {}
        # id of each compiled subexpression -> it (kept, so that its id stays its own)
        # and its number
        self.seen: dict[int, tuple[E.Expr, int]] = {}

    def __call__(self, e: E.Expr) -> Fn:
        if isinstance(e, E.Lit):
            v = e.value
            return lambda fr: v
        if isinstance(e, E.VarRef):
            name = e.name
            return lambda fr: fr[name]
        if isinstance(e, E.CurrentMode):
            return lambda fr: fr["mode"]
        inner = self._op(e)  # (its children compiled and numbered first)
        i = self.ids.setdefault(self._key(e), len(self.ids))
        self.seen[id(e)] = (e, i)

        def cached(fr: Frame) -> Any:
            memo = fr[MEMO]
            if i in memo:
                return memo[i]
            v = memo[i] = inner(fr)
            return v

        return cached

    def key(self, e: E.Expr) -> int | None:
        """The number of a compiled subexpression (None for a literal or a variable)."""
        got = self.seen.get(id(e))
        if got is not None and got[0] is e:
            return got[1]
        if isinstance(e, (E.Lit, E.VarRef, E.CurrentMode)):
            return None
        return self.ids.get(self._key(e))

    def _key(self, e: E.Expr) -> tuple[Any, ...]:
        """`e`'s structure, each compiled child as its number (see the class)."""
        return (type(e), *(tuple(self._part(x) for x in v) if isinstance(v, tuple)
                           else self._part(v)
                           for v in (getattr(e, f.name) for f in dataclasses.fields(e))))

    def _part(self, v: Any) -> Any:
        got = self.seen.get(id(v))
        return ("#", got[1]) if got is not None and got[0] is v else v

    def _op(self, e: E.Expr) -> Fn:
        if isinstance(e, E.Unary):
            f = self(e.operand)
            h1 = known_op(lambda: kernel.unary(e.op)).vector
            return lambda fr: h1(f(fr))
        if isinstance(e, E.Binary):
            f, g = self(e.left), self(e.right)
            h2 = known_op(lambda: kernel.binary(e.op)).vector
            return lambda fr: h2(f(fr), g(fr))
        if isinstance(e, E.Ite):
            c, a, b = self(e.cond), self(e.then), self(e.other)
            ite = kernel.ite_vector
            return lambda fr: ite(c(fr), a(fr), b(fr))
        if isinstance(e, E.Call):
            fs = [self(a) for a in e.args]
            h = known_op(lambda: kernel.call(e.func, e.type)).vector
            if len(fs) == 1:
                f0 = fs[0]
                return lambda fr: h(f0(fr))
            return lambda fr: h(*(f(fr) for f in fs))
        raise SimError(f"cannot evaluate the expression {type(e).__name__}")
