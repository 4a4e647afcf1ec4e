"""The state-space guard: an estimate before building, and builds in a watched child.

Storm has neither a state limit nor a progress callback. So a build that might be big
runs in a child process (spawned, so it is safe from a threaded parent) that this process
watches: its memory use gives an estimate of the states explored so far (the sparse
builder needs about 110-260 bytes per state, /work/shared/notes/performance.md), which is
shown as progress and compared with --max-states; the child is killed when it exceeds the
budget, and RLIMIT_AS backs this up inside the child. After the build the exact number of
states is compared with --max-states before anything is checked.
"""

from __future__ import annotations

import math
import multiprocessing
import os
import signal
import sys
import time
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from dataclasses import replace
from decimal import Decimal
from typing import Any

from afsmc.lifetime import die_with_parent
from afsmc.model import ir
from afsmc.verify.storm import DD_MEMORY_RETRY, Job, JobResult, StormFailure, execute

# Below this upper bound a build takes well under a second: no child process needed.
IN_PROCESS_STATES = 200_000
# Bytes per state of a sparse build as it runs: the low end of the measured range, so the
# estimate of states explored errs on the high side.
BYTES_PER_STATE = 150
# The child is stopped when its memory grows past max_states states at a generous rate.
BUDGET_BYTES_PER_STATE = 400
BUDGET_SLACK = 128 << 20
# Default --max-states: a sparse build plus one check at ~250 bytes per state in 70% of the
# memory available now, capped so a default run cannot occupy a shared machine for hours.
DEFAULT_CAP = 50_000_000

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


def human(n: float) -> str:
    """12_345_678 -> '12.3 M'; from 10^12 on, powers of ten: 2e19 -> '2.0e19'."""
    if isinstance(n, float) and not math.isfinite(n):
        return str(n)
    if n >= 1e12:
        mantissa, exponent = f"{Decimal(n):.1e}".split("e")  # Decimal: ints beyond floats too
        return f"{mantissa}e{int(exponent)}"
    if n >= 1e9:
        return f"{n / 1e9:.1f} G"
    if n >= 1e6:
        return f"{n / 1e6:.1f} M"
    if n >= 1e4:
        return f"{n / 1e3:.0f} k"
    return f"{int(n):,}"


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
    conn.send(("ready", _rss(os.getpid())))
    result = execute(job, lambda event, data: conn.send((event, data)))
    conn.send(("result", result))
    conn.close()


def run_isolated(job: Job, progress: Progress | None, *, every: float = 5.0,
                 first: float = 3.0) -> JobResult:
    """Run `job` in a watched child process; see the module docstring."""
    res, code = _run_isolated(job, progress, every, first)
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
            res, code = _run_isolated(replace(job, dd_memory_mb=DD_MEMORY_RETRY, names=rest,
                                              hybrid_extra=extra), progress, every, first)
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


def _run_isolated(job: Job, progress: Progress | None, every: float,
                  first: float) -> tuple[JobResult, int | None]:
    ctx = multiprocessing.get_context("spawn")
    parent, child_end = ctx.Pipe(duplex=False)
    avail = mem_available()
    # Never let the child take more than 85% of what is free now.
    cap = int(avail * 0.85) if avail is not None else None
    budget = None
    if job.max_states is not None and job.engine == "sparse":
        budget = job.max_states * BUDGET_BYTES_PER_STATE + BUDGET_SLACK
    address_limit = None
    if job.engine == "sparse":
        # Symbolic engines reserve large address ranges up front (Sylvan), so only sparse.
        address_limit = max(2 << 30, 3 * (budget or 0), cap or 0)
    proc = ctx.Process(target=_child, args=(child_end, job, address_limit, os.getpid()),
                       daemon=True)
    with child_environment():
        proc.start()
    child_end.close()
    start = time.monotonic()
    next_report = start + first
    baseline: int | None = None
    phase = "start"
    phase_start = start
    peak = 0
    result: JobResult | None = None
    answered: dict[str, float] = {}  # values the child sent before it may die
    seconds: dict[str, float] = {}  # and how long each took
    built = 0  # states, once the child has built the model
    engine = ""  # the engine it checks with ("auto" decides after building)

    def say(text: str) -> None:
        if progress is not None:
            progress(text)

    try:
        while result is None:
            if parent.poll(0.2):
                try:
                    event, data = parent.recv()
                except EOFError:
                    break
                if event == "ready":
                    baseline = data
                elif event == "phase":
                    phase, phase_start = data, time.monotonic()
                elif event == "engine":
                    engine = data
                elif event == "built":
                    states, transitions, secs = data
                    built = states
                    say(f"built the {job.what}: {states:,} states, {transitions:,} transitions "
                        f"in {secs:.1f} s")
                elif event == "refused":
                    say(f"the hybrid engine cannot check {', '.join(data)}: E404 follows "
                        "once the other queries of this process are checked")
                elif event == "value":
                    name, value, secs = data
                    answered[name], seconds[name] = value, secs
                    say(f"checked {name} on the {job.what} in {seconds[name]:.0f} s "
                        f"({time.monotonic() - start:.0f} s into this process)")
                elif event == "result":
                    result = data
                continue
            if not proc.is_alive():
                break
            rss = _rss(proc.pid or 0)
            if rss is None or baseline is None:
                continue
            peak = max(peak, rss)
            grown = max(0, rss - baseline)
            explored = grown / BYTES_PER_STATE
            now = time.monotonic()
            if phase == "build" and budget is not None and grown > budget:
                proc.kill()
                proc.join()
                assert job.max_states is not None
                return JobResult(failure=StormFailure(
                    "too-big", f"stopped building the {job.what} after {now - start:.0f} s: about "
                    f"{human(explored)} states explored (estimated from memory use), more than "
                    f"--max-states {job.max_states:,}", states=int(explored))), None
            if cap is not None and rss > cap:
                proc.kill()
                proc.join()
                return JobResult(states=built, values=answered, seconds=seconds,
                                 elapsed=now - start,
                                 engine=engine, failure=StormFailure(
                    "memory", f"stopped the {job.what} after {now - start:.0f} s: it used "
                    f"{rss / 2**30:.1f} GB, 85% of the memory that was available",
                    prop=_checking(phase))), None
            if now >= next_report:
                next_report = now + report_interval(now - phase_start, every)
                if phase == "build":
                    est = (f", about {human(explored)} states so far (estimated from memory use)"
                           if job.engine == "sparse" else f", {rss / 2**30:.1f} GB")
                    say(f"building the {job.what}: {now - start:.0f} s{est}")
                elif phase.startswith("check "):
                    say(f"checking {phase[6:]} on the {job.what}: {now - start:.0f} s, "
                        f"{rss / 2**30:.1f} GB")
    except KeyboardInterrupt as exc:
        raise Interrupted(dict(answered)) from exc
    finally:
        if proc.is_alive() and result is None:
            proc.kill()
        proc.join()
        parent.close()
    if result is not None:
        return result, proc.exitcode
    code = proc.exitcode
    why = (f"was killed by signal {-code}" if code is not None and code < 0
           else f"exited with code {code}")
    if _tables_full(code, job):
        why += (f" (with decision-diagram tables of {job.dd_memory_mb} MB; Sylvan exits when "
                "they are full)")
    gb = f"; it had used {peak / 2**30:.1f} GB" if peak else ""
    return JobResult(states=built, values=answered, seconds=seconds,
                     elapsed=time.monotonic() - start,
                     engine=engine, failure=StormFailure(
        "memory" if code is not None and code < 0 else "internal",
        f"the Storm process {'checking' if phase.startswith('check') else 'building'} the "
        f"{job.what} {why}{gb}", prop=_checking(phase))), code


def _checking(phase: str) -> str | None:
    """The query the child was checking when it was stopped or died (its "check" phase)."""
    return phase[len("check "):] if phase.startswith("check ") else None


def run_job(job: Job, bound: int, *, isolate: bool | None, progress: Progress | None) -> JobResult:
    """Run in this process when the model is surely small, else in a watched child."""
    if isolate is None:
        isolate = bound > IN_PROCESS_STATES
    if not isolate:
        if bound > IN_PROCESS_STATES and job.dd_memory_mb < DD_MEMORY_RETRY:
            # No child to retry in (a Dask worker): full tables for a model that may be big,
            # as Sylvan would end this very process when they are full.
            job = replace(job, dd_memory_mb=DD_MEMORY_RETRY)
        return execute(job)
    return run_isolated(job, progress)
