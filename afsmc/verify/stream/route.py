"""The queries of afsmc's own exploration answered through the scratch directory
(``verify --scratch``): :func:`afsmc.verify.engines.explicit.answer` calls :func:`answer`
when a job has a scratch directory and asks for no strategy."""

from __future__ import annotations

import time
from pathlib import Path
from typing import Any

from afsmc.verify.engines import explicit
from afsmc.verify.engines.explore import Compiled
from afsmc.verify.stream import layers, sweep
from afsmc.verify.stream.scratch import Scratch, clear


def mb(n: int) -> str:
    return f"{n / 1e6:,.1f} MB"


def answer(c: Compiled, p: explicit.Plan, means: list[str], where: str, what: str,
           notify: explicit.Notify, max_states: int | None,
           before_write: Any = None) -> explicit.Answer:
    """Explore into `where` (a directory of this job's own), answer every query of `p`
    by one sweep over the files, and remove them (also on error). Raises what
    layers.explore raises, and ScratchFull."""
    started = time.perf_counter()
    s = Scratch(Path(where), before_write)

    def explored(_event: str, data: Any) -> None:
        notify("solver", f"explored {data[1]:,} states of the {what} so far (clock at "
               f"{data[0]}; {mb(data[2])} on the scratch disk; "
               f"{time.perf_counter() - started:.0f} s)")

    try:
        st = layers.explore(c, s, explored, max_states)
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

        values, pairs = sweep.run(st, p.queries, c.reward_names, len(p.targets), solved)
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
                           st.transitions, built, p.left, None, uniform, s.written)
