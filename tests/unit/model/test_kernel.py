"""The expression kernel: each operator's scalar and vector forms agree, and the checks'
evaluation (scalar and vectorised), the folding, the simulator's closures and the
explorer's closures give every random expression the same value, because all of them take
their operators from afsmc.model.kernel. (Storm is the oracle of test_kernel_storm.py.)"""

from __future__ import annotations

from typing import Any

import numpy as np
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from afsmc.model import expr as E
from afsmc.model import kernel
from afsmc.model.evaluate import Env, EvalError, evaluate
from afsmc.sim.compile import Scope, SimError, compile_expr, fold
from afsmc.verify.explorer.explore_eval import Compiler, frame
from tests.unit.model.exprgen import (
    VARS,
    any_expression,
    assignments,
    doubles,
    ints,
    same,
)

SETTINGS = settings(max_examples=300, deadline=None,
                    suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large])
INT64 = 2**63
BEYOND = "beyond 64 bits"
numbers = st.one_of(ints, doubles)


def _scalar(op: kernel.Op, *args: Any) -> Any:
    try:
        return op.scalar(*args)
    except kernel.RangeError:
        return INT64  # beyond 64 bits
    except EvalError:
        return None  # undefined


def _vector(op: kernel.Op, *args: Any) -> Any:
    with np.errstate(all="ignore"):
        return np.asarray(op.vector(*(np.array([a, a]) for a in args)))[0]


def _agree(op: kernel.Op, *args: Any) -> None:
    want, got = _scalar(op, *args), _vector(op, *args)
    if want is None:  # a division or mod by zero: NaN in the vector form
        assert got != got, (args, got)
    elif isinstance(want, int) and not -INT64 <= want < INT64:
        pass  # exact in the scalar form, wrapped around in int64: refused by the checks (E307)
    else:
        assert same(want, got), (args, want, got)


@SETTINGS
@given(st.sampled_from(sorted(kernel.BINARY)), numbers, numbers)
def test_every_binary_operator_has_equal_scalar_and_vector_forms(op: str, a: Any, b: Any) -> None:
    if op in ("&&", "||", "=>"):
        a, b = bool(a), bool(b)
    _agree(kernel.BINARY[op], a, b)


@SETTINGS
@given(st.sampled_from(sorted(kernel.CALLS)), numbers, numbers, numbers)
def test_every_function_has_equal_scalar_and_vector_forms(fn: str, a: Any, b: Any, c: Any) -> None:
    op = kernel.CALLS[fn]
    if fn in ("floor", "ceil"):
        _agree(op, a)
    elif fn in ("min", "max"):
        _agree(op, a, b)
        _agree(op, a, b, c)
    elif fn == "mod":
        _agree(op, int(a), int(b))
    else:
        _agree(op, a, b)


@SETTINGS
@given(ints, st.one_of(st.integers(-4, 70), ints), numbers)
def test_integer_pow_and_negation_have_equal_scalar_and_vector_forms(b: int, k: int, v: Any) -> None:
    _agree(kernel.INT_POW, b, k)
    _agree(kernel.UNARY["-"], v)
    _agree(kernel.UNARY["!"], bool(v))


def test_the_kernel_rules_by_hand() -> None:
    """Values worked out by hand from PRISM's and Storm's rules (see the kernel's docstring)."""
    s = {k: op.scalar for k, op in kernel.BINARY.items()}
    c = {k: op.scalar for k, op in kernel.CALLS.items()}
    assert s["/"](7, 2) == 3.5 and s["/"](-7, 2) == -3.5
    assert [c["mod"](a, b) for a, b in [(7, 3), (-7, 3), (7, -3), (-7, -3), (-6, 3)]] == [1, 2, 1, -4, 3]
    assert (c["floor"](-2.5), c["ceil"](-2.5), c["floor"](2), c["ceil"](2.0000001)) == (-3, -2, 2, 3)
    assert kernel.INT_POW.scalar(2, -1) == 0.5 and kernel.INT_POW.scalar(-2, 3) == -8
    assert kernel.INT_POW.scalar(3, 39) == 4052555153018976267  # exact, not via a double
    assert c["pow"](-8.0, 1 / 3) != c["pow"](-8.0, 1 / 3)  # NaN
    assert c["min"](1, 2.5) == 1.0 and isinstance(c["min"](1, 2.5), float)
    assert c["max"](-1, -3) == -1 and isinstance(c["max"](-1, -3), int)
    assert s["=="](0.1 + 0.2, 0.3) and not s["!="](0.1 + 0.2, 0.3)
    assert not s["=="](1e-11, 0.0) and s["=="](float("inf"), float("inf"))
    assert s["=>"](False, False) and not s["=>"](True, False)
    for what, fn in [("division by zero", lambda: s["/"](1, 0)),
                     ("mod by zero", lambda: c["mod"](1, 0))]:
        try:
            fn()
        except EvalError as exc:
            assert str(exc) == what
        else:
            raise AssertionError(what)


def fits_int64(e: E.Expr, state: dict[str, int]) -> bool:
    """No part of `e` is an integer beyond 64 bits in this state."""
    env = Env(vars=state)
    for n in E.walk(e):
        try:
            v = evaluate(n, env)
        except kernel.RangeError:
            return False
        except EvalError:
            continue
        if (isinstance(v, int) or n.type is E.Type.INT) and not -INT64 <= v < INT64:
            return False  # (an integer-typed part may be a double: `pow(9, 20.0)`)
    return True


def undefined_constant_part(e: E.Expr) -> bool:
    """`e` has a part that reads no variable and is undefined (`1 / 0` under a `?:` that
    never takes it, which the resolver accepts): the checks' vectorised evaluation computes
    such a part once, as a scalar, and raises EvalError, whatever the states."""
    for n in E.walk(e):
        if E.state_free(n) and not isinstance(n, E.Lit):
            try:
                evaluate(n, Env())
            except kernel.RangeError:
                continue
            except EvalError:
                return True
    return False


def evaluators(e: E.Expr, states: list[dict[str, int]]) -> dict[str, list[Any]]:
    """`e`'s value in each state by every evaluator of afsmc (None: undefined)."""
    out: dict[str, list[Any]] = {"kernel": [], "folded": []}
    for st_ in states:
        try:
            out["kernel"].append(evaluate(e, Env(vars=st_)))
        except kernel.RangeError:
            out["kernel"].append(BEYOND)
        except EvalError:
            out["kernel"].append(None)
        as_consts = E.transform(e, lambda n: E.ConstRef(n.name, n.type)
                                if isinstance(n, E.VarRef) else None)
        try:
            lit = fold(as_consts, Scope(st_, {}, {}, {}))
            out["folded"].append(lit.value if isinstance(lit, E.Lit) else "not folded")
        except SimError:
            out["folded"].append(None)
    arrays = {n: np.array([s[n] for s in states], dtype=np.int64) for n in VARS}
    with np.errstate(all="ignore"):
        for name, fn in [("checks", lambda: evaluate(e, Env(vars=arrays))),
                         ("simulator", lambda: compile_expr(e)(arrays)),
                         ("explorer", lambda: Compiler()(e)(frame(dict(arrays))))]:
            try:
                v = np.broadcast_to(fn(), (len(states),))
            except (EvalError, SimError, OverflowError):
                # a part that reads no variable is undefined, or an integer beyond 64 bits
                v = np.full(len(states), None)
            out[name] = list(v)
    return out


@settings(max_examples=300, deadline=None,
          suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large])
@given(any_expression, st.lists(assignments, min_size=1, max_size=4))
def test_afsmcs_evaluators_agree_on_random_expressions(e: E.Expr, states: list[dict[str, int]]) -> None:
    got = evaluators(e, states)
    for i, want in enumerate(got["kernel"]):
        if want is BEYOND:
            continue  # refused by the checks (E307)
        if want is None:
            continue  # undefined: the checks refuse a model that uses such a value (E306)
        if not fits_int64(e, states[i]):
            continue  # a part beyond 64 bits: refused by the checks (E307)
        for name in ("folded", "checks", "simulator", "explorer"):
            if name == "checks" and undefined_constant_part(e):
                continue
            assert same(want, got[name][i]), (name, e, states[i], want, got[name][i])
