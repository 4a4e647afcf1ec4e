"""Stopping a watched explicit build at --max-states with an exact count of its states.

Storm reports nothing while it builds, so the guard (:mod:`afsmc.verify.engines.guard`) estimates
the states explored from the child's memory. An estimate cannot stop a build soundly: a
state costs 60 bytes in a chain and several hundred in a model with many transitions. So
when the memory says the limit is near, the guard sends the child SIGTERM, which Storm's
own signal handler turns into an abort of the exploration that prints how many states it
had explored ("Explored N states in T seconds before abort."). Over the limit, that exact
count is the E405; within it (the memory ran ahead of the states), the build is started
again with the trigger moved to the bytes per state just measured, and at the third
attempt without the trigger (the memory budget alone then stops it).

This module holds both halves: what the child does (:func:`prepare_child`,
:func:`after_abort`) and the parent's trigger (:func:`trigger_bytes`), plus the wording
that names the variables making a model large (:func:`large_variables`).
"""

from __future__ import annotations

import contextlib
import ctypes
import os
import re
import signal
import sys
import tempfile
from dataclasses import replace
from typing import IO

from afsmc.model import ir
from afsmc.text import count
from afsmc.verify.engines.storm import Job, JobResult, StormFailure

# The first trigger: memory grown past --max-states states at this rate (a chain of single
# transitions costs 60-95 bytes per state as its hash table grows: stopped at once)
FIRST_TRIGGER_BYTES_PER_STATE = 100
TRIGGER_SLACK = 32 << 20
# Seconds Storm's handler waits for the exploration to end after SIGTERM before it exits
ABORT_WAIT = 30
ATTEMPTS = 3  # the last one without a trigger
_EXPLORED = re.compile(r"Explored (\d+) states in \d+ seconds before abort")
_ABORTED = "Aborted in state space exploration"


def trigger_bytes(job: Job, rate: float | None) -> int | None:
    """The memory growth at which the parent interrupts the child's explicit build (None:
    no trigger); `rate` in bytes per state."""
    if rate is None or job.max_states is None:
        return None
    return int(job.max_states * rate) + TRIGGER_SLACK


class Capture:
    """Storm's output while it builds explicitly, in a file: it prints the count on stdout,
    which must stay clean for --json, and its handler's notice of the signal on stderr.
    stderr is given back once the build is over (`release`), for what Storm says later."""

    def __init__(self) -> None:
        self.file: IO[bytes] = tempfile.TemporaryFile(prefix="afsmc-storm-")  # noqa: SIM115
        sys.stdout.flush()
        sys.stderr.flush()
        self.stderr: int | None = os.dup(2)
        os.dup2(self.file.fileno(), 1)
        os.dup2(self.file.fileno(), 2)

    def release(self) -> None:
        if self.stderr is not None:
            os.dup2(self.stderr, 2)
            os.close(self.stderr)
            self.stderr = None

    def text(self) -> str:
        with contextlib.suppress(OSError, AttributeError):
            ctypes.CDLL(None).fflush(None)  # Storm's std::cout shares C's stdout buffer
        self.file.seek(0)
        return self.file.read().decode("utf-8", "replace")


def prepare_child() -> Capture:
    """In the child, before Storm builds: Storm's handler for SIGTERM (the exploration
    ends with an exact count), and Storm's output captured."""
    from stormpy import developer

    developer.install_signal_handler(ABORT_WAIT)
    # Ctrl-C reaches the whole process group: the parent stops this child (see guard).
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    return Capture()


def after_abort(job: Job, res: JobResult, captured: Capture, seconds: float) -> JobResult:
    """The child's result once Storm has built or stopped: an exploration aborted by the
    parent's SIGTERM becomes too-big with the exact count, or "stopped" (under the limit:
    the parent starts again)."""
    f = res.failure
    if f is None or f.stage != "build" or _ABORTED not in f.message:
        return res
    m = _EXPLORED.search(captured.text())
    if m is None:
        return res
    n = int(m.group(1))
    assert job.max_states is not None
    if n > job.max_states:
        return replace(res, states=n, failure=StormFailure(
            "too-big", f"stopped building the {job.what} after {seconds:.0f} s: {n:,} states "
            f"explored, more than --max-states {job.max_states:,}", states=n))
    return replace(res, states=n, failure=StormFailure(
        "stopped", f"stopped at {n:,} states, within --max-states", states=n))


def large_variables(model: ir.Model, most: int = 3) -> str:
    """The variables with the largest ranges, for a message about the model's size:
    `x in [0..1000000000] (1.0 G values), cell in [0..4] (5 values)`."""
    big = sorted(model.variables, key=lambda v: -v.size)[:most]
    parts = [f"{v.name} ({count(v.size)} values)" for v in big if v.size > 1]
    if len(model.modes) > 1:
        parts.append(f"{len(model.modes)} modes")
    return ", ".join(parts)
