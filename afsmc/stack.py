"""Room for deep expressions: every stage walks expressions recursively, and a long flat
chain (`a + b + c + ...`, 2000 terms) nests as deep as it is long. CPython's default
limit of 1000 frames stops that with a RecursionError; a higher limit on the main thread's
8 MB stack could crash the interpreter instead. So the command runs in a thread with a
stack of STACK_BYTES and a recursion limit of RECURSION_LIMIT frames: 5 KB of stack per
frame, where CPython 3.11 uses well under 1 KB even when the recursion goes through C
(hash, ==, repr, pickle, deepcopy of nested dataclasses, json of nested lists). The
parser refuses expressions nested deeper than afsmc.syntax.parser.MAX_DEPTH (E113) and the
resolver formulas that nest deeper once inlined (E246); the stages use a few frames per
level, so what is accepted fits the limit.
"""

from __future__ import annotations

import ctypes
import sys
import threading
from collections.abc import Callable
from typing import TypeVar

T = TypeVar("T")

STACK_BYTES = 512 * 2**20  # address space; only the pages touched take memory
RECURSION_LIMIT = 100_000


def run_deep(fn: Callable[[], T]) -> T:
    """`fn()` in a thread with a large stack and a matching recursion limit; its result or
    its exception, as if called here. A Ctrl-C (delivered to the main thread) is passed on
    to it as a KeyboardInterrupt, so the command handles it as it would on its own. If no
    such thread can be made (a small `ulimit -v`), `fn()` runs here with Python's limits."""
    box: dict[str, object] = {}

    def body() -> None:
        try:
            box["result"] = fn()
        except BaseException as exc:  # re-raised in the caller
            box["error"] = exc

    old_limit = sys.getrecursionlimit()
    try:
        old_size = threading.stack_size(STACK_BYTES)
    except (ValueError, RuntimeError):
        return fn()
    worker = threading.Thread(target=body, name="afsmc", daemon=True)
    sys.setrecursionlimit(max(old_limit, RECURSION_LIMIT))
    try:
        worker.start()
    except RuntimeError:  # "can't start new thread": no room for the stack
        sys.setrecursionlimit(old_limit)
        return fn()
    finally:
        threading.stack_size(old_size)
    try:
        while True:
            try:
                worker.join()
                break
            except KeyboardInterrupt:
                _interrupt(worker)
    finally:
        sys.setrecursionlimit(old_limit)
    if "error" in box:
        error = box["error"]
        assert isinstance(error, BaseException)
        raise error
    return box["result"]  # type: ignore[return-value]


def _interrupt(worker: threading.Thread) -> None:
    """Raise KeyboardInterrupt in `worker` at its next Python instruction."""
    if worker.ident is not None and worker.is_alive():
        ctypes.pythonapi.PyThreadState_SetAsyncExc(ctypes.c_ulong(worker.ident),
                                                   ctypes.py_object(KeyboardInterrupt))
