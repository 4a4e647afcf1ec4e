"""Find a state of one mode that satisfies a predicate, exactly.

Every semantic check is phrased as "is there a state where ... ?". The answer is exact:
over the product of the domains of the variables the predicate reads, enumerated with
numpy when that product is small enough, and otherwise decided by the Z3 SMT solver.
Reachability is not considered: a check speaks of every state of the mode.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass
from fractions import Fraction
from typing import Any

import numpy as np

from afsmc.model import expr as E
from afsmc.model import ir
from afsmc.model.evaluate import Env, EvalError, evaluate
from afsmc.model.pretty import number
from afsmc.model.semantics import inline, stuck

ENUMERATION_LIMIT = 4_000_000  # states enumerated at once before switching to Z3


class Undecided(Exception):
    """Neither enumeration nor the SMT solver could decide a question."""


@dataclass(frozen=True)
class Witness:
    mode: str
    values: tuple[tuple[str, int | bool], ...]  # (display name, value) of the variables read

    def __str__(self) -> str:
        parts = [f"mode = {self.mode}"] + [f"{n} = {number(v)}" for n, v in self.values]
        return ", ".join(parts)

    def as_dict(self) -> dict[str, int | bool | str]:
        return {"mode": self.mode} | dict(self.values)


def find(model: ir.Model, mode: int, pred: E.Expr,
         consts: Mapping[str, Any] | None = None) -> Witness | None:
    """A state with the given mode where `pred` holds, or None if there is none."""
    return _search(model, mode, *_prepare(model, pred, consts))


def exists(model: ir.Model, mode: int, pred: E.Expr,
           consts: Mapping[str, Any] | None = None) -> bool:
    """Whether some state of the mode satisfies `pred`. Predicates that hold somewhere (an
    action that can fire) usually hold at a few typical values too, so those are tried
    first; only a miss pays for the exhaustive search."""
    inlined, variables, values = _prepare(model, pred, consts)
    for picks in (_typical, _ends, _init):  # fewer values per variable when there are many
        axes = [np.array(sorted(picks(v))) for v in variables]
        if math.prod(len(a) for a in axes) <= SAMPLE_LIMIT:
            if _enumerate(model, mode, inlined, variables, values, axes) is not None:
                return True  # a sampled state is a state: the answer is exact
            break
    return _search(model, mode, inlined, variables, values) is not None


def deadlock_witness(model: ir.Model, mode: int) -> Witness | None:
    """A state of the (non-final) mode where no action is enabled, or None. The lowering
    asks too (it makes such states absorbing), so the answer is kept on the model."""
    memo = model.memo.deadlocks
    if mode not in memo:
        memo[mode] = find(model, mode, stuck(model, mode))
    return memo[mode]


def _prepare(model: ir.Model, pred: E.Expr, consts: Mapping[str, Any] | None
             ) -> tuple[E.Expr, list[ir.Variable], dict[str, Any]]:
    """The predicate inlined, the variables it reads (in declaration order), the constants."""
    inlined = inline(pred, model)
    # (the model's own dict unless some values are given: a copy per question would make
    # a model of N constants and N actions cost N^2)
    values = model.const_values | dict(consts) if consts else model.const_values
    order = {v.name: i for i, v in enumerate(model.variables)}
    names = sorted(E.vars_read(inlined), key=order.__getitem__)
    return inlined, [model.variable(n) for n in names], values


def _search(model: ir.Model, mode: int, pred: E.Expr, variables: list[ir.Variable],
            values: Mapping[str, Any]) -> Witness | None:
    if math.prod(v.size for v in variables) <= ENUMERATION_LIMIT:
        return _enumerate(model, mode, pred, variables, values)
    return _smt(model, mode, pred, variables, values)


SAMPLE_LIMIT = 50_000  # states tried before the exhaustive search


def _typical(v: ir.Variable) -> set[Any]:
    if v.type is not E.Type.INT:
        return {False, True}
    near = {v.lo, v.hi, v.lo + 1, v.hi - 1, (v.lo + v.hi) // 2, int(v.init)}
    return {x for x in near if v.lo <= x <= v.hi}


def _ends(v: ir.Variable) -> set[Any]:
    return {False, True} if v.type is not E.Type.INT else {v.lo, v.hi, int(v.init)}


def _init(v: ir.Variable) -> set[Any]:
    return {v.init}


def _enumerate(model: ir.Model, mode: int, pred: E.Expr, variables: list[ir.Variable],
               consts: Mapping[str, Any], axes: list[Any] | None = None) -> Witness | None:
    if axes is None:
        axes = [np.arange(v.lo, v.hi + 1) if v.type is E.Type.INT else np.array([False, True])
                for v in variables]
    # Open grids broadcast against each other: no copy of the full product per variable.
    grids = np.meshgrid(*axes, indexing="ij", sparse=True) if axes else []
    env_vars = {v.name: g for v, g in zip(variables, grids, strict=True)}
    env = Env(vars=env_vars, mode=mode, consts=consts)
    with np.errstate(all="ignore"):
        try:
            hit = np.asarray(evaluate(pred, env), dtype=bool)
        except (EvalError, ArithmeticError, ValueError):
            # never "no witness" by accident: let the solver decide instead
            return _smt(model, mode, pred, variables, consts)
    shape = tuple(len(a) for a in axes)
    if hit.shape != shape:  # (a predicate that reads no variable, or not all of them)
        hit = np.broadcast_to(hit, shape)
    if not hit.any():
        return None
    index = np.unravel_index(int(np.argmax(hit)), shape) if shape else ()
    vals = []
    for v, axis, i in zip(variables, axes, index, strict=True):
        raw = axis[i]
        vals.append((v.display, bool(raw) if v.type is E.Type.BOOL else int(raw)))
    return Witness(model.mode_by_number(mode).name, tuple(vals))


def _smt(model: ir.Model, mode: int, pred: E.Expr, variables: list[ir.Variable],
         consts: Mapping[str, Any]) -> Witness | None:
    import z3

    zvars: dict[str, Any] = {}
    solver = z3.Solver()
    solver.set("timeout", 20_000)
    for v in variables:
        if v.type is E.Type.BOOL:
            zvars[v.name] = z3.Bool(v.name)
        else:
            zvars[v.name] = z3.Int(v.name)
            solver.add(zvars[v.name] >= v.lo, zvars[v.name] <= v.hi)
    try:
        solver.add(_z3(pred, zvars, mode, consts))
    except (EvalError, z3.Z3Exception) as exc:
        raise Undecided(f"cannot translate it for the SMT solver ({exc})") from None
    answer = solver.check()
    if answer == z3.unknown:
        raise Undecided(f"the SMT solver gave up ({solver.reason_unknown()})")
    if answer != z3.sat:
        return None
    model_z3 = solver.model()
    vals = []
    for v in variables:
        val = model_z3.eval(zvars[v.name], model_completion=True)
        vals.append((v.display, z3.is_true(val) if v.type is E.Type.BOOL else val.as_long()))
    return Witness(model.mode_by_number(mode).name, tuple(vals))


def _z3(e: E.Expr, zvars: dict[str, Any], mode: int, consts: Mapping[str, Any]) -> Any:
    import z3

    def lit(v: Any) -> Any:
        if isinstance(v, bool):
            return z3.BoolVal(v)
        if isinstance(v, int):
            return z3.IntVal(v)
        return z3.RealVal(Fraction(v).limit_denominator(10**12))

    def real(x: Any) -> Any:
        # ToReal accepts integer terms only: a double (a real literal, constant or
        # quotient) already is one.
        return z3.ToReal(x) if z3.is_int(x) else x

    def go(n: E.Expr) -> Any:
        if isinstance(n, E.Lit):
            return lit(n.value)
        if isinstance(n, E.VarRef):
            return zvars[n.name]
        if isinstance(n, E.ConstRef):
            return lit(consts[n.name])
        if isinstance(n, E.ModeVal):
            return z3.IntVal(n.number)
        if isinstance(n, E.CurrentMode):
            return z3.IntVal(mode)
        if isinstance(n, E.Unary):
            x = go(n.operand)
            return z3.Not(x) if n.op == "!" else -x
        if isinstance(n, E.Ite):
            return z3.If(go(n.cond), go(n.then), go(n.other))
        if isinstance(n, E.Binary):
            a, b = go(n.left), go(n.right)
            ops: dict[str, Any] = {
                "&&": lambda: z3.And(a, b), "||": lambda: z3.Or(a, b),
                "=>": lambda: z3.Implies(a, b), "+": lambda: a + b, "-": lambda: a - b,
                "*": lambda: a * b, "/": lambda: real(a) / real(b),
                "==": lambda: a == b, "!=": lambda: a != b, "<": lambda: a < b,
                "<=": lambda: a <= b, ">": lambda: a > b, ">=": lambda: a >= b}
            return ops[n.op]()
        if isinstance(n, E.Call):
            args = [go(a) for a in n.args]
            if n.func in ("min", "max"):
                out = args[0]
                for a in args[1:]:
                    out = z3.If(a < out, a, out) if n.func == "min" else z3.If(a > out, a, out)
                return out
            if n.func == "floor":
                return z3.ToInt(real(args[0]))
            if n.func == "ceil":
                return -z3.ToInt(-real(args[0]))
            if n.func == "mod":  # Storm's (evaluate.storm_mod); z3's % is Euclidean
                x, y = args
                return z3.If(x >= 0, x % y, y - ((-x) % y))
            if n.func == "pow":
                return args[0] ** args[1]
        raise EvalError(f"cannot translate {type(n).__name__} for the SMT solver")

    return go(e)
