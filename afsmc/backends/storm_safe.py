"""Expressions that Storm computes wrongly, rewritten into equal ones it computes right.

Both Storm backends (PRISM and JANI) print every expression through `signed_pow`.

Storm's sparse engine computes an integer `pow(b, k)` whose base it folds to a negative
constant (`pow(0 - 2, x)`, `pow(B, x)` with `B = -2`, `pow(a - 4, x)` with `a` never
written) as `-(|b| ^ k)`: `pow(0 - 2, 0)` is -1 and `pow(0 - 2, 2)` is -4, from PRISM and
from JANI alike, without a word. Its symbolic engines compute it right, and so does the
sparse engine for a base it does not fold (a variable) and for doubles.
"""

from __future__ import annotations

from afsmc.lower.lowering import Lowered
from afsmc.model import expr as E
from afsmc.model.bounds import bounds

INT = E.Type.INT


def signed_pow(e: E.Expr, low: Lowered) -> E.Expr | None:
    """For an integer `pow(b, k)` whose base may be negative, the equal expression
    `(b < 0 && mod(k, 2) == 1 ? -1 : 1) * pow(max(b, 0 - b), k)`: the base Storm sees is
    never negative, and the sign follows the parity of the exponent (`mod(k, 2)` is 1 for
    every odd `k`, also negative ones, in Storm's `mod` as in any other). None otherwise."""
    if not (isinstance(e, E.Call) and e.func == "pow" and e.type is INT):
        return None
    base, power = e.args
    if _is_abs(base) or bounds(base, low.model, None, low.bounds)[0] >= 0:
        return None
    odd = E.Binary("==", E.Call("mod", (power, E.Lit(2, INT)), INT), E.Lit(1, INT), E.Type.BOOL)
    negative = E.Binary("<", base, E.Lit(0, INT), E.Type.BOOL)
    sign = E.Ite(E.Binary("&&", negative, odd, E.Type.BOOL), E.Lit(-1, INT), E.Lit(1, INT), INT)
    magnitude = E.Call("max", (base, E.Binary("-", E.Lit(0, INT), base, INT)), INT)
    return E.Binary("*", sign, E.Call("pow", (magnitude, power), INT, e.span), INT, e.span)


def _is_abs(e: E.Expr) -> bool:
    """`max(b, 0 - b)`, as `signed_pow` writes it."""
    if not (isinstance(e, E.Call) and e.func == "max" and len(e.args) == 2):
        return False
    b, neg = e.args
    return (isinstance(neg, E.Binary) and neg.op == "-" and neg.left == E.Lit(0, INT)
            and neg.right == b)
