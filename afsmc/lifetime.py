"""Child processes die with the afsmc process that started them.

A Storm child or a pool worker left behind by a `kill` of afsmc (a CI timeout, a closed
terminal) would go on holding its gigabytes and a core for as long as its check runs,
which on scenario 1 is an hour.
"""

from __future__ import annotations

import os
import signal
import sys
import types
from collections.abc import Iterator
from contextlib import contextmanager

PR_SET_PDEATHSIG = 1  # <linux/prctl.h>


def worker_died(exc: BaseException) -> bool:
    """A pool worker was killed (the out-of-memory killer, a signal): not a bug of afsmc.
    Dask says KilledWorker; distributed is not imported for it (it takes a second)."""
    from concurrent.futures.process import BrokenProcessPool

    return isinstance(exc, BrokenProcessPool) or (
        type(exc).__name__ == "KilledWorker" and type(exc).__module__.startswith("distributed"))


def die_with_parent(parent: int) -> None:
    """Call first thing in a child: the kernel sends it SIGKILL when the process `parent`
    (its parent's pid, passed in) dies, however it dies. Linux only (prctl); elsewhere
    nothing changes. The parent must wait for the child in the thread that started it: the
    signal follows the death of that thread.

    It also dies at a SIGTERM again. A forked child inherits the CLI's Python handler,
    which turns SIGTERM into an exception; a pool worker catches that as the failure of
    its batch and goes on with the next, so the parent's `terminate()` would not stop it.
    It inherits the forking thread's signal mask too: SIGTERM is unblocked."""
    import ctypes

    signal.signal(signal.SIGTERM, signal.SIG_DFL)
    signal.pthread_sigmask(signal.SIG_UNBLOCK, {signal.SIGTERM})

    try:
        libc = ctypes.CDLL(None, use_errno=True)
        if libc.prctl(PR_SET_PDEATHSIG, signal.SIGKILL) != 0:
            return
    except (OSError, AttributeError):
        return
    if os.getppid() != parent:  # the parent died before prctl took effect
        os._exit(1)


@contextmanager
def without_main() -> Iterator[None]:
    """Around starting a spawned child: a bare __main__, so that the child does not import
    the caller's script again. The child runs afsmc's own code only; a script without an
    `if __name__ == "__main__":` guard would otherwise verify again in the child, which
    multiprocessing refuses ("before the current process has finished its bootstrapping
    phase"), as it does a script read from stdin."""
    main = sys.modules.get("__main__")
    sys.modules["__main__"] = types.ModuleType("__main__")
    try:
        yield
    finally:
        if main is not None:
            sys.modules["__main__"] = main
