"""User-facing wording of numbers and nouns, written once for every stage and command.

- `literal(v)`: a value as the language and `--const` write it (`true`, `3`, `0.25`).
- `short(v, digits)`: a measured or computed number in a sentence (`0.6351`), `n/a` for none.
- `num(v)`: a value in a results table (6 significant digits, large ones in fixed point).
- `count(n)`: a state or byte count for progress lines (`12.3 M`).
- `article(word)` and `plural(n, word)`: 'an int', '3 points'.

The IR's own printer (`afsmc.model.pretty.number`) is not here: it writes doubles as PRISM
and JANI need them (`2.0`, never `2`), which is a backend's format, not wording.
"""

from __future__ import annotations

import math
from decimal import Decimal


def literal(v: object) -> str:
    """A constant's value as `--const` takes it and afsm writes it: `true`, not Python's
    `True`; an int as digits; a double in Python's shortest round-trip form. A string is
    taken to be written already."""
    if isinstance(v, str):
        return v
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, int):
        return str(v)
    return repr(float(v))  # type: ignore[arg-type]


def short(v: object, digits: int = 4) -> str:
    """A number to `digits` significant digits; `n/a` for a missing or non-numeric value
    (a bool, None, NaN)."""
    if isinstance(v, bool) or not isinstance(v, (int, float)) or math.isnan(v):
        return "n/a"
    return f"{v:.{digits}g}"


def num(v: float | None) -> str:
    """A value in a table: 6 significant digits, large ones in fixed point."""
    if v is None:
        return "-"
    if v != v or v in (float("inf"), float("-inf")):
        return str(v)
    if abs(v) >= 1e5:  # an expected reward of 3000000000.002 read "3e+09"
        return f"{v:.4f}".rstrip("0").rstrip(".")
    return f"{v:.6g}"


def count(n: float) -> str:
    """12_345_678 -> '12.3 M'; from 10^12 on, powers of ten: 2e19 -> '2.0e19'."""
    if isinstance(n, float) and not math.isfinite(n):
        return str(n)
    if n >= 1e12:
        mantissa, exponent = f"{Decimal(n):.1e}".split("e")  # Decimal: ints beyond floats too
        return f"{mantissa}e{int(exponent)}"
    if n >= 1e9:
        return f"{n / 1e9:.1f} G"
    if n >= 1e6:
        return f"{n / 1e6:.1f} M"
    if n >= 1e4:
        return f"{n / 1e3:.0f} k"
    return f"{int(n):,}"


def article(word: str) -> str:
    """'a' or 'an' for `word`, by its first letter: 'an int', 'a bool', 'an action'."""
    return "an" if word[:1] in "aeiou" else "a"


def plural(n: int, word: str, many: str | None = None) -> str:
    """'1 point', '3 points'; `many` for an irregular plural."""
    return f"{n} {word if n == 1 else (many or word + 's')}"
