"""The state-space guard: an estimate before building, and builds in a watched child.

Storm has neither a state limit nor a progress callback. So a build that might be big
runs in a child process (spawned, so it is safe from a threaded parent) that this process
watches: its memory use gives an estimate of the states explored so far, which is
shown as progress and compared with --max-states; the child is killed when it exceeds the
budget, and RLIMIT_AS backs this up inside the child. After the build the exact number of
states is compared with --max-states before anything is checked.
"""

from __future__ import annotations

import multiprocessing
import os
import signal
import sys
import time
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from dataclasses import dataclass, field, replace
from multiprocessing.connection import Connection
from multiprocessing.process import BaseProcess
from typing import Any

from afsmc.lifetime import die_with_parent, without_main
from afsmc.model import ir
from afsmc.text import count
from afsmc.verify.engines import stopping
from afsmc.verify.engines.storm import (
    DD_MEMORY_RETRY,
    Job,
    JobResult,
    StormFailure,
    execute,
    explores_first,
)

# Below this upper bound a build takes well under a second: no child process needed.
IN_PROCESS_STATES = 200_000
# Bytes per state of a sparse build as it runs, low in the measured range so that the
# estimate of states explored errs on the high side. Measured with stormpy 2.0 on a 2-core,
# 23 GB machine, on hand-written PRISM models of the UAV mission at 5.5-11 M states: the
# build alone about 100 bytes per state, a build and one check 200-260 (about 90 bytes per
# transition).
BYTES_PER_STATE = 150
# The child is stopped when its memory grows past max_states states at a generous rate.
BUDGET_BYTES_PER_STATE = 400
BUDGET_SLACK = 128 << 20
# Default --max-states: a sparse build plus one check at ~250 bytes per state in 70% of the
# memory available now, capped so a default run cannot occupy a shared machine for hours.
DEFAULT_CAP = 50_000_000
MAX_STATES_LIMIT = 10**10  # the largest --max-states: 1.5 TB of sparse matrices

Progress = Callable[[str], None]

# Storm's explicit matrices (gigabytes, converted anew for every hybrid query) in
# transparent huge pages: the 5x5 UAV's checks about 5% shorter (docs/benchmarks.md). glibc
# reads the tunable when a process starts, so it is set for the child only.
HUGE_PAGES = "glibc.malloc.hugetlb=1"


@contextmanager
def child_environment() -> Iterator[None]:
    """Around starting a Storm child: GLIBC_TUNABLES with malloc's huge pages, unless the
    user's own GLIBC_TUNABLES already sets that key (glibc.malloc.hugetlb=0 turns it off)."""
    old = os.environ.get("GLIBC_TUNABLES")
    if old is not None and "glibc.malloc.hugetlb=" in old:
        yield
        return
    os.environ["GLIBC_TUNABLES"] = f"{old}:{HUGE_PAGES}" if old else HUGE_PAGES
    try:
        yield
    finally:
        if old is None:
            os.environ.pop("GLIBC_TUNABLES", None)
        else:
            os.environ["GLIBC_TUNABLES"] = old


def _tables_full(code: int | None, job: Job) -> bool:
    """Sylvan ends the process when its decision-diagram tables are full: exit code 1, or
    sometimes a segmentation fault (likely its worker threads racing the exit): a test that
    fills 1 MB tables ended so in 3 of 25 runs on a busy machine, after "Unique table
    full" on stderr."""
    return job.engine != "sparse" and code in (1, -signal.SIGSEGV)


def upper_bound(model: ir.Model) -> int:
    """A cheap upper bound on the reachable states: modes × the product of variable ranges."""
    n = len(model.modes)
    for v in model.variables:
        n *= v.size
    return n


def mem_available() -> int | None:
    try:
        with open("/proc/meminfo", encoding="ascii") as f:
            for line in f:
                if line.startswith("MemAvailable:"):
                    return int(line.split()[1]) * 1024
    except OSError:
        return None
    return None


def default_max_states() -> int:
    avail = mem_available()
    if avail is None:
        return 10_000_000
    n = int(avail * 0.7 / 250)
    return max(100_000, min(DEFAULT_CAP, n - n % 100_000))


def _rss(pid: int) -> int | None:
    try:
        with open(f"/proc/{pid}/status", encoding="ascii") as f:
            for line in f:
                if line.startswith("VmRSS:"):
                    return int(line.split()[1]) * 1024
    except OSError:
        return None
    return None


def _vmsize() -> int | None:
    try:
        with open("/proc/self/status", encoding="ascii") as f:
            for line in f:
                if line.startswith("VmSize:"):
                    return int(line.split()[1]) * 1024
    except OSError:
        return None
    return None


def _child(conn: Any, job: Job, address_limit: int | None, parent: int) -> None:
    """Runs in the child: report readiness and memory baseline, then the job's events."""
    import resource

    die_with_parent(parent)
    # A Ctrl-C reaches the whole process group: the parent stops this child and reports
    # what it had; the child's own KeyboardInterrupt would only print a traceback.
    signal.signal(signal.SIGINT, signal.SIG_IGN)

    import stormpy  # noqa: F401  (imported before the baseline is measured)

    if address_limit is not None:
        size = _vmsize()
        if size is not None:
            # A backstop: an allocation past this fails in the child, not in the machine.
            limit = size + address_limit
            _, hard = resource.getrlimit(resource.RLIMIT_AS)
            if hard != resource.RLIM_INFINITY:
                limit = min(limit, hard)  # a user's `ulimit -v` may not be raised
            resource.setrlimit(resource.RLIMIT_AS, (limit, limit))
    captured = (stopping.prepare_child() if job.max_states is not None
                and (job.engine == "sparse" or explores_first(job)) else None)
    conn.send(("ready", _rss(os.getpid())))
    started = time.monotonic()

    explored: list[bool] = []

    def notify(event: str, data: Any) -> None:
        if captured is not None and (event in ("built", "engine")
                                     or (data == "build" and explored)):
            captured.release()  # the explicit build is over (a symbolic one may follow)
        if data == "explore":
            explored.append(True)
        conn.send((event, data))

    result = execute(job, notify)
    if captured is not None:
        captured.release()
        result = stopping.after_abort(job, result, captured, time.monotonic() - started)
    conn.send(("result", result))
    conn.close()


def run_isolated(job: Job, progress: Progress | None, *, every: float = 5.0,
                 first: float = 3.0) -> JobResult:
    """Run `job` in a watched child process; see the module docstring."""
    rate: float = stopping.FIRST_TRIGGER_BYTES_PER_STATE
    measured: float | None = None
    for attempt in range(1, stopping.ATTEMPTS + 1):
        res, code, grown = _run_isolated(job, progress, every, first,
                                         rate if attempt < stopping.ATTEMPTS else None, measured)
        if res.failure is None or res.failure.stage != "stopped":
            break
        # Interrupted within the limit: the memory ran ahead of the states. Again, with
        # the trigger at the rate just measured (and some room).
        measured = grown / max(1, res.states)
        rate = max(rate, 1.25 * measured)
        if progress is not None:
            progress(f"the {job.what} had {res.states:,} states when its memory reached "
                     f"what --max-states allows at {grown / max(1, res.states):.0f} bytes per "
                     "state: building it again")
    if _tables_full(code, job) and job.dd_memory_mb < DD_MEMORY_RETRY:
        # The tables are too small for the diagrams.
        # Full tables after the build: the symbolic engine checks (auto picked hybrid).
        queries = len(job.hybrid_queries)
        if queries > 1 and res.states:
            # Full while checking one of several queries: the caller decides what to run
            # again and with which tables (the nodes of earlier checks may have filled them).
            res.failure = StormFailure(
                "tables", f"the decision-diagram tables ({job.dd_memory_mb} MB) of the "
                f"{job.what} were full after {len(res.values)} of its {queries} queries")
            return res
        # Too small for the model itself, or for its one query: once more with Storm's
        # default size, for the queries the process had not answered yet.
        note = (f"the decision-diagram tables ({job.dd_memory_mb} MB) were too small for the "
                f"{job.what}: retrying with {DD_MEMORY_RETRY} MB")
        if progress is not None:
            progress(note)
        else:  # Sylvan has said "Unique table full" on stderr: say what it means there too
            print(f"afsmc: {note}", file=sys.stderr, flush=True)
        done, first_seconds = res.values, res.seconds
        rest = tuple(n for n in job.names if n not in done)
        extra = tuple(n for n in job.hybrid_extra if n not in done)
        try:
            res, code, _ = _run_isolated(replace(job, dd_memory_mb=DD_MEMORY_RETRY, names=rest,
                                                 hybrid_extra=extra), progress, every, first,
                                         None)
        except Interrupted as exc:
            exc.values = done | exc.values  # the first attempt's answers count too
            raise
        res.values = done | res.values
        res.seconds = first_seconds | res.seconds
        res.dd_retried = True
    return res


def report_interval(in_phase: float, every: float) -> float:
    """Seconds to the next progress line of a phase (a build, a check) that has run for
    `in_phase` s: `every` at first, then sparser, so that an hour's check leaves a log of
    some 80 lines rather than 700."""
    return every if in_phase < 60 else max(every, 30.0) if in_phase < 600 else max(every, 60.0)


class Interrupted(KeyboardInterrupt):
    """Ctrl-C while a Storm process ran: carries the values it had sent."""

    def __init__(self, values: dict[str, float]):
        super().__init__()
        self.values = values


def _run_isolated(job: Job, progress: Progress | None, every: float, first: float,
                  rate: float | None, measured: float | None = None
                  ) -> tuple[JobResult, int | None, int]:
    """Run `job` once in a watched child: its result, the child's exit code (None when
    this process stopped the child for its memory), and how much its memory had grown
    when it was interrupted at `rate` bytes per state (see :mod:`afsmc.verify.engines.stopping`)."""
    ctx = multiprocessing.get_context("spawn")
    conn, child_end = ctx.Pipe(duplex=False)
    avail = mem_available()
    # Never let the child take more than 85% of what is free now.
    cap = int(avail * 0.85) if avail is not None else None
    budget = None
    if job.max_states is not None and (job.engine == "sparse" or explores_first(job)):
        # at the rate measured by an interrupted attempt, if higher (see stopping)
        budget = int(job.max_states * max(BUDGET_BYTES_PER_STATE, 2 * (measured or 0))) \
            + BUDGET_SLACK
    address_limit = None
    if job.engine == "sparse":
        # Symbolic engines reserve large address ranges up front (Sylvan), so only sparse.
        address_limit = max(2 << 30, 3 * (budget or 0), cap or 0)
    proc = ctx.Process(target=_child, args=(child_end, job, address_limit, os.getpid()),
                       daemon=True)
    with child_environment(), without_main():
        proc.start()
    child_end.close()
    start = time.monotonic()
    watch = _Watch(job, progress, every, budget, cap, start=start, phase_start=start,
                   next_report=start + first, pid=proc.pid or 0, measured=measured,
                   trigger=stopping.trigger_bytes(job, rate) if budget is not None else None)
    try:
        stopped = _follow(watch, proc, conn)
    except KeyboardInterrupt as exc:
        raise Interrupted(dict(watch.answered)) from exc
    finally:
        if proc.is_alive() and watch.result is None:
            proc.kill()
        proc.join()
        conn.close()
    if stopped is not None:
        return stopped, None, watch.interrupted
    if watch.result is not None:
        return watch.result, proc.exitcode, watch.interrupted
    return watch.died(proc.exitcode), proc.exitcode, watch.interrupted


def _follow(watch: _Watch, proc: BaseProcess, conn: Connection) -> JobResult | None:
    """Read the child's events and watch its memory until it sends its result or dies
    (None), or stop it when it outgrows the budget or the cap (a result saying so)."""
    while watch.result is None:
        if conn.poll(0.2):
            try:
                event, data = conn.recv()
            except EOFError:
                return None
            watch.on(event, data)
            continue
        if not proc.is_alive():
            return None
        rss = _rss(proc.pid or 0)
        if rss is None or watch.baseline is None:
            continue
        stopped = watch.measure(rss)
        if stopped is not None:
            proc.kill()
            proc.join()
            return stopped
    return None


@dataclass
class _Watch:
    """What this process knows of a watched child as it runs, from its events and its
    memory: what to say as progress, and what to report when it is stopped or dies."""

    job: Job
    progress: Progress | None
    every: float  # seconds between progress lines, at first (see report_interval)
    budget: int | None  # bytes the build may grow by: --max-states at a generous rate
    cap: int | None  # bytes the child may use: 85% of the memory free at its start
    start: float
    phase_start: float
    next_report: float
    baseline: int | None = None  # the child's memory once stormpy is imported
    phase: str = "start"
    peak: int = 0
    result: JobResult | None = None
    answered: dict[str, float] = field(default_factory=dict)  # values sent before it may die
    seconds: dict[str, float] = field(default_factory=dict)  # and how long each took
    built: int = 0  # states, once the child has built the model
    engine: str = ""  # the engine it checks with ("auto" decides after building)
    pid: int = 0
    trigger: int | None = None  # growth at which to interrupt an explicit build (stopping)
    interrupted: int = 0  # the growth when it was interrupted
    measured: float | None = None  # bytes per state an earlier attempt measured (stopping)

    @property
    def explicit(self) -> bool:
        """Whether the child is building sparse matrices, whose memory counts the states:
        the sparse engine's build, or the explicit count a symbolic job makes first."""
        return self.phase == "explore" or (self.phase == "build" and self.job.engine == "sparse")

    def say(self, text: str) -> None:
        if self.progress is not None:
            self.progress(text)

    def on(self, event: str, data: Any) -> None:
        """One event from the child (see :func:`afsmc.verify.engines.storm.execute`)."""
        what = self.job.what
        if event == "ready":
            self.baseline = data
        elif event == "phase":
            self.phase, self.phase_start = data, time.monotonic()
        elif event == "engine":
            self.engine = data
        elif event == "built":
            states, transitions, secs = data
            self.built = states
            self.say(f"built the {what}: {states:,} states, {transitions:,} transitions "
                     f"in {secs:.1f} s")
        elif event == "solver":  # which path solves the queries (afsmc.verify.arrays.acyclic)
            self.say(data)
        elif event == "refused":
            self.say(f"the hybrid engine cannot check {', '.join(data)}: E404 follows "
                     "once the other queries of this process are checked")
        elif event == "value":
            name, value, secs = data
            self.answered[name], self.seconds[name] = value, secs
            self.say(f"checked {name} on the {what} in {self.seconds[name]:.0f} s "
                     f"({time.monotonic() - self.start:.0f} s into this process)")
        elif event == "result":
            self.result = data

    def measure(self, rss: int) -> JobResult | None:
        """The child's memory now: a result if it must be stopped, else a progress line
        when one is due."""
        assert self.baseline is not None
        job, start = self.job, self.start
        self.peak = max(self.peak, rss)
        grown = max(0, rss - self.baseline)
        explored = grown / (self.measured or BYTES_PER_STATE)
        now = time.monotonic()
        if self.explicit and self.trigger is not None and grown > self.trigger \
                and not self.interrupted:
            # Storm's handler ends the exploration and reports the exact count (stopping)
            self.interrupted = grown
            os.kill(self.pid, signal.SIGTERM)
        # With a trigger, the exact count decides; the budget stops a build without one.
        if self.explicit and self.budget is not None and grown > self.budget \
                and (self.trigger is None or self.interrupted):
            assert job.max_states is not None
            return JobResult(failure=StormFailure(
                "too-big", f"stopped building the {job.what} after {now - start:.0f} s: about "
                f"{count(explored)} states explored (estimated from memory use), more than "
                f"--max-states {job.max_states:,}", states=int(explored)))
        if self.cap is not None and rss > self.cap:
            return JobResult(states=self.built, values=self.answered, seconds=self.seconds,
                             elapsed=now - start, engine=self.engine, failure=StormFailure(
                "memory", f"stopped the {job.what} after {now - start:.0f} s: it used "
                f"{rss / 2**30:.1f} GB, 85% of the memory that was available",
                prop=_checking(self.phase)))
        if now >= self.next_report:
            self.next_report = now + report_interval(now - self.phase_start, self.every)
            if self.phase in ("build", "explore"):
                est = (f", about {count(explored)} states so far (estimated from memory use)"
                       if self.explicit else f", {rss / 2**30:.1f} GB")
                self.say(f"building the {job.what}: {now - start:.0f} s{est}")
            elif self.phase.startswith("check "):
                self.say(f"checking {self.phase[6:]} on the {job.what}: {now - start:.0f} s, "
                         f"{rss / 2**30:.1f} GB")
        return None

    def died(self, code: int | None) -> JobResult:
        """The child ended without a result: the failure, with what it had answered."""
        job = self.job
        why = (f"was killed by signal {-code}" if code is not None and code < 0
               else f"exited with code {code}")
        if _tables_full(code, job):
            why += (f" (with decision-diagram tables of {job.dd_memory_mb} MB; Sylvan exits "
                    "when they are full)")
        gb = f"; it had used {self.peak / 2**30:.1f} GB" if self.peak else ""
        return JobResult(states=self.built, values=self.answered, seconds=self.seconds,
                         elapsed=time.monotonic() - self.start,
                         engine=self.engine, failure=StormFailure(
            "memory" if code is not None and code < 0 else "internal",
            f"the Storm process {'checking' if self.phase.startswith('check') else 'building'} "
            f"the {job.what} {why}{gb}", prop=_checking(self.phase)))


def _checking(phase: str) -> str | None:
    """The query the child was checking when it was stopped or died (its "check" phase)."""
    return phase[len("check "):] if phase.startswith("check ") else None


def run_job(job: Job, bound: int, *, isolate: bool | None, progress: Progress | None) -> JobResult:
    """Run in this process when the model is surely small, else in a watched child; with
    a scratch directory, in a subdirectory of it made here and removed here (after the
    child is gone: on exit, on error and on interrupt)."""
    if job.scratch is None or job.explicit is None:
        return _run_job(job, bound, isolate=isolate, progress=progress)
    from afsmc.verify.stream.scratch import made

    with made(job.scratch) as where:
        return _run_job(replace(job, scratch=str(where)), bound, isolate=isolate,
                        progress=progress)


def _run_job(job: Job, bound: int, *, isolate: bool | None, progress: Progress | None
             ) -> JobResult:
    if isolate is None:
        isolate = bound > IN_PROCESS_STATES
    if not isolate:
        if bound > IN_PROCESS_STATES and job.dd_memory_mb < DD_MEMORY_RETRY:
            # No child to retry in (a Dask worker): full tables for a model that may be big,
            # as Sylvan would end this very process when they are full.
            job = replace(job, dd_memory_mb=DD_MEMORY_RETRY)
        return execute(job)
    return run_isolated(job, progress)
