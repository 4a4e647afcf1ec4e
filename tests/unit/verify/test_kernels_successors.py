"""The successor kernel compiled from the lowered commands (afsmc.verify.kernels.successors,
taken by afsmc.verify.explorer.explore.expand under AFSMC_SUCCESSORS=numba) against the
numpy path it replaces: `expand` of every reachable state bit for bit, whole explorations
bit for bit, and each operator's translation against afsmc.model.kernel's scalar form."""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from afsmc.model import expr as E
from afsmc.model import kernel
from afsmc.verify.explorer import explore, explore_graph
from afsmc.verify.kernels import successors
from tests.unit.verify.test_kernels_explore import _differences
from tests.unit.verify.test_streaming import CASES, _loops, _plan


@pytest.fixture(autouse=True)
def _cache(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv("AFSMC_KERNEL_CACHE", str(tmp_path / "kernels"))


def _reachable(c: explore.Compiled) -> np.ndarray[Any, np.dtype[np.int64]]:
    """Every reachable key, by the numpy path's expand from the initial state."""
    seen = {c.initial}
    frontier = np.array([c.initial], np.int64)
    while frontier.size:
        x = explore.expand(c, frontier)
        new = sorted(set(x.target.tolist()) - seen)
        seen.update(new)
        frontier = np.array(new, np.int64)
    return np.array(sorted(seen), np.int64)


def _case(case: str, tmp: Path) -> tuple[str, dict[str, str]]:
    return (_loops(tmp), {}) if case == "loops" else CASES[case]


SLOW = pytest.mark.slow  # numba compiles these models' kernels for a minute or more


# (the UAV and overtake, and every example the explorer accepts, compare alike: numba
# compiles each of them for a minute or more, too long for the suite; run them by adding
# their names here when the generated kernels change)
@pytest.mark.parametrize("case", ["loops", pytest.param("rover", marks=SLOW)])
def test_the_kernels_expansion_of_every_reachable_state_is_numpys(
        case: str, tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    _, c = _plan(*_case(case, tmp_path))
    keys = _reachable(c)
    monkeypatch.delenv("AFSMC_SUCCESSORS", raising=False)
    want = explore.expand(c, keys, fast=True)
    monkeypatch.setenv("AFSMC_SUCCESSORS", "numba")
    taken: list[bool] = []
    real = successors.run
    monkeypatch.setattr(successors, "run", lambda *a: (r := real(*a), taken.append(r is not None))[0])
    got = explore.expand(c, keys, fast=True)
    assert taken == [True]  # the kernel answered, not the numpy fallback
    assert _differences(want, got) == []
    assert len(want.target) > len(keys)  # a model with choices and branches to compare


@pytest.mark.parametrize("case", ["loops", pytest.param("rover", marks=SLOW)])
def test_the_exploration_with_the_successor_kernel_is_numpys(
        case: str, tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    _, c = _plan(*_case(case, tmp_path))
    monkeypatch.setenv("AFSMC_KERNELS", "numpy")
    want = explore_graph.explore(c)
    monkeypatch.setenv("AFSMC_KERNELS", "numba")
    monkeypatch.setenv("AFSMC_SUCCESSORS", "numba")
    got = explore_graph.explore(c)
    assert callable(c.successors)
    assert _differences(want, got) == []


def _outcome(c: explore.Compiled, keys: np.ndarray[Any, np.dtype[np.int64]]) -> Any:
    try:
        return explore.expand(c, keys, fast=True)
    except explore.GiveUp as e:
        return f"GiveUp: {e}"


def test_states_the_model_does_not_reach_get_numpys_answer_or_its_give_up(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """Each reachable state put in every mode number the key can hold (modes without a
    command, guards that no longer hold, variables leaving their ranges): the kernel's
    expansion, or its fallback's GiveUp, is numpy's."""
    _, c = _plan(*_case("loops", tmp_path))
    keys = _reachable(c)
    f = c.layout.fields["mode"]
    for m in range(f.mask + 1):
        moved = (keys & ~(f.mask << f.shift)) | (m << f.shift)
        for part in (moved, moved[:1]):
            monkeypatch.delenv("AFSMC_SUCCESSORS", raising=False)
            want = _outcome(c, part)
            monkeypatch.setenv("AFSMC_SUCCESSORS", "numba")
            assert _differences(want, _outcome(c, part)) == []


# --- each operator's translation against its scalar form -------------------------------

INT, DOUBLE, BOOL = E.Type.INT, E.Type.DOUBLE, E.Type.BOOL


def _translated(e: E.Expr, names: list[str]) -> Any:
    """`e` over the variables `names` as a numba function of their values; ValueError
    where the kernel would leave the state to the numpy path."""
    import numba

    em = successors._Emitter({n: n for n in names})
    em.stop = lambda ind, cond: em.lines.extend(  # type: ignore[method-assign]
        [f"{ind}if {cond}:", f"{ind}    raise ValueError('numpy decides')"])
    out = em.expr(e, "    ")
    text = "\n".join([f"def f({', '.join(names)}):", *em.lines, f"    return {out}"])
    scope: dict[str, Any] = {"np": np, "math": math}
    header = successors.HEADER.replace("cache=True", "cache=False")  # no file to cache beside
    exec(compile(header, "<header>", "exec"), scope)
    exec(text, scope)
    return numba.njit(scope["f"])


def _var(name: str, t: E.Type) -> E.VarRef:
    return E.VarRef(name, t)


def _scalar(e: E.Expr, env: dict[str, Any]) -> Any:
    """The expression by afsmc.model.kernel's scalar forms."""
    if isinstance(e, E.VarRef):
        return env[e.name]
    if isinstance(e, E.Lit):
        return e.value
    if isinstance(e, E.Unary):
        return kernel.unary(e.op).scalar(_scalar(e.operand, env))
    if isinstance(e, E.Binary):
        return kernel.binary(e.op).scalar(_scalar(e.left, env), _scalar(e.right, env))
    if isinstance(e, E.Ite):
        return _scalar(e.then, env) if _scalar(e.cond, env) else _scalar(e.other, env)
    assert isinstance(e, E.Call)
    return kernel.call(e.func, e.type).scalar(*(_scalar(a, env) for a in e.args))


def _same(e: E.Expr, env: dict[str, Any]) -> None:
    fn = _CACHE.get(e) or _CACHE.setdefault(e, _translated(e, sorted(env)))
    try:
        want = _scalar(e, env)
    except kernel.EvalError:
        want = None
    try:
        got = fn(*(env[n] for n in sorted(env)))
    except ValueError:
        # left to numpy: where the scalar form is undefined, not an integer where its type
        # says one, not finite (floor/ceil), or NaN (min/max)
        assert want is None or (isinstance(e, E.Call) and (
            (not isinstance(want, int) and e.type is INT) or e.func in ("floor", "ceil", "min", "max")))
        return
    assert want is not None
    if isinstance(want, float) and math.isnan(want):
        assert math.isnan(got)
    else:
        assert type(got) in (bool, int, float, np.int64, np.float64, np.bool_)
        assert got == want and (float(got) == float(want))
        assert np.signbit(float(got)) == np.signbit(float(want)) or got == 0


_CACHE: dict[E.Expr, Any] = {}
INTS = st.integers(-40, 40)
DOUBLES = st.floats(-50, 50, allow_nan=False) | st.sampled_from([0.1 + 0.2, 0.3, -0.5, 0.0])
OPS = ["+", "-", "*", "/", "==", "!=", "<", "<=", ">", ">="]


@settings(max_examples=150, deadline=None)
@given(st.sampled_from(OPS), st.booleans(), INTS, INTS, DOUBLES)
def test_binary_operators_are_the_kernels(op: str, double: bool, a: int, b: int,
                                          d: float) -> None:
    t = BOOL if op in ("==", "!=", "<", "<=", ">", ">=") else DOUBLE if double or op == "/" else INT
    right = _var("y", DOUBLE if double else INT)
    _same(E.Binary(op, _var("x", INT), right, t), {"x": a, "y": d if double else b})


@settings(max_examples=150, deadline=None)
@given(st.sampled_from(["mod", "pow", "min", "max"]), st.booleans(), INTS, INTS, DOUBLES)
def test_calls_of_two_arguments_are_the_kernels(func: str, double: bool, a: int, b: int,
                                                d: float) -> None:
    if func == "pow":
        b = b % 9 - 3  # negative exponents too, without leaving 64 bits
    t = DOUBLE if double else INT
    _same(E.Call(func, (_var("x", INT), _var("y", t)), t), {"x": a, "y": d if double else b})


@settings(max_examples=100, deadline=None)
@given(st.sampled_from(["floor", "ceil"]), DOUBLES | st.floats(-1e3, 1e3))
def test_floor_and_ceil_are_the_kernels(func: str, d: float) -> None:
    _same(E.Call(func, (_var("x", DOUBLE),), INT), {"x": d})


@settings(max_examples=100, deadline=None)
@given(st.booleans(), st.booleans(), INTS, DOUBLES)
def test_logic_and_the_conditional_are_the_kernels(p: bool, q: bool, a: int, d: float) -> None:
    x, y = _var("p", BOOL), _var("q", BOOL)
    env = {"p": p, "q": q, "a": a, "d": d}
    for op in ("&&", "||", "=>"):
        _same(E.Binary(op, x, y, BOOL), env)
    _same(E.Unary("!", x, BOOL), env)
    _same(E.Ite(x, _var("a", INT), _var("d", DOUBLE), DOUBLE), env)
    _same(E.Unary("-", _var("a", INT), INT), env)
    for op in ("==", "!="):  # within TOLERANCE: 0.1 + 0.2 == 0.3
        _same(E.Binary(op, _var("d", DOUBLE), E.Lit(0.3, DOUBLE), BOOL), env)
