"""Each simulator runs in a child process, under a time limit and a memory limit.

Simulators come from third-party packages (the ``afsmc.simulators`` entry points): one may
raise ``SystemExit``, call ``os._exit``, hang, or allocate without end. In a child, none
of that reaches `sim-check`: whatever ends the child without samples is a
:class:`SimulatorFailure` with the reason, which the command reports at the constant (E505).
The samples come back through a pipe; their count is bounded beforehand
(:func:`runs_that_fit`), and the child's address space is limited (RLIMIT_AS) so that a
simulator that needs more fails there with a MemoryError, not in the machine.
"""

from __future__ import annotations

import multiprocessing
import os
import signal
import sys
import time
from typing import Any

import numpy as np
import numpy.typing as npt

from afsmc.lifetime import die_with_parent
from afsmc.simlib import registry

DEFAULT_TIMEOUT = 600.0  # seconds per simulator: the built-in ones take under 10 s at 10^6 runs
# Bytes each run costs while sim-check holds its samples: the output array in the child
# (as returned, as converted, as cached, as sent, and the simulator's own arrays) and in
# this process (as received, and sorted for the quantiles of an interval). Measured as the
# growth of the peak memory with --runs on examples/uav.afsm's simulators (about 170 bytes
# a run), with a margin: the up-front check refuses what the child could not hold.
BYTES_PER_RUN = 256
MEMORY_SHARE = 0.7  # of the memory available when sim-check starts


class SimulatorFailure(Exception):
    """A simulator ended without samples: it raised, exited, hung or ran out of memory."""


def mem_available() -> int | None:
    try:
        with open("/proc/meminfo", encoding="ascii") as f:
            for line in f:
                if line.startswith("MemAvailable:"):
                    return int(line.split()[1]) * 1024
    except OSError:
        return None
    return None


def memory_budget() -> int | None:
    """Bytes a simulator's child may use: MEMORY_SHARE of the memory available now."""
    avail = mem_available()
    return int(avail * MEMORY_SHARE) if avail is not None else None


def runs_that_fit(budget: int | None) -> int | None:
    """The most runs whose samples fit in `budget` bytes (None: no limit known)."""
    return None if budget is None else max(2, budget // BYTES_PER_RUN)


def sample(ref: str, runs: int, seed: int, *, timeout: float = DEFAULT_TIMEOUT,
           budget: int | None = None) -> npt.NDArray[Any]:
    """`registry.sample(ref, runs, seed)`, computed in a child process; raises
    SimulatorFailure when the child ends without samples or outlives `timeout` seconds."""
    # fork: the child has the registry this process loaded, and starts at once
    ctx: Any = multiprocessing.get_context("fork" if sys.platform == "linux" else "spawn")
    conn, child_end = ctx.Pipe(duplex=False)
    proc = ctx.Process(target=_child, args=(child_end, ref, runs, seed, budget, os.getpid()),
                       daemon=True)
    proc.start()
    child_end.close()
    deadline = time.monotonic() + timeout
    try:
        got = _wait(conn, proc, deadline, timeout)
        if got is None:
            proc.join(5)
            code = proc.exitcode
            raise SimulatorFailure(
                "it ended the process (exit code 0) without returning samples" if code == 0
                else f"it was killed by signal {-code}" if code is not None and code < 0
                else f"it ended the process with exit code {code} without returning samples")
        status, data = got
        if status != "ok":
            raise SimulatorFailure(str(data))
        if not isinstance(data, np.ndarray):
            raise SimulatorFailure("it returned no sample array")
        return data
    finally:
        if proc.is_alive():
            proc.kill()
        proc.join()
        conn.close()


def _wait(conn: Any, proc: Any, deadline: float, timeout: float) -> tuple[str, object] | None:
    """The child's message, None if it ended without one; SimulatorFailure at the deadline."""
    while True:
        left = deadline - time.monotonic()
        if left <= 0:
            raise SimulatorFailure(f"it did not finish within --timeout {timeout:g} s (raise "
                                   "--timeout SECONDS if it needs longer)")
        if conn.poll(min(left, 0.2)):
            try:
                msg: tuple[str, object] = conn.recv()
            except EOFError:
                return None
            return msg
        if not proc.is_alive() and not conn.poll(0):
            return None


def _child(conn: Any, ref: str, runs: int, seed: int, budget: int | None, parent: int) -> None:
    die_with_parent(parent)
    signal.signal(signal.SIGINT, signal.SIG_IGN)  # Ctrl-C: the parent stops this child
    if budget is not None:
        import resource

        size = _vmsize()
        if size is not None:
            limit = size + budget
            _, hard = resource.getrlimit(resource.RLIMIT_AS)
            if hard != resource.RLIM_INFINITY:
                limit = min(limit, hard)
            resource.setrlimit(resource.RLIMIT_AS, (limit, limit))
    try:
        x = np.asarray(registry.sample(ref, runs, seed), dtype=np.float64)
        msg: tuple[str, object] = ("ok", x)
    except MemoryError:
        limit_gb = f" (its limit: {budget / 2**30:.1f} GB, {MEMORY_SHARE:.0%} of the free memory)" \
            if budget is not None else ""
        msg = ("error", f"it ran out of memory at {runs:,} runs{limit_gb}; lower --runs")
    except registry.BadOutput as exc:  # what it returned is no samples: said as such
        msg = ("error", str(exc))
    except SystemExit as exc:
        msg = ("error", f"it raised SystemExit({exc.code!r}) instead of returning samples")
    except BaseException as exc:  # a plugin's error of any kind is its verdict
        msg = ("error", f"{type(exc).__name__}: {exc}")
    try:
        conn.send(msg)
        conn.close()
    finally:
        os._exit(0)  # not the plugin's atexit handlers, nor its threads


def _vmsize() -> int | None:
    try:
        with open("/proc/self/status", encoding="ascii") as f:
            for line in f:
                if line.startswith("VmSize:"):
                    return int(line.split()[1]) * 1024
    except OSError:
        return None
    return None
