"""afsmc.verify.explorer.explore_eval.Compiler numbers each subexpression by its structure
(class and fields, a compiled child standing for its number) instead of hashing the
expression: two expressions share a number exactly when they are equal (the dataclasses'
equality is the oracle), the same object or an equal copy; and a chain nested thousands
deep compiles and evaluates."""

from __future__ import annotations

import copy

import numpy as np
from hypothesis import HealthCheck, given, settings

from afsmc.model import expr as E
from afsmc.stack import deep
from afsmc.verify.explorer.explore_eval import Compiler, frame
from tests.unit.model.exprgen import any_expression

LEAVES = (E.Lit, E.VarRef, E.CurrentMode)


@settings(max_examples=300, deadline=None,
          suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large])
@given(any_expression, any_expression)
def test_two_expressions_share_a_number_exactly_when_they_are_equal(a: E.Expr, b: E.Expr
                                                                      ) -> None:
    c = Compiler()
    c(a)
    c(b)
    twin = copy.deepcopy(a)  # an equal expression, another object
    c(twin)
    if isinstance(a, LEAVES):
        assert c.key(a) is None
        return
    assert c.key(a) is not None and c.key(twin) == c.key(a)
    if not isinstance(b, LEAVES):
        assert (c.key(a) == c.key(b)) == (a == b)


def _chain(depth: int) -> E.Expr:
    x = E.VarRef("x", E.Type.INT)
    e: E.Expr = x
    for _ in range(depth):
        e = E.Binary("+", e, x, E.Type.INT)
    return e


@deep  # the room the commands give deep expressions
def _compiled(e: E.Expr) -> tuple[Compiler, list[int]]:
    c = Compiler()
    return c, list(c(e)(frame({"x": np.array([1, 2], np.int64)})))


def test_a_chain_nested_thousands_deep_compiles_and_evaluates() -> None:
    e = _chain(4000)
    c, got = _compiled(e)
    assert got == [4001, 8002]
    # each level numbered once, the innermost first: as many numbers as levels
    assert len(c.ids) == 4000 and c.key(e) == 3999
