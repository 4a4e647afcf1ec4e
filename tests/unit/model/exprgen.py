"""Random typed IR expressions for the kernel's differential tests (hypothesis).

Every operator of the language appears, over integers and doubles (negative, zero, large)
and booleans, reading the integer variables `x0`, `x1`, `x2`. The types are the resolver's
(`+` of two integers is an integer, `/` a double, `floor` an integer...), so that every
expression is one a model could hold.
"""

from __future__ import annotations

import contextlib
import functools
from typing import Any

import numpy as np
from hypothesis import strategies as st

from afsmc.model import expr as E
from afsmc.model.evaluate import Env, EvalError, evaluate
from afsmc.model.expr import Type

INT, DOUBLE, BOOL = Type.INT, Type.DOUBLE, Type.BOOL
VARS = ("x0", "x1", "x2")

small_ints = st.integers(-10, 10)
large_ints = st.integers(-(2**40), 2**40)
ints = st.one_of(small_ints, small_ints, large_ints)
# Binary fractions (test_kernel_storm writes them for Storm as integers divided by a power
# of two); other doubles come from the operators.
doubles = st.one_of(
    st.sampled_from([0.0, 0.5, -2.5, 0.25, 3.0, -7.25, 1e9, -1e12, 2.0**-20]),
    st.integers(-(2**20), 2**20).map(lambda k: k / 64),
    st.integers(-(2**40), 2**40).map(lambda k: k / 1024),
)


def _unify(a: E.Expr, b: E.Expr) -> Type:
    return INT if a.type is INT and b.type is INT else DOUBLE


def _int_leaf() -> Any:
    return st.one_of(ints.map(lambda v: E.Lit(v, INT)),
                     st.sampled_from(VARS).map(lambda n: E.VarRef(n, INT)))


def _double_leaf() -> Any:
    return doubles.map(lambda v: E.Lit(v, DOUBLE))


def _bool_leaf() -> Any:
    return st.booleans().map(lambda v: E.Lit(v, BOOL))


@functools.cache
def _expr(t: Type, depth: int) -> Any:
    """Expressions of type `t`, at most `3 - depth` levels deep."""
    leaf = {INT: _int_leaf, DOUBLE: _double_leaf, BOOL: _bool_leaf}[t]()
    if depth >= 3:
        return leaf
    d = depth + 1
    i, f, b = _expr(INT, d), _expr(DOUBLE, d), _expr(BOOL, d)
    num = st.one_of(i, f)
    if t is INT:
        compound = st.one_of(
            st.builds(lambda x: E.Unary("-", x, INT), i),
            st.builds(lambda op, x, y: E.Binary(op, x, y, INT), st.sampled_from("+-*"), i, i),
            st.builds(lambda fn, xs: E.Call(fn, tuple(xs), INT), st.sampled_from(["min", "max"]),
                      st.lists(i, min_size=2, max_size=3)),
            st.builds(lambda fn, x: E.Call(fn, (x,), INT), st.sampled_from(["floor", "ceil"]), num),
            st.builds(lambda x, k: E.Call("pow", (x, k), INT), i,
                      st.one_of(st.integers(-3, 6).map(lambda v: E.Lit(v, INT)), i)),
            st.builds(lambda x, y: E.Call("mod", (x, y), INT), i, i),
            st.builds(lambda c, x, y: E.Ite(c, x, y, INT), b, i, i),
        )
    elif t is DOUBLE:
        compound = st.one_of(
            st.builds(lambda x: E.Unary("-", x, DOUBLE), f),
            st.builds(lambda op, x, y: E.Binary(op, x, y, DOUBLE), st.sampled_from("+-*"), f, num),
            st.builds(lambda op, x, y: E.Binary(op, x, y, DOUBLE), st.sampled_from("+-*"), num, f),
            st.builds(lambda x, y: E.Binary("/", x, y, DOUBLE), num, num),
            st.builds(lambda fn, x, y: E.Call(fn, (x, y), DOUBLE),
                      st.sampled_from(["min", "max"]), f, num),
            st.builds(lambda x, y: E.Call("pow", (x, y), DOUBLE), f, num),
            st.builds(lambda x, y: E.Call("pow", (x, y), DOUBLE), num, f),
            st.builds(lambda c, x, y: E.Ite(c, x, y, _unify(x, y)), b, f, num),
        )
    else:
        compound = st.one_of(
            st.builds(lambda op, x, y: E.Binary(op, x, y, BOOL),
                      st.sampled_from(["==", "!=", "<", "<=", ">", ">="]), num, num),
            st.builds(lambda op, x, y: E.Binary(op, x, y, BOOL),
                      st.sampled_from(["&&", "||", "=>"]), b, b),
            st.builds(lambda x: E.Unary("!", x, BOOL), b),
            st.builds(lambda c, x, y: E.Ite(c, x, y, BOOL), b, b, b),
        )
    return st.one_of(leaf, compound, compound)


def expressions(t: Type) -> Any:
    return _expr(t, 0)


any_expression = st.one_of(expressions(INT), expressions(DOUBLE), expressions(BOOL))
assignments = st.fixed_dictionaries({n: ints for n in VARS})


def same(a: Any, b: Any) -> bool:
    """Equal values, NaN equal to NaN, an integer equal to the same double."""
    a, b = _plain(a), _plain(b)
    if isinstance(a, float) or isinstance(b, float):
        return (a != a and b != b) or float(a) == float(b)
    return bool(a == b)


def _plain(v: Any) -> Any:
    return v.item() if isinstance(v, np.generic) else v


def subvalues(e: E.Expr, env: Env) -> list[Any]:
    """The values of `e`'s parts that can be computed in one state (undefined ones left
    out): to keep the comparisons where they are meaningful."""
    out = []
    for n in E.walk(e):
        with contextlib.suppress(EvalError):
            out.append(_plain(evaluate(n, env)))
    return out
