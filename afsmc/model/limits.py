"""What PRISM, JANI and Storm can represent: 64-bit integers, finite doubles, and the
integers Storm stores in a state.

The resolver refuses a literal, constant or mode number beyond these (E245, E249), the
overflow check an expression whose values leave them (E307), and `afsmc sweep` a value
list beyond them.
"""

from __future__ import annotations

import math
from typing import Any

INT64 = (-(2**63), 2**63 - 1)
NUMBERS_HINT = "PRISM and Storm compute with 64-bit integers and finite doubles"

# What a variable (the mode included) may hold. Storm's explicit builder stores values
# beyond this wrongly (x : [0..2^49] init 2^49 starts elsewhere, so P [F x = 2^49] is 0),
# and larger magnitudes are wrong even in small ranges (at 2^58).
STATE_INT = (-(2**48), 2**48 - 1)
STATE_INT_HINT = "Storm's state encoding holds these wrongly; rescale the variable"
BEYOND_STATE_INT = (f"goes beyond what Storm stores in a state ({STATE_INT[0]}..{STATE_INT[1]}, "
                    "±2^48)")


def unrepresentable(v: Any) -> str | None:
    """What keeps the value `v` from PRISM and Storm ("is infinite", ...), or None."""
    if isinstance(v, bool):
        return None
    if isinstance(v, int) and not INT64[0] <= v <= INT64[1]:
        return f"does not fit in a 64-bit integer ({INT64[0]} to {INT64[1]})"
    if isinstance(v, float) and not math.isfinite(v):
        return "is not a number (NaN)" if math.isnan(v) else "is infinite"
    return None
