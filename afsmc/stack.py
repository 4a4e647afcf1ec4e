"""Room for deep expressions: every stage walks expressions recursively, and a long flat
chain (`a + b + c + ...`, 2000 terms) nests as deep as it is long. CPython's default
limit of 1000 frames stops that with a RecursionError.

The command keeps running on the main thread (so Ctrl-C arrives where the commands expect
it), with a higher recursion limit. Frames that recurse through C (hash and == of nested
dataclasses, json, pickle) use the C stack, which on Linux grows on demand up to the soft
RLIMIT_STACK, read when it grows; so the soft limit is raised to STACK_BYTES where the hard
limit allows, and the recursion limit follows the stack there is at FRAME_BYTES a frame.
Measured: the deepest command (compile -t jani) on an expression nested 5000 levels, the
parser's limit (afsmc.syntax.parser.MAX_DEPTH, E113), used 3.7 MB of stack and about
25,000 frames, i.e. ~150 bytes a frame. The resolver refuses formulas nested deeper once
inlined (E246); a RecursionError that still gets through is E114 (afsmc.cli).
"""

from __future__ import annotations

import functools
import resource
import sys
import threading
from collections.abc import Callable
from typing import ParamSpec, TypeVar

T = TypeVar("T")
P = ParamSpec("P")

STACK_BYTES = 64 * 2**20  # the kernel keeps at least 128 MB free below the main stack
FRAME_BYTES = 1024  # generous: ~150 measured
RECURSION_LIMIT = 100_000


def _stack_bytes() -> int:
    """The main thread's stack limit after raising it as far as allowed (bytes)."""
    try:
        soft, hard = resource.getrlimit(resource.RLIMIT_STACK)
        if soft != resource.RLIM_INFINITY and soft < STACK_BYTES:
            new = STACK_BYTES if hard == resource.RLIM_INFINITY else min(STACK_BYTES, hard)
            if new > soft:
                resource.setrlimit(resource.RLIMIT_STACK, (new, hard))
                soft = new
    except (ValueError, OSError):
        return 8 * 2**20
    return STACK_BYTES if soft == resource.RLIM_INFINITY else int(soft)


def run_deep(fn: Callable[[], T]) -> T:
    """`fn()` on this thread with room for RECURSION_LIMIT frames (fewer if the stack
    cannot be made that large). Only the main thread's stack grows: on another thread the
    limits stay as they are (a higher recursion limit there would crash the process where
    a RecursionError is raised now)."""
    if threading.current_thread() is not threading.main_thread():
        return fn()
    old_limit = sys.getrecursionlimit()
    frames = min(RECURSION_LIMIT, _stack_bytes() // FRAME_BYTES)
    sys.setrecursionlimit(max(old_limit, frames))
    try:
        return fn()
    finally:
        sys.setrecursionlimit(old_limit)


def deep(fn: Callable[P, T]) -> Callable[P, T]:
    """The Python API's entry points (afsmc.compiler.load, afsmc.verify.run and sweep) and
    a sweep's worker task run with the room the commands have, so deep expressions work
    there too."""
    @functools.wraps(fn)
    def wrapper(*args: P.args, **kwargs: P.kwargs) -> T:
        return run_deep(lambda: fn(*args, **kwargs))
    return wrapper
