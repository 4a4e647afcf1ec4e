"""The expression kernel computes what Storm computes: random expressions over every
operator (integers and doubles, negative, zero and large; booleans), evaluated by afsmc's
kernel, the checks' vectorised evaluation, the simulator's closures and the explorer's, and
by Storm's model builder, agree in every state.

The oracle is plain stormpy on a hand-built PRISM model: from its initial state it moves to
one state per assignment of the variables x0, x1, x2, where each integer or double
expression is the state reward of a reward structure and each boolean one a label; the
expressions are printed by afsmc's PRISM printer. Every integer is written `z + c` (or
`z - c`) with the state variable z = 0, so that Storm computes it in its model builder, as
it computes a model's guards and updates, rather than folding it when it parses the model.
Every double is a binary fraction written `(z + k) / 2^j`: Storm's builder reads most
decimal literals a few units in the last place off (16384.0 as 16383.999999999998, 0.001
as 0.0009999999999999998, -94.3305 as -94.33049999999997), which would hide what its
operators compute. And the base of a `pow` that is a negation, `pow(-a, b)`, is written
`pow(z - a, b)`: Storm's sparse builder computes `pow(-a, b)` as `-(a^b)` (`pow(-2.0, 2.0)`
is -4 there, 4 in its symbolic engines); afsmc's backends write integer powers so that
Storm never sees such a base (afsmc.backends.storm_safe).

Where the comparison would be meaningless it is left out, for reasons the kernel documents:
an undefined value (a division or mod by zero, `pow(0, k)` with k < 0, a NaN: the checks
refuse them, E306), an integer beyond 2^53 (Storm's builder computes integers in doubles;
the checks refuse what leaves 64 bits, E307) and two doubles within the kernel's
tolerance of each other but not equal (the kernel calls them equal; Storm's builder compares
its doubles exactly). Storm's `pow` of doubles is not the C library's: it may differ in the
last place (pow(0.5, -0.609375) is 1.5255981507445384 there, 1.5255981507445382 in
numpy), so doubles agree to a relative 1e-12, and a comparison, `floor` or `ceil` that such
a difference could decide is left out as well. Nor is `pow(pow(a, b), c)` compared: Storm's
builder computes it as `pow(a, b * c)`, which is another number where a < 0 (pow(pow(-1,
1e9), 2^-20) is NaN there, though pow(-1, 1e9) alone is 1) or where `pow(a, b)` underflows
(pow(pow(2, -1e12), 2^-80) is 0.99999999999943 there, 0 in IEEE arithmetic).
"""

from __future__ import annotations

import json
import math
from pathlib import Path
from typing import Any

import numpy as np
import pytest
import stormpy
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from afsmc.backends.prism import PrismPrinter
from afsmc.model import expr as E
from afsmc.model import kernel
from afsmc.model.evaluate import Env, EvalError, evaluate
from afsmc.model.expr import Type
from tests.unit.model.exprgen import VARS, assignments, expressions, same, subvalues
from tests.unit.model.test_kernel import evaluators, undefined_constant_part

EXACT = 2**53  # Storm's builder computes integers exactly up to here (doubles)
RELATIVE = 1e-12  # Storm's `pow` (its own) may be an ulp off the C library's


def _storm_text(e: E.Expr) -> str:
    """`e` in PRISM, every number computed by Storm's builder (see the module docstring)."""
    z = E.VarRef("z", Type.INT)

    def unfold(n: E.Expr) -> E.Expr | None:
        if isinstance(n, E.Call) and n.func == "pow" and isinstance(n.args[0], E.Unary):
            base = n.args[0]  # -a as z - a: see the module docstring
            minus = E.Binary("-", z, base.operand, base.type)
            return E.Call("pow", (minus, n.args[1]), n.type)
        if not isinstance(n, E.Lit) or n.type is Type.BOOL:
            return None
        if n.type is Type.DOUBLE:  # k / 2^j, written with integers only
            scale = next(2**j for j in range(64) if (n.value * 2**j).is_integer())
            k = E.Lit(int(n.value * scale), Type.INT)
            return E.Binary("/", unfold(k), E.Lit(scale, Type.INT), Type.DOUBLE)
        if n.value < 0:
            return E.Binary("-", z, E.Lit(-n.value, Type.INT), Type.INT)
        return E.Binary("+", z, n, Type.INT)

    return PrismPrinter({}).show(E.transform(e, unfold), 0)


def _storm_values(exprs: list[E.Expr], states: list[dict[str, int]],
                  tmp: Path) -> list[dict[tuple[int, ...], Any]]:
    """Each expression's value in each assignment, by Storm's sparse model builder."""
    lo = {n: min(0, *(s[n] for s in states)) for n in VARS}
    hi = {n: max(0, *(s[n] for s in states)) for n in VARS}
    moves = " + ".join(f"1/{len(states)} : (s'=1)" + "".join(f" & ({n}'={s[n]})" for n in VARS)
                       for s in states)
    lines = ["dtmc", "module m", "  s : [0..1] init 0;", "  z : [0..1] init 0;"]
    lines += [f"  {n} : [{lo[n]}..{hi[n]}] init 0;" for n in VARS]
    lines += [f"  [] s = 0 -> {moves};", "  [] s = 1 -> true;", "endmodule"]
    for i, e in enumerate(exprs):
        text = _storm_text(e)
        if e.type is Type.BOOL:
            lines.append(f'label "e{i}" = {text};')
        else:
            lines.append(f'rewards "e{i}" s = 1 : {text}; endrewards')
    path = tmp / "kernel.prism"
    path.write_text("\n".join(lines) + "\n")
    opts = stormpy.BuilderOptions()
    opts.set_build_state_valuations()
    opts.set_build_all_labels()
    opts.set_build_all_reward_models()
    model = stormpy.build_model(stormpy.parse_prism_program(str(path)), options=opts)
    where: dict[tuple[int, ...], int] = {}
    for sid in range(model.nr_states):
        v = json.loads(str(model.state_valuations.to_json(sid)))
        if v["s"] == 1:
            where[tuple(int(v[n]) for n in VARS)] = sid
    out: list[dict[tuple[int, ...], Any]] = []
    for i, e in enumerate(exprs):
        if e.type is Type.BOOL:
            holds = model.labeling.get_states(f"e{i}")
            out.append({k: sid in holds for k, sid in where.items()})
        else:
            rewards = model.reward_models[f"e{i}"].state_rewards
            out.append({k: rewards[sid] for k, sid in where.items()})
    return out


def _comparable(e: E.Expr, state: dict[str, int]) -> bool:
    """Whether Storm's value of `e` in `state` is the kernel's to compare (module docstring)."""
    env = Env(vars=state)
    try:
        v = evaluate(e, env)
    except EvalError:
        return False
    if isinstance(v, float) and not math.isfinite(v):
        return False
    for n in E.walk(e):
        try:
            part = evaluate(n, env)
        except EvalError:
            continue  # in a branch that is not taken (the whole is defined)
        if isinstance(part, float) and not math.isfinite(part):
            return False
        if isinstance(part, (int, float)) and abs(part) > EXACT:
            return False
        if isinstance(n, E.Binary) and n.op in ("==", "!=", "<", "<=", ">", ">="):
            a, b = (evaluate(x, env) for x in (n.left, n.right))
            if a != b and _near(a, b, _has_pow(n)):
                return False
        if (isinstance(n, E.Call) and n.func == "pow" and isinstance(n.args[0], E.Call)
                and n.args[0].func == "pow"):
            return False  # pow(pow(a, b), c): see the module docstring
        if isinstance(n, E.Call) and n.func in ("floor", "ceil") and _has_pow(n):
            a = evaluate(n.args[0], env)
            if a != round(a) and _near(a, round(a), True):
                return False
    return all(abs(p) <= EXACT for p in subvalues(e, env) if isinstance(p, int))


def _near(a: float, b: float, powers: bool) -> bool:
    """Within the kernel's tolerance, or (`powers`) within Storm's error in `pow`, of each
    other."""
    return abs(a - b) <= max(kernel.TOLERANCE, RELATIVE * max(abs(a), abs(b)) if powers else 0)


def _has_pow(e: E.Expr) -> bool:
    return any(isinstance(n, E.Call) and n.func == "pow" for n in E.walk(e))


def _close(got: Any, want: Any) -> bool:
    """The same value; for doubles within Storm's error in `pow` (module docstring)."""
    if isinstance(got, (bool, np.bool_)) or (isinstance(got, (int, np.integer))
                                            and float(want).is_integer()):
        return same(got, want)
    return same(got, want) or math.isclose(float(got), float(want), rel_tol=RELATIVE)


batches = st.tuples(st.lists(st.one_of(expressions(Type.INT), expressions(Type.DOUBLE),
                                       expressions(Type.BOOL)), min_size=1, max_size=6),
                    st.lists(assignments, min_size=1, max_size=4,
                             unique_by=lambda s: tuple(s[n] for n in VARS)))


@pytest.mark.storm
# derandomized, as the fuzz tests are: CI runs the same examples every time. (A random draw
# found mod(1, pow(257, -8)): the two pows differ in their last bit, and the remainder of 1
# by 5e-20 turns that into a relative difference of 60%. Storm's pow is not correctly
# rounded; that comparison needs an error bound this test does not have.)
@settings(max_examples=100, deadline=None, derandomize=True, database=None,
          suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large,
                                 HealthCheck.function_scoped_fixture])
@given(batches)
def test_the_kernel_computes_what_storm_computes(tmp_path: Path,
                                                batch: tuple[list[E.Expr], list[dict[str, int]]]) -> None:
    exprs, states = batch
    storm = _storm_values(exprs, states, tmp_path)
    for e, by_storm in zip(exprs, storm, strict=True):
        ours = evaluators(e, states)
        for i, state in enumerate(states):
            if not _comparable(e, state):
                continue
            want = by_storm[tuple(state[n] for n in VARS)]
            for name in ("kernel", "checks", "simulator", "explorer"):
                if name == "checks" and undefined_constant_part(e):
                    continue
                got = ours[name][i]
                assert _close(got, want), (name, _storm_text(e), state, got, want)


def _every_operator() -> list[E.Expr]:
    """One expression per operator (and per kind of operand), over x0 and x1."""
    x, y = E.VarRef("x0", Type.INT), E.VarRef("x1", Type.INT)
    half = E.Binary("/", x, E.Lit(2, Type.INT), Type.DOUBLE)
    out: list[E.Expr] = [E.Unary("-", x, Type.INT), E.Unary("-", half, Type.DOUBLE)]
    for op in ("+", "-", "*"):
        out += [E.Binary(op, x, y, Type.INT), E.Binary(op, half, y, Type.DOUBLE)]
    out.append(E.Binary("/", x, y, Type.DOUBLE))
    for op in ("==", "!=", "<", "<=", ">", ">="):
        out += [E.Binary(op, x, y, Type.BOOL), E.Binary(op, half, y, Type.BOOL)]
    px, py = (E.Binary(">", v, E.Lit(0, Type.INT), Type.BOOL) for v in (x, y))
    out += [E.Binary(op, px, py, Type.BOOL) for op in ("&&", "||", "=>")]
    out += [E.Unary("!", px, Type.BOOL), E.Ite(px, x, half, Type.DOUBLE)]
    for fn in ("min", "max"):
        out += [E.Call(fn, (x, y), Type.INT), E.Call(fn, (half, y, x), Type.DOUBLE)]
    out += [E.Call(fn, (half,), Type.INT) for fn in ("floor", "ceil")]
    out += [E.Call("mod", (x, y), Type.INT),
            E.Call("pow", (x, E.Call("mod", (y, E.Lit(4, Type.INT)), Type.INT)), Type.INT),
            E.Call("pow", (x, E.Lit(-2, Type.INT)), Type.INT),
            E.Call("pow", (E.Call("max", (half, E.Lit(0.5, Type.DOUBLE)), Type.DOUBLE),
                           E.Binary("/", y, E.Lit(3, Type.INT), Type.DOUBLE)), Type.DOUBLE)]
    return out


@pytest.mark.storm
def test_every_operator_computes_what_storm_computes(tmp_path: Path) -> None:
    """The operators one by one, over negative, zero and positive operands: every value is
    compared (none is left out), and equal."""
    exprs = _every_operator()
    states = [{"x0": a, "x1": b, "x2": 0} for a in (-7, 0, 6, 2**40 + 3) for b in (-3, 5)]
    storm = _storm_values(exprs, states, tmp_path)
    for e, by_storm in zip(exprs, storm, strict=True):
        ours = evaluators(e, states)
        compared = [i for i, state in enumerate(states) if _comparable(e, state)]
        # left out: pow(0, -2) (infinite), pow(2^40 + 3, 3) (beyond 64 bits)
        assert len(compared) >= len(states) - 2, _storm_text(e)
        for i in compared:
            want = by_storm[tuple(states[i][n] for n in VARS)]
            for name in ("kernel", "checks", "simulator", "explorer"):
                assert _close(ours[name][i], want), (name, _storm_text(e), states[i])


def test_storm_text_writes_every_number_as_computed_by_the_builder() -> None:
    e = E.Binary("+", E.Lit(-3, Type.INT), E.Call("pow", (E.VarRef("x0", Type.INT), E.Lit(2, Type.INT)),
                                                 Type.INT), Type.INT)
    assert _storm_text(e) == "z - 3 + pow(x0, z + 2)"
    assert _storm_text(E.Lit(-2.5, Type.DOUBLE)) == "(z - 5) / 2"
    assert np.isnan(kernel.CALLS["pow"].scalar(-8.0, 1 / 3))
