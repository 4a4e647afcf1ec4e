"""Resolved, typed expressions of the IR.

Names are resolved: a variable reference names a flat state variable (``pos.x`` becomes
``pos_x``), a mode name becomes its number, a weight reference names an action.
Every node carries its type and the span it came from.
"""

from __future__ import annotations

from collections.abc import Callable, Iterator
from dataclasses import dataclass, replace
from enum import StrEnum
from typing import Union

from afsmc.diagnostics import Span


class Type(StrEnum):
    INT = "int"
    DOUBLE = "double"
    BOOL = "bool"
    MODE = "mode"

    @property
    def numeric(self) -> bool:
        return self in (Type.INT, Type.DOUBLE)


@dataclass(frozen=True)
class Lit:
    value: int | float | bool
    type: Type
    span: Span | None = None


@dataclass(frozen=True)
class VarRef:
    name: str  # flat state-variable name
    type: Type
    span: Span | None = None


@dataclass(frozen=True)
class ConstRef:
    name: str
    type: Type
    span: Span | None = None


@dataclass(frozen=True)
class ModeVal:
    """A mode used as a value, e.g. in `mode == Search`; compiled to its number."""

    name: str
    number: int
    span: Span | None = None
    type: Type = Type.MODE


@dataclass(frozen=True)
class CurrentMode:
    span: Span | None = None
    type: Type = Type.MODE


@dataclass(frozen=True)
class FormulaRef:
    name: str
    type: Type
    span: Span | None = None


@dataclass(frozen=True)
class LabelRef:
    name: str
    span: Span | None = None
    type: Type = Type.BOOL


@dataclass(frozen=True)
class WeightRef:
    """`w(Action)`: the action's effective weight in the current state."""

    action: str
    span: Span | None = None
    type: Type = Type.DOUBLE


@dataclass(frozen=True)
class Unary:
    op: str  # "-" or "!"
    operand: Expr
    type: Type
    span: Span | None = None


@dataclass(frozen=True)
class Binary:
    op: str  # + - * / == != < <= > >= && || =>
    left: Expr
    right: Expr
    type: Type
    span: Span | None = None


@dataclass(frozen=True)
class Ite:
    cond: Expr
    then: Expr
    other: Expr
    type: Type
    span: Span | None = None


@dataclass(frozen=True)
class Call:
    func: str  # min max floor ceil pow mod
    args: tuple[Expr, ...]
    type: Type
    span: Span | None = None


Expr = Union[Lit, VarRef, ConstRef, ModeVal, CurrentMode, FormulaRef, LabelRef, WeightRef,
             Unary, Binary, Ite, Call]

FUNCTIONS = {"min", "max", "floor", "ceil", "pow", "mod"}


def children(e: Expr) -> tuple[Expr, ...]:
    if isinstance(e, Unary):
        return (e.operand,)
    if isinstance(e, Binary):
        return (e.left, e.right)
    if isinstance(e, Ite):
        return (e.cond, e.then, e.other)
    if isinstance(e, Call):
        return e.args
    return ()


def walk(e: Expr) -> Iterator[Expr]:
    """Every node of `e`, parents before children, left to right. Iterative: a recursive
    generator would pass each node up through every level above it (cubic work on a long
    chain like `a + b + c + ...`)."""
    stack = [e]
    while stack:
        n = stack.pop()
        yield n
        stack.extend(reversed(children(n)))


def depth(e: Expr, formulas: Callable[[str], int] | None = None) -> int:
    """How deeply `e` nests (a leaf is 1); with `formulas`, a formula reference counts as
    deep as `formulas(name)` says (its value once inlined). Iterative."""
    best = 0
    stack = [(e, 1)]
    while stack:
        n, d = stack.pop()
        if formulas is not None and isinstance(n, FormulaRef):
            d += formulas(n.name) - 1
        best = max(best, d)
        stack.extend((c, d + 1) for c in children(n))
    return best


def transform(e: Expr, fn: Callable[[Expr], Expr | None]) -> Expr:
    """Rebuild bottom-up; `fn` returns a replacement for a node or None to keep it. A node
    none of whose parts changed is kept itself, not copied (inlining an expression that
    refers to no formula rebuilds nothing)."""
    if isinstance(e, Unary):
        operand = transform(e.operand, fn)
        if operand is not e.operand:
            e = replace(e, operand=operand)
    elif isinstance(e, Binary):
        left, right = transform(e.left, fn), transform(e.right, fn)
        if left is not e.left or right is not e.right:
            e = replace(e, left=left, right=right)
    elif isinstance(e, Ite):
        cond, then, other = transform(e.cond, fn), transform(e.then, fn), transform(e.other, fn)
        if cond is not e.cond or then is not e.then or other is not e.other:
            e = replace(e, cond=cond, then=then, other=other)
    elif isinstance(e, Call):
        args = tuple(transform(a, fn) for a in e.args)
        if any(a is not b for a, b in zip(args, e.args, strict=True)):
            e = replace(e, args=args)
    out = fn(e)
    return e if out is None else out


def vars_read(e: Expr) -> set[str]:
    return {n.name for n in walk(e) if isinstance(n, VarRef)}


def reads_mode(e: Expr) -> bool:
    return any(isinstance(n, CurrentMode) for n in walk(e))


def consts_read(e: Expr) -> set[str]:
    return {n.name for n in walk(e) if isinstance(n, ConstRef)}


def state_free(e: Expr) -> bool:
    """Made of numbers and constants only: the same value in every state."""
    return all(isinstance(n, (Lit, ConstRef, Unary, Binary, Ite, Call)) for n in walk(e))


# ---- small constructors used by the lowering and the backends ------------------

TRUE = Lit(True, Type.BOOL)
FALSE = Lit(False, Type.BOOL)


def lit(v: int | float | bool) -> Lit:
    if isinstance(v, bool):
        return Lit(v, Type.BOOL)
    if isinstance(v, int):
        return Lit(v, Type.INT)
    return Lit(v, Type.DOUBLE)


def conj(*parts: Expr) -> Expr:
    items = [p for p in parts if not (isinstance(p, Lit) and p.value is True)]
    if any(isinstance(p, Lit) and p.value is False for p in items):
        return FALSE
    if not items:
        return TRUE
    out = items[0]
    for p in items[1:]:
        out = Binary("&&", out, p, Type.BOOL)
    return out


def disj(*parts: Expr) -> Expr:
    items = [p for p in parts if not (isinstance(p, Lit) and p.value is False)]
    if any(isinstance(p, Lit) and p.value is True for p in items):
        return TRUE
    if not items:
        return FALSE
    out = items[0]
    for p in items[1:]:
        out = Binary("||", out, p, Type.BOOL)
    return out


def neg(e: Expr) -> Expr:
    if isinstance(e, Lit) and isinstance(e.value, bool):
        return lit(not e.value)
    if isinstance(e, Unary) and e.op == "!":
        return e.operand
    return Unary("!", e, Type.BOOL)


def mul(a: Expr, b: Expr) -> Expr:
    if isinstance(a, Lit) and a.value == 1:
        return b
    if isinstance(b, Lit) and b.value == 1:
        return a
    t = Type.INT if a.type is Type.INT and b.type is Type.INT else Type.DOUBLE
    return Binary("*", a, b, t)


def sub(a: Expr, b: Expr) -> Expr:
    t = Type.INT if a.type is Type.INT and b.type is Type.INT else Type.DOUBLE
    return Binary("-", a, b, t)


def mode_in(numbers: set[int] | frozenset[int], names: dict[int, str]) -> Expr:
    """`mode` is one of `numbers`, as compact as contiguous runs allow."""
    parts: list[Expr] = []
    for lo, hi in runs(sorted(numbers)):
        if lo == hi:
            parts.append(Binary("==", CurrentMode(), ModeVal(names[lo], lo), Type.BOOL))
        else:
            parts.append(conj(Binary(">=", CurrentMode(), ModeVal(names[lo], lo), Type.BOOL),
                              Binary("<=", CurrentMode(), ModeVal(names[hi], hi), Type.BOOL)))
    return disj(*parts)


def runs(nums: list[int]) -> list[tuple[int, int]]:
    out: list[tuple[int, int]] = []
    for n in nums:
        if out and out[-1][1] == n - 1:
            out[-1] = (out[-1][0], n)
        else:
            out.append((n, n))
    return out
