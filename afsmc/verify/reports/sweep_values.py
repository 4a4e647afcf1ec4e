"""The values a sweep takes: `afsmc sweep --const T=0:900:25` and `--bound 0:40:5`.

`parse_values` reads the value grammar (a range `start:stop:step` or a list `a,b,c`, of
numbers or of `false,true`); a value is written back with :func:`afsmc.text.literal`.
"""

from __future__ import annotations

import re
from decimal import Decimal, InvalidOperation
from typing import Literal

from afsmc.text import literal

Kind = Literal["const", "bound"]  # what is swept: an open constant, or the step bound
Number = int | float
MAX_POINTS = 10_000

# A value is an int only as written so (`1e0` and `2.0` are doubles), as verify's --const
# reads it: an int constant swept over `1e0:2` is refused (E208) there too.
_INT = re.compile(r"[+-]?[0-9]+")


def parse_values(text: str) -> list[Number]:
    """`start:stop:step` (stop included when the steps reach it) or `a,b,c` (sorted; a
    value given twice is an error).

    Integers stay integers; decimals are stepped exactly (0:1:0.1 has 11 points); `false,true`
    sweeps a bool constant."""
    text = text.strip()
    if not text:
        raise ValueError("no values")
    words = [part.strip() for part in text.split(",")]
    if any(w in ("true", "false") for w in words):
        return _bools(text, words)
    if ":" in text:
        return _range(text)
    return _list(text)


def _bools(text: str, words: list[str]) -> list[Number]:
    if not all(w in ("true", "false") for w in words):
        raise ValueError(f"mixes true/false with numbers: {text!r}")
    if len(set(words)) < len(words):
        raise ValueError(f"a value is given twice in {text!r}")
    return sorted(w == "true" for w in words)


def _range(text: str) -> list[Number]:
    """`start:stop:step` (or `start:stop`, step 1), stepped exactly in decimal."""
    parts = text.split(":")
    if len(parts) not in (2, 3):
        raise ValueError(f"expected start:stop:step, got {text!r}")
    try:
        start, stop = Decimal(parts[0]), Decimal(parts[1])
        step = Decimal(parts[2]) if len(parts) == 3 else Decimal(1)
    except InvalidOperation:
        raise ValueError(f"expected numbers in start:stop:step, got {text!r}") from None
    if not all(d.is_finite() for d in (start, stop, step)):
        raise ValueError(f"expected finite numbers in start:stop:step, got {text!r}")
    if step <= 0:
        raise ValueError(f"the step of {text!r} must be positive")
    if stop < start:
        raise ValueError(f"{text!r} is empty: stop is below start")
    count = int((stop - start) / step) + 1
    if count > MAX_POINTS:
        many = f"{count:,}" if count < 10**18 else "more than 10^18"  # (a count of 4,300
        raise ValueError(f"{text!r} has {many} points; at most {MAX_POINTS:,}")  # digits or
        # more cannot even be printed)
    whole = all(_INT.fullmatch(x.strip()) for x in parts)
    return [_number(start + i * step, whole) for i in range(count)]


def _list(text: str) -> list[Number]:
    """`a,b,c`: each a finite number, none twice; sorted."""
    out = []
    for part in text.split(","):
        try:
            d = Decimal(part.strip())
        except InvalidOperation:
            raise ValueError(f"not a number: {part.strip()!r}") from None
        if not d.is_finite():
            raise ValueError(f"not a finite number: {part.strip()!r}")
        out.append(_number(d, bool(_INT.fullmatch(part.strip()))))
    seen: set[Number] = set()
    for x in out:
        if x in seen:
            raise ValueError(f"{literal(x)} is given twice in {text!r}")
        seen.add(x)
    # In increasing order, as a range: the curves join neighbouring points.
    return sorted(out)


def _number(d: Decimal, whole: bool) -> Number:
    if whole and d.adjusted() >= 19:  # beyond 64 bits, and perhaps beyond what str() prints
        raise ValueError(f"{d:.3e} does not fit in a 64-bit integer")
    return int(d) if whole and d == d.to_integral_value() else float(d)
