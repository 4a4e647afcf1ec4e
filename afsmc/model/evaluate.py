"""Evaluation of IR expressions, over one state or over many states at once (numpy).

The checks enumerate state spaces with it, so it evaluates one expression over whole
arrays of states; scalars work too (constants, and the parts of an expression that read
no variable), and are computed exactly. What each operator computes is
:mod:`afsmc.model.kernel`'s: this module only walks the expression, resolves names and
picks the scalar or the vector form of each operator.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from afsmc.model import kernel
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
    Unary,
    VarRef,
    WeightRef,
)
from afsmc.model.kernel import EvalError, RangeError, storm_mod

Array = Any  # numpy array or Python scalar

__all__ = ["Env", "EvalError", "RangeError", "evaluate", "scalar", "storm_mod"]


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
        op = kernel.unary(e.op)
        return op.scalar(v) if _one(v) else op.vector(v)
    if isinstance(e, Binary):
        return _binary(e, env)
    if isinstance(e, Ite):
        c = evaluate(e.cond, env)
        if _one(c):  # one branch for every state: the other one is not used
            return evaluate(e.then if c else e.other, env)
        return kernel.ite_vector(c, evaluate(e.then, env), evaluate(e.other, env))
    if isinstance(e, Call):
        return _call(e, env)
    raise EvalError(f"cannot evaluate {type(e).__name__}")


def _one(v: Array) -> bool:
    """One value (a Python or numpy scalar), not an array of states (nor a 0-d array,
    which the vector forms take): the kernel's scalar forms then compute it, in plain
    Python where they can (numpy's ufuncs cost about a microsecond each on a scalar, and
    the checks evaluate thousands of state-free parts). Not np.ndim: it costs as much."""
    return not isinstance(v, np.ndarray)


def _binary(e: Binary, env: Env) -> Array:
    op = e.op
    left = evaluate(e.left, env)
    if op in ("&&", "||", "=>") and _one(left):
        # A scalar left side may decide the result for every state: skip the right side.
        if op == "&&" and not left:
            return False
        if op == "||" and left:
            return True
        if op == "=>" and not left:
            return True
    right = evaluate(e.right, env)
    fn = kernel.binary(op)
    if _one(left) and _one(right):
        return fn.scalar(left, right)
    return fn.vector(left, right)


def _call(e: Call, env: Env) -> Array:
    args = [evaluate(a, env) for a in e.args]
    fn = kernel.call(e.func, e.type)
    if all(_one(a) for a in args):
        return fn.scalar(*args)
    return fn.vector(*args)


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
