"""Vectorised evaluation of IR expressions over many states at once (numpy).

The checks enumerate state spaces with it and the Monte Carlo simulator advances
thousands of runs with it, so it evaluates one expression over whole arrays of states.
Scalars work too (constants). Semantics follow PRISM: `/` is real division, `floor` and
`ceil` give integers, `=>` is implication; `mod` is Storm's (`storm_mod`).
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from afsmc.model.expr import (
    Binary,
    Call,
    ConstRef,
    CurrentMode,
    Expr,
    FormulaRef,
    Ite,
    LabelRef,
    Lit,
    ModeVal,
    Type,
    Unary,
    VarRef,
    WeightRef,
)

Array = Any  # numpy array or Python scalar


class EvalError(Exception):
    """An expression cannot be evaluated (division by zero, a missing name)."""


class RangeError(EvalError):
    """A value beyond what PRISM and Storm compute with (a 64-bit integer)."""


@dataclass
class Env:
    vars: Mapping[str, Array] = field(default_factory=dict)
    mode: Array | None = None
    consts: Mapping[str, Any] = field(default_factory=dict)
    formulas: Mapping[str, Expr] = field(default_factory=dict)
    labels: Mapping[str, Expr] = field(default_factory=dict)
    weight: Callable[[str], Array] | None = None
    memo: dict[int, Array] = field(default_factory=dict)
    # Values of compound nodes already evaluated in this same state-free environment, by
    # id (with the node, so that a reused id is not mistaken): a caller that evaluates
    # every level of a long chain (the resolver's folding check) then pays for each node once.
    nodes: dict[int, tuple[Expr, Any]] | None = None


def evaluate(e: Expr, env: Env) -> Array:
    if env.nodes is not None and isinstance(e, (Unary, Binary, Call)):
        hit = env.nodes.get(id(e))
        if hit is not None and hit[0] is e:
            if isinstance(hit[1], _Raised):
                raise hit[1].exc
            return hit[1]
        try:
            v = _evaluate(e, env)
        except (EvalError, ArithmeticError) as exc:
            env.nodes[id(e)] = (e, _Raised(exc))
            raise
        env.nodes[id(e)] = (e, v)
        return v
    return _evaluate(e, env)


@dataclass(frozen=True)
class _Raised:
    """What a node's evaluation raised, remembered like a value in Env.nodes."""

    exc: Exception


def _evaluate(e: Expr, env: Env) -> Array:
    if isinstance(e, Lit):
        return e.value
    if isinstance(e, VarRef):
        try:
            return env.vars[e.name]
        except KeyError:
            raise EvalError(f"variable {e.name} has no value here") from None
    if isinstance(e, ConstRef):
        try:
            return env.consts[e.name]
        except KeyError:
            raise EvalError(f"constant {e.name} has no value") from None
    if isinstance(e, ModeVal):
        return e.number
    if isinstance(e, CurrentMode):
        if env.mode is None:
            raise EvalError("the current mode is not known here")
        return env.mode
    if isinstance(e, FormulaRef):
        key = id(env.formulas[e.name])
        if key not in env.memo:
            env.memo[key] = evaluate(env.formulas[e.name], env)
        return env.memo[key]
    if isinstance(e, LabelRef):
        return evaluate(env.labels[e.name], env)
    if isinstance(e, WeightRef):
        if env.weight is None:
            raise EvalError("weights are not known here")
        return env.weight(e.action)
    if isinstance(e, Unary):
        v = evaluate(e.operand, env)
        return np.logical_not(v) if e.op == "!" else -v
    if isinstance(e, Binary):
        return _binary(e, env)
    if isinstance(e, Ite):
        c = evaluate(e.cond, env)
        a = evaluate(e.then, env)
        b = evaluate(e.other, env)
        if np.ndim(c) == 0 and np.ndim(a) == 0 and np.ndim(b) == 0:
            return a if c else b
        return np.where(c, a, b)
    if isinstance(e, Call):
        return _call(e, env)
    raise EvalError(f"cannot evaluate {type(e).__name__}")


# Python scalars (one state, or a part that reads no variable): numpy's ufuncs cost about
# a microsecond each on them, and the checks evaluate thousands of such parts.
_SCALAR = (bool, int, np.bool_, np.integer)
_PYTHON_OPS: dict[str, Callable[[Any, Any], Any]] = {
    "+": lambda a, b: a + b, "-": lambda a, b: a - b, "*": lambda a, b: a * b,
    "<": lambda a, b: a < b, "<=": lambda a, b: a <= b, ">": lambda a, b: a > b,
    ">=": lambda a, b: a >= b, "==": lambda a, b: a == b, "!=": lambda a, b: a != b,
}


def _binary(e: Binary, env: Env) -> Array:
    op = e.op
    left = evaluate(e.left, env)
    if op in ("&&", "||", "=>"):
        # A scalar left side may decide the result for every state: skip the right side.
        if isinstance(left, _SCALAR):
            if op == "&&" and not left:
                return False
            if op == "||" and left:
                return True
            if op == "=>" and not left:
                return True
        right = evaluate(e.right, env)
        if op == "&&":
            return np.logical_and(left, right)
        if op == "||":
            return np.logical_or(left, right)
        return np.logical_or(np.logical_not(left), right)
    right = evaluate(e.right, env)
    # Integers and booleans only: doubles keep numpy's semantics (== with a tolerance).
    if isinstance(left, _SCALAR) and isinstance(right, _SCALAR) and op in _PYTHON_OPS:
        return _PYTHON_OPS[op](left, right)
    if op == "+":
        return left + right
    if op == "-":
        return left - right
    if op == "*":
        return left * right
    if op == "/":
        return _masked(np.true_divide, left, right, "division by zero")
    if op == "==":
        return _eq(left, right)
    if op == "!=":
        return np.logical_not(_eq(left, right))
    if op == "<":
        return np.less(left, right)
    if op == "<=":
        return np.less_equal(left, right)
    if op == ">":
        return np.greater(left, right)
    if op == ">=":
        return np.greater_equal(left, right)
    raise EvalError(f"unknown operator {op}")


def _eq(a: Array, b: Array) -> Array:
    # Doubles compare with a tolerance, as Storm does for its constants.
    if np.issubdtype(np.asarray(a).dtype, np.floating) or np.issubdtype(np.asarray(b).dtype, np.floating):
        return np.isclose(a, b, rtol=0.0, atol=1e-12)
    return np.equal(a, b)


def _call(e: Call, env: Env) -> Array:
    args = [evaluate(a, env) for a in e.args]
    f = e.func
    if f == "min":
        out = args[0]
        for a in args[1:]:
            out = np.minimum(out, a)
        return out
    if f == "max":
        out = args[0]
        for a in args[1:]:
            out = np.maximum(out, a)
        return out
    if f == "floor":
        return _to_int(np.floor(args[0]))
    if f == "ceil":
        return _to_int(np.ceil(args[0]))
    if f == "pow":
        base, power = args
        if (e.type is Type.INT and isinstance(base, (int, np.integer))
                and isinstance(power, (int, np.integer)) and power >= 0):
            # Exact on scalars (constants), where numpy's int64 would wrap around unseen.
            b, k = int(base), int(power)
            if (abs(b) > 1 and k >= 64) or not -(2**63) <= b**k < 2**63:
                raise RangeError(f"pow({b}, {k}) does not fit in a 64-bit integer")
            return b**k
        exp = np.asarray(args[1])
        if e.type is Type.INT and not np.any(exp < 0):
            return np.power(np.asarray(args[0], dtype=np.int64), exp.astype(np.int64))
        return np.power(np.asarray(args[0], dtype=float), exp)
    if f == "mod":
        return _masked(storm_mod, args[0], args[1], "mod by zero")
    raise EvalError(f"unknown function {f}")


def storm_mod(a: Array, b: Array) -> Array:
    """`mod(a, b)` of integers as Storm computes it (sparse and symbolic engines, from
    PRISM and from JANI alike): the C++ remainder (truncated division, the sign of `a`),
    plus `b` where `a` is negative. So mod(7, 3) = 1, mod(-7, 3) = 2, mod(7, -3) = 1,
    mod(-7, -3) = -4 and mod(-6, 3) = 3: not numpy's (sign of `b`) nor Python's. `b` != 0."""
    if isinstance(a, (int, np.integer)) and isinstance(b, (int, np.integer)):
        x, y = int(a), int(b)  # exact on scalars
        r = abs(x) % abs(y)
        return r if x >= 0 else y - r
    left, right = np.asarray(a), np.asarray(b)
    rem = np.fmod(left, right)
    return np.where(left >= 0, rem, rem + right)


def _masked(fn: Any, left: Array, right: Array, what: str) -> Array:
    """`fn(left, right)`; over arrays of states, NaN where `right` is 0, so that one such
    state (often excluded by a guard or an untaken `?:` branch) does not stop the others."""
    r = np.asarray(right)
    if r.ndim == 0 and np.ndim(left) == 0:
        if r == 0:
            raise EvalError(what)
        return fn(left, right)
    zero = r == 0
    if not np.any(zero):
        return fn(left, right)
    # `fn` sees 1 where `right` is 0, so it needs no ufunc `where=` (storm_mod has none)
    return np.where(zero, np.nan, fn(left, np.where(zero, 1, r)))


def _to_int(v: Array) -> Array:
    if np.ndim(v) == 0:
        if not np.isfinite(v):
            raise EvalError("not a number")
        return int(v)
    arr = np.asarray(v)
    if np.issubdtype(arr.dtype, np.floating) and not np.all(np.isfinite(arr)):
        return arr  # keeps NaN where a division by zero was (see _masked)
    return arr.astype(np.int64)


def scalar(e: Expr, consts: Mapping[str, Any], formulas: Mapping[str, Expr] | None = None,
           nodes: dict[int, tuple[Expr, Any]] | None = None) -> Any:
    """The value of a state-free expression, as a Python scalar. `nodes`: the values of
    subexpressions evaluated before with the same constants (see Env.nodes), kept across
    calls."""
    with np.errstate(all="ignore"):  # inf and NaN are the caller's to judge, not warnings
        v = evaluate(e, Env(consts=consts, formulas=formulas or {}, nodes=nodes))
    if isinstance(v, np.generic):
        return v.item()
    if isinstance(v, np.ndarray):
        return v.item()
    return v
