"""Compiled kernels of afsmc's own exploration and backward pass (numba).

Each kernel has a numpy counterpart in the module that calls it; that numpy code is the
reference the tests compare the kernels against, value for value. `enabled(size)` says
whether a call on `size` elements takes the compiled kernel: numba's import and the
loading of compiled code from its cache cost about half a second per process, which only
pays off on large models, so small ones (and every model when AFSMC_KERNELS=numpy is set)
keep the numpy path.
"""

from __future__ import annotations

import os
from collections.abc import Callable
from typing import Any, TypeVar, cast

F = TypeVar("F", bound=Callable[..., Any])

# The size (states, keys or branches, as the caller counts) from which a compiled kernel
# is used: below it, numpy's vectorised code finishes before numba's import and cache
# load are paid back (docs/benchmarks.md, "Compiled explorer").
THRESHOLD = 1_000_000

ANY_KEY = (1 << 63) - 1  # above every state key (they are packed into 62 bits)


def enabled(size: int) -> bool:
    """Take the compiled kernel for a call on `size` elements? AFSMC_KERNELS=numpy keeps
    the numpy reference always; AFSMC_KERNELS=numba takes the kernel at any size (tests)."""
    mode = os.environ.get("AFSMC_KERNELS", "")
    if mode == "numpy":
        return False
    if mode == "numba":
        return True
    return size >= THRESHOLD


def jit(fn: F) -> F:
    """`fn` compiled by numba (nopython, cached on disk beside the module, without the
    GIL). Kernel modules import numba through this at their own import, so callers
    import them only once `enabled` said yes."""
    import numba

    return cast(F, numba.njit(cache=True, nogil=True)(fn))
