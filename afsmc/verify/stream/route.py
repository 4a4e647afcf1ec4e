"""The queries of afsmc's own exploration answered through the scratch directory (and the
strategies and witnesses asked of them): :func:`afsmc.verify.engines.explicit.answer`
calls :func:`answer` when a job has a scratch directory, at once with ``verify --scratch
DIR``, and by default (:func:`where`) once the in-memory exploration passes
:data:`STREAM_FROM` states or would not fit comfortably (:class:`Watch`, :func:`too_big`),
going on from the buckets it explored; ``--no-scratch`` keeps it in memory."""

from __future__ import annotations

import os
import tempfile
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from afsmc.verify.engines import explicit
from afsmc.verify.engines.strategy_storm import Extract, Extracted
from afsmc.verify.explorer import explore_graph
from afsmc.verify.explorer.explore import Compiled
from afsmc.verify.stream import extract as extract_files
from afsmc.verify.stream import layers, sweep
from afsmc.verify.stream.scratch import Scratch, clear, unusable

# The share of the memory available when the exploration starts that the in-memory route
# may take (its peak estimated as the memory grown so far times explore_graph.PEAK_FACTOR,
# as the route estimates its own): above it, by default, the model is streamed. Below the
# 70% of free memory the in-memory route gives itself before handing the model to Storm
# (jobs.make_job's budget), so that the watch trips first; not lower, since the streamed
# route takes about twice the CPU where memory would have held (docs/benchmarks.md).
COMFORT = 0.65
# Bytes per state of the in-memory route's explored blocks (0.72 GB for scenario 2's 8.4 M
# states, 86 per state; rounded up): with the upper bound, a model surely small.
BLOCK_BYTES_PER_STATE = 100


@dataclass(frozen=True)
class Scratching:
    """Where a job may explore through a scratch directory: `directory` (None: in
    memory), and whether only once the in-memory exploration would not fit (`auto`)."""

    directory: str | None
    auto: bool = False


def where(given: str | None, forbidden: bool, bound: int, available: int | None
          ) -> Scratching:
    """`--scratch DIR` (`given`) streams into DIR; `--no-scratch` (`forbidden`) never
    streams; else the system temp directory, taken once the in-memory exploration would
    not fit comfortably, unless the model's upper bound `bound` surely fits or the temp
    directory cannot be written."""
    if given is not None:
        return Scratching(given)
    if forbidden or surely_fits(bound, available):
        return Scratching(None)
    tmp = tempfile.gettempdir()
    return Scratching(None) if unusable(tmp) is not None else Scratching(tmp, auto=True)


def surely_fits(bound: int, available: int | None) -> bool:
    """Whether `bound` states explored in memory fit comfortably in `available` bytes."""
    return available is None or \
        bound * BLOCK_BYTES_PER_STATE * explore_graph.PEAK_FACTOR <= COMFORT * available


def too_big(grown: int, available: int | None) -> bool:
    """Whether an in-memory exploration whose process has grown by `grown` bytes would
    peak past the comfortable share of `available` bytes."""
    return available is not None and grown * explore_graph.PEAK_FACTOR > COMFORT * available


def too_big_why(states: int, grown: int, available: int) -> str:
    """Why an exploration that grew by `grown` bytes after `states` states is streamed."""
    return (f"in memory it would peak at about {grown * explore_graph.PEAK_FACTOR / 1e9:.1f} "
            f"GB after {states:,} states, more than {COMFORT:.0%} of the "
            f"{available / 1e9:.1f} GB available")


# From this many states on, by default, the exploration goes on through the disk: the
# streamed route is then the faster one as well as the smaller (docs/benchmarks.md,
# "Streaming by default, without a restart").
STREAM_FROM = 2_000_000


def resident() -> int:
    """This process's resident memory in bytes (0 where /proc is not there)."""
    try:
        with open("/proc/self/statm", encoding="ascii") as f:
            return int(f.read().split()[1]) * os.sysconf("SC_PAGE_SIZE")
    except OSError:
        return 0


class Watch:
    """The in-memory exploration's `handover`, asked after each bucket: a reason to go on
    through the disk once the exploration would not fit comfortably (too_big), or once
    it passes STREAM_FROM states."""

    def __init__(self, available: int | None) -> None:
        self.available = available
        self.base = resident()

    def handover(self, states: int) -> str | None:
        grown = resident() - self.base
        if self.available is not None and too_big(grown, self.available):
            return too_big_why(states, grown, self.available)
        if states >= STREAM_FROM:
            return (f"passed {states:,} states (from {STREAM_FROM:,} on, the streamed route "
                    "is the faster one and the smaller)")
        return None


def mb(n: int) -> str:
    return f"{n / 1e6:,.1f} MB"


def answer(c: Compiled, p: explicit.Plan, means: list[str], into: str, what: str,
           notify: explicit.Notify, max_states: int | None, why: str = "--scratch",
           before_write: Any = None, extract: Extract | None = None,
           view_of: extract_files.ViewOf | None = None,
           resume: explore_graph.Partial | None = None) -> explicit.Answer:
    """Explore into `into` (a directory of this job's own), answer every query of `p`
    by one sweep over the files, and remove them (also on error); `why` it is streamed
    goes into the answer. With `extract`, the queries it asks of by a sweep of their
    own, and their strategies and witness from the same files
    (afsmc.verify.stream.extract; `view_of` reads the states' variables from their
    keys). `resume`: an in-memory exploration's buckets, written first and gone on
    from. Raises what layers.explore raises, and ScratchFull."""
    started = time.perf_counter()
    s = Scratch(Path(into), before_write)

    def explored(_event: str, data: Any) -> None:
        notify("solver", f"explored {data[1]:,} states of the {what} so far (clock at "
               f"{data[0]}; {mb(data[2])} on the scratch disk; "
               f"{time.perf_counter() - started:.0f} s)")

    try:
        st = layers.explore(c, s, explored, max_states, resume)
        del resume
        built = time.perf_counter() - started
        notify("built", (st.states, st.transitions, built))
        notify("solver", f"the {what} explored by afsmc into the scratch directory "
               f"({mb(s.written)} of layers, {len(st.start):,} buckets), acyclic but for "
               "self-loops: every query by a backward pass reading the layers back, "
               f"keeping the values of at most {sweep.live_rows(st):,} states at once")
        mine = [q for q in p.queries if q.opt != "mean"]
        notify("phase", "check " + ", ".join(q.name for q in mine))
        t0 = time.perf_counter()
        shown = [t0]

        def solved(done: int, of: int, left: int) -> None:
            if time.perf_counter() - shown[0] > 2.0:
                shown[0] = time.perf_counter()
                notify("solver", f"solved {done:,} of {of:,} buckets of the {what}"
                       + (f" ({left} sweeps to go, this one included)" if left > 1 else ""))

        out = None
        if extract is None or not any(q.name in extract.queries for q in p.queries):
            values, pairs = sweep.run(st, p.queries, c.reward_names, len(p.targets), solved)
        else:
            assert view_of is not None
            out = Extracted()
            values, pairs = extract_files.run(st, p.queries, c.reward_names, len(p.targets),
                                              extract, view_of, out, notify, solved)
    finally:
        clear(s.root)
    secs = (time.perf_counter() - t0) / len(p.queries)
    for q in mine:
        notify("value", (q.name, values[q.name], secs))
    uniform = None
    if means:
        notify("solver", "the uniform DTMC's values from the same sweep: in each state the "
               "mean of its floor/ceil choices")
        uniform = explicit.Uniform({n: values[explicit.MEAN + n] for n in means},
                                   dict.fromkeys(means, secs), pairs)
    return explicit.Answer({q.name: values[q.name] for q in mine},
                           {q.name: secs for q in mine}, st.states, st.choices,
                           st.transitions, built, p.left, out, uniform, s.written, why)
