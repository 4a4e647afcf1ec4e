"""Child processes stop when afsmc stops them, and die with afsmc."""

from __future__ import annotations

import multiprocessing
import os
import signal
import time
from concurrent.futures import ProcessPoolExecutor

from afsmc.cli import _raise_terminated
from afsmc.lifetime import die_with_parent


def _spin(seconds: float) -> int:
    end = time.monotonic() + seconds
    while time.monotonic() < end:
        pass
    return os.getpid()


def _signals(pid: int | None) -> str:
    """The signal lines of a live process's status (blocked, ignored, caught), for the
    message of a failure."""
    try:
        with open(f"/proc/{pid}/status", encoding="ascii") as f:
            return " ".join(line.strip() for line in f if line.startswith(("State", "Sig")))
    except OSError as exc:
        return str(exc)


def test_a_forked_pool_worker_dies_at_sigterm_despite_the_clis_handler() -> None:
    # The CLI turns SIGTERM into an exception; a forked worker inherits that handler, and
    # without die_with_parent resetting it the worker would catch the exception as its
    # batch's failure and go on with the next batch, so terminate() would not stop it.
    previous = signal.signal(signal.SIGTERM, _raise_terminated)
    pool = ProcessPoolExecutor(max_workers=1, mp_context=multiprocessing.get_context("fork"),
                               initializer=die_with_parent, initargs=(os.getpid(),))
    try:
        pool.submit(_spin, 0.0).result(timeout=60)  # the worker is up, its initializer run
        for _ in range(3):
            pool.submit(_spin, 30.0)
        procs = list(pool._processes.values())
        assert procs
        for proc in procs:
            proc.terminate()
        for proc in procs:
            proc.join(timeout=30)
        states = [_signals(proc.pid) for proc in procs if proc.exitcode is None]
        assert [proc.exitcode for proc in procs] == [-signal.SIGTERM] * len(procs), states
    finally:
        signal.signal(signal.SIGTERM, previous)
        pool.shutdown(wait=False, cancel_futures=True)
