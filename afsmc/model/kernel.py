"""What every operator of afsmc's expressions computes, stated once.

Each operator has two forms, defined side by side and tested equal element by element
(tests/unit/model/test_kernel.py):

- `scalar`: one value (Python numbers, or numpy scalars): the checks' folding of
  constants and of state-free parts, the resolver, the reductions. Integers are exact.
- `vector`: numpy arrays of many states (or runs) at once, scalars broadcast: the
  checks' enumeration, the simulator's closures (:mod:`afsmc.sim.compile`) and the
  explorer's (:mod:`afsmc.verify.explorer.explore_eval`). Integers are int64.

:func:`afsmc.model.evaluate.evaluate` walks an expression with them; the simulator and
the explorer compile closures that call them. So an operator changes here and nowhere
else.

The semantics are PRISM's as Storm computes them (checked against Storm's model builder
by the differential test tests/unit/model/test_kernel_storm.py):

- `+ - *` of integers give integers, `/` is real division (`7 / 2` is 3.5; the language
  has no integer division and no `round`: `floor(a / b)` and `floor(x + 0.5)` say them);
- `floor` and `ceil` give integers; `min` and `max` of integers an integer, with a
  double among the arguments a double;
- `pow` of integers with an exponent >= 0 is an integer; with a negative exponent a
  fraction (`pow(2, -1)` is 0.5: the checks refuse assigning it to an integer, E308);
  with a double argument a double, the C library's `pow` (`pow(-8.0, 1/3)` is NaN);
- `mod(a, b)` is Storm's (see :func:`storm_mod`): not numpy's, not Python's;
- `==` and `!=` of doubles treat values within `TOLERANCE` as equal (`0.1 + 0.2 == 0.3`
  holds, as it does where Storm folds constants, in exact rationals); integers compare
  exactly. Storm's model builder compares its doubles exactly, so within `TOLERANCE` of a
  tie the two may disagree; `<`, `<=`, `>`, `>=` have no tolerance;
- `&&`, `||`, `=>` and `!` on booleans; `c ? a : b` picks per state.

Undefined values: a division or `mod` by zero. In the scalar form they raise `EvalError`;
in the vector form they are NaN in the states concerned, so that one such state (often
excluded by a guard, a `&&` or an untaken `?:` branch) does not stop the others. The checks
(E306) refuse an expression whose undefined value would be used; `pow(0, k)` with k < 0
is infinite, as in Storm, and refused by the same check.

Storm's model builder computes integers in doubles: exactly up to 2^53, and beyond that
rounded, where the kernel's integers stay exact up to 2^63.

Integers beyond 64 bits: the scalar `pow` raises `RangeError` (its value could be
astronomically large); scalar `+ - *` are exact Python integers and their callers judge
the value (`afsmc.model.limits.unrepresentable`); the vector forms wrap around as int64
does. The checks refuse an expression whose values leave 64 bits (E307), so no model that
passes them reaches a wrap-around.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np

from afsmc.model.expr import Type

Array = Any  # a numpy array or a scalar

# Doubles closer than this are equal (== and !=).
TOLERANCE = 1e-12


class EvalError(Exception):
    """An expression cannot be evaluated (division by zero, a missing name)."""


class RangeError(EvalError):
    """A value beyond what PRISM and Storm compute with (a 64-bit integer)."""


@dataclass(frozen=True)
class Op:
    """An operator's two forms: `scalar` on single values, `vector` on arrays."""

    scalar: Callable[..., Any]
    vector: Callable[..., Any]


# ---- equality of doubles ------------------------------------------------------------

def _floating(v: Any) -> bool:
    """A double (or doubles). (dtype.kind, not np.issubdtype: the simulator asks it at
    every `==` of every step, and issubdtype takes a microsecond.)"""
    if isinstance(v, (np.ndarray, np.generic)):
        return v.dtype.kind == "f"
    return isinstance(v, float)


def _eq_scalar(a: Any, b: Any) -> bool:
    if _floating(a) or _floating(b):
        return bool(a == b or abs(a - b) <= TOLERANCE)  # a == b: inf == inf
    return bool(a == b)


def _eq_vector(a: Array, b: Array) -> Array:
    if _floating(a) or _floating(b):
        with np.errstate(invalid="ignore"):  # inf - inf is NaN: equal by a == b
            return np.equal(a, b) | (np.abs(np.subtract(a, b)) <= TOLERANCE)
    return np.equal(a, b)


def _ne_scalar(a: Any, b: Any) -> bool:
    return not _eq_scalar(a, b)


def _ne_vector(a: Array, b: Array) -> Array:
    return np.logical_not(_eq_vector(a, b))


# ---- division and mod: undefined by zero --------------------------------------------

def _div_scalar(a: Any, b: Any) -> Any:
    if b == 0:
        raise EvalError("division by zero")
    return float(np.true_divide(a, b))  # numpy's: a double also from np.int64 operands


def _div_vector(a: Array, b: Array) -> Array:
    return _masked(np.true_divide, a, b)


def storm_mod(a: Array, b: Array) -> Array:
    """`mod(a, b)` of integers as Storm computes it (sparse and symbolic engines, from
    PRISM and from JANI alike): the C++ remainder (truncated division, the sign of `a`),
    plus `b` where `a` is negative. So mod(7, 3) = 1, mod(-7, 3) = 2, mod(7, -3) = 1,
    mod(-7, -3) = -4 and mod(-6, 3) = 3: not numpy's (sign of `b`) nor Python's. `b` != 0."""
    if isinstance(a, (int, np.integer)) and isinstance(b, (int, np.integer)):
        x, y = int(a), int(b)  # exact on scalars
        r = abs(x) % abs(y)
        return r if x >= 0 else y - r
    if np.ndim(a) == 0 and np.ndim(b) == 0:  # a fraction (`mod(pow(2, -1), 3)`)
        with np.errstate(invalid="ignore"):  # mod(inf, 3) is NaN
            rem = float(np.fmod(a, b))
        return rem if a >= 0 else rem + float(b)
    left, right = np.asarray(a), np.asarray(b)
    rem = np.fmod(left, right)
    return np.where(left >= 0, rem, rem + right)


def _mod_scalar(a: Any, b: Any) -> Any:
    if b == 0:
        raise EvalError("mod by zero")
    return storm_mod(a, b)


def _mod_vector(a: Array, b: Array) -> Array:
    return _masked(storm_mod, a, b)


def _masked(fn: Callable[[Array, Array], Array], left: Array, right: Array) -> Array:
    """`fn(left, right)`, NaN where `right` is 0."""
    r = np.asarray(right)
    zero = r == 0
    if not np.any(zero):
        return fn(left, right)
    # `fn` sees 1 where `right` is 0, so it needs no ufunc `where=` (storm_mod has none)
    return np.where(zero, np.nan, fn(left, np.where(zero, 1, r)))


# ---- rounding -------------------------------------------------------------------------

def _to_int_scalar(v: Any) -> int:
    if not math.isfinite(v):
        raise EvalError("not a number")
    return int(v)


def _to_int_vector(v: Array) -> Array:
    arr = np.asarray(v)
    if np.issubdtype(arr.dtype, np.floating) and not np.all(np.isfinite(arr)):
        return arr  # keeps NaN where a division by zero was (see _masked)
    return arr.astype(np.int64)


def _floor_scalar(v: Any) -> int:
    return _to_int_scalar(math.floor(v) if math.isfinite(v) else v)


def _floor_vector(v: Array) -> Array:
    return _to_int_vector(np.floor(v))


def _ceil_scalar(v: Any) -> int:
    return _to_int_scalar(math.ceil(v) if math.isfinite(v) else v)


def _ceil_vector(v: Array) -> Array:
    return _to_int_vector(np.ceil(v))


# ---- min and max ----------------------------------------------------------------------

def _pick_scalar(smaller: bool, args: tuple[Any, ...]) -> Any:
    """numpy's minimum/maximum folded over `args`: NaN wins, a double makes a double."""
    out = args[0]
    for a in args[1:]:
        if out != out or a != a:  # NaN
            out = math.nan
        elif (a < out) if smaller else (a > out):
            out = a
        if isinstance(a, float) or isinstance(out, float):
            out = float(out)
    return out


def _min_scalar(*args: Any) -> Any:
    return _pick_scalar(True, args)


def _max_scalar(*args: Any) -> Any:
    return _pick_scalar(False, args)


def _min_vector(*args: Array) -> Array:
    out = args[0]
    for a in args[1:]:
        out = np.minimum(out, a)
    return out


def _max_vector(*args: Array) -> Array:
    out = args[0]
    for a in args[1:]:
        out = np.maximum(out, a)
    return out


# ---- pow ------------------------------------------------------------------------------

def _int_pow_scalar(base: Any, power: Any) -> Any:
    """pow of two integer-typed values: exact when the exponent is >= 0, else a fraction
    (and a fraction where an integer-typed argument is one: `pow(pow(2, -1), 2)`)."""
    if _floating(base) or _floating(power) or power < 0:
        return _real_pow_scalar(base, power)
    b, k = int(base), int(power)
    if (abs(b) > 1 and k >= 64) or not -(2**63) <= b**k < 2**63:
        raise RangeError(f"pow({b}, {k}) does not fit in a 64-bit integer")
    return b**k


def _int_pow_vector(base: Array, power: Array) -> Array:
    exp = np.asarray(power)
    if _floating(base) or _floating(exp) or np.any(exp < 0):  # a fraction, as Storm computes it
        return _real_pow_vector(base, exp)
    return np.power(np.asarray(base, dtype=np.int64), exp.astype(np.int64))


# np.float_power, not np.power: numpy's power of two float arrays takes a faster route (SIMD)
# that is off by a unit in the last place in about 5% of cases, and not the route of one
# value, so the scalar and vector forms would disagree. float_power is the C library's pow.

def _real_pow_scalar(base: Any, power: Any) -> float:
    with np.errstate(all="ignore"):  # pow(0, -1) is inf, pow(-8, 1/3) NaN: see the docstring
        return float(np.float_power(float(base), power))


def _real_pow_vector(base: Array, power: Array) -> Array:
    return np.float_power(base, power)


# ---- the tables -------------------------------------------------------------------------

UNARY: dict[str, Op] = {
    "-": Op(lambda v: -v, np.negative),
    "!": Op(lambda v: not v, np.logical_not),
}

BINARY: dict[str, Op] = {
    "+": Op(lambda a, b: a + b, np.add),
    "-": Op(lambda a, b: a - b, np.subtract),
    "*": Op(lambda a, b: a * b, np.multiply),
    "/": Op(_div_scalar, _div_vector),
    "==": Op(_eq_scalar, _eq_vector),
    "!=": Op(_ne_scalar, _ne_vector),
    "<": Op(lambda a, b: bool(a < b), np.less),
    "<=": Op(lambda a, b: bool(a <= b), np.less_equal),
    ">": Op(lambda a, b: bool(a > b), np.greater),
    ">=": Op(lambda a, b: bool(a >= b), np.greater_equal),
    "&&": Op(lambda a, b: bool(a and b), np.logical_and),
    "||": Op(lambda a, b: bool(a or b), np.logical_or),
    "=>": Op(lambda a, b: bool(not a or b), lambda a, b: np.logical_or(np.logical_not(a), b)),
}

CALLS: dict[str, Op] = {
    "min": Op(_min_scalar, _min_vector),
    "max": Op(_max_scalar, _max_vector),
    "floor": Op(_floor_scalar, _floor_vector),
    "ceil": Op(_ceil_scalar, _ceil_vector),
    "pow": Op(_real_pow_scalar, _real_pow_vector),  # a double argument
    "mod": Op(_mod_scalar, _mod_vector),
}
INT_POW = Op(_int_pow_scalar, _int_pow_vector)  # pow of two integers


def unary(op: str) -> Op:
    try:
        return UNARY[op]
    except KeyError:
        raise EvalError(f"unknown operator {op}") from None


def binary(op: str) -> Op:
    try:
        return BINARY[op]
    except KeyError:
        raise EvalError(f"unknown operator {op}") from None


def call(func: str, typ: Type) -> Op:
    """The function `func` of a call whose (resolved) type is `typ`."""
    if func == "pow" and typ is Type.INT:
        return INT_POW
    try:
        return CALLS[func]
    except KeyError:
        raise EvalError(f"unknown function {func}") from None


def ite_vector(cond: Array, then: Array, other: Array) -> Array:
    """`cond ? then : other` per state."""
    return np.where(cond, then, other)
