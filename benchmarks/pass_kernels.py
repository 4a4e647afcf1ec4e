"""The backward pass with its compiled kernels (afsmc.verify.kernels.passes) against its
numpy reference, on one UAV instance (scenario 2 by default).

    .venv/bin/python benchmarks/pass_kernels.py [--instance scenario2] [--repeat 2]
        [--part whole,inprocess] [--out benchmarks/pass_kernels.csv]

`whole`: `afsmc verify ... --json` as its own command under `/usr/bin/time -v`, with
AFSMC_KERNELS=numpy (the reference) and without it (the kernels, on a model this large),
one after the other, `--repeat` times: CPU seconds (user + system, of every process: on a
shared machine it says more than the wall time), wall seconds, peak GB, and the run's own
`timings.check` (the MDP's queries) and `timings.uniform_check` (the uniform DTMC's,
including its transitions' count), which are wall times.

`inprocess`: the instance explored once in this process, then each phase of the pass
timed in CPU seconds of this thread (time.thread_time: other processes on the machine do
not count), each mode in turn, `--repeat` times: the MDP's min/max queries
(acyclic.solve_many), the uniform DTMC's (the means), its transitions
(explicit._mean_transitions) and the self-loops (acyclic.self_loops). The kernels are
compiled (or loaded from numba's cache) before the first timing.

Every row's values are compared with the numpy reference's of the same part ("max
diff"); rows are appended to the CSV and printed as a markdown table.
"""

from __future__ import annotations

import argparse
import csv
import os
import sys
import time
from collections.abc import Callable
from typing import Any

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, ROOT)

from benchmarks.acyclic import max_diff, values_of  # noqa: E402
from benchmarks.explicit import timed_row  # noqa: E402
from benchmarks.run import INSTANCES, UAV, _consts  # noqa: E402

MODES = {"numpy": "numpy", "kernels": ""}  # label -> AFSMC_KERNELS ("": afsmc decides)
FIELDS = ["measured", "load", "instance", "part", "mode", "status", "wall_s", "cpu_s",
          "peak_gb", "check_s", "uniform_check_s", "mdp_pass_s", "uniform_pass_s",
          "transitions_s", "self_loops_s", "transitions", "max_diff"]


def _set_mode(mode: str) -> None:
    if MODES[mode]:
        os.environ["AFSMC_KERNELS"] = MODES[mode]
    else:
        os.environ.pop("AFSMC_KERNELS", None)


def whole(instance: str, repeat: int) -> list[dict[str, object]]:
    """The command, each mode in turn: its CSV rows."""
    rows: list[dict[str, object]] = []
    first: dict[str, float | None] | None = None
    for _ in range(repeat):
        for mode in MODES:
            _set_mode(mode)
            out, row = timed_row(["verify", UAV, *INSTANCES[instance], "--json"], 7200,
                                 {"instance": instance, "part": "whole", "mode": mode})
            if out is not None and "timings" in out:
                t: Any = out["timings"]
                row |= {"check_s": round(t["check"], 2),
                        "uniform_check_s": round(t["uniform_check"], 2),
                        "transitions": out["uniform_model"]["transitions"]}  # type: ignore[index]
                got = values_of(out)
                first = got if first is None else first
                row["max_diff"] = max_diff(got, first)
            rows.append(row)
            print(row, flush=True)
    return rows


def _cpu(fn: Callable[[], Any]) -> tuple[Any, float]:
    t0 = time.thread_time()
    got = fn()
    return got, time.thread_time() - t0


def inprocess(instance: str, repeat: int) -> list[dict[str, object]]:
    """The pass's phases on one exploration, each mode in turn: CSV rows."""
    from afsmc.backends.prism import property_variants
    from afsmc.compiler import load, lowered
    from afsmc.verify.arrays import acyclic
    from afsmc.verify.engines import explicit
    from afsmc.verify.explorer import explore, explore_graph

    low = lowered(load(UAV, _consts(INSTANCES[instance])).model, "nondet")
    names = tuple(n for p in low.model.properties for n, _ in property_variants(low, p))
    plan = explicit.plan(low, names)
    explicit.plan_uniform(low, tuple(p.name for p in low.model.properties), plan)
    a = explore_graph.explore(explore.compile_model(low, plan.targets, plan.rewards)).arrays
    mine = [q for q in plan.queries if q.opt != "mean"]
    means = [q for q in plan.queries if q.opt == "mean"]
    for mode in MODES:  # numba's compilation or cache load, and the first touch of pages
        _set_mode(mode)
        acyclic.solve_many(a, mine[:1])
        explicit._mean_transitions(a)
    rows: list[dict[str, object]] = []
    first: dict[str, float | None] | None = None
    for _ in range(repeat):
        for mode in MODES:
            _set_mode(mode)
            load_avg = os.getloadavg()[0]
            values, mdp = _cpu(lambda: acyclic.solve_many(a, mine))
            uniform, mean = _cpu(lambda: acyclic.solve_many(a, means))
            count, counted = _cpu(lambda: explicit._mean_transitions(a))
            _, loops = _cpu(lambda: acyclic.self_loops(a.states, a.choices, a.target, a.prob))
            got: dict[str, float | None] = {**values, **uniform}
            first = got if first is None else first
            rows.append({
                "measured": time.strftime("%Y-%m-%d %H:%M"), "load": round(load_avg, 1),
                "instance": instance, "part": "inprocess", "mode": mode, "status": "ok",
                "mdp_pass_s": round(mdp, 2), "uniform_pass_s": round(mean, 2),
                "transitions_s": round(counted, 2), "self_loops_s": round(loops, 2),
                "transitions": count, "max_diff": max_diff(got, first)})
            print(rows[-1], flush=True)
    return rows


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--instance", default="scenario2", choices=sorted(INSTANCES))
    ap.add_argument("--repeat", type=int, default=2)
    ap.add_argument("--part", default="whole,inprocess")
    ap.add_argument("--out", default=os.path.join(ROOT, "benchmarks", "pass_kernels.csv"))
    args = ap.parse_args()
    rows: list[dict[str, object]] = []
    for part in args.part.split(","):
        rows += (whole if part == "whole" else inprocess)(args.instance, args.repeat)
    new = not os.path.exists(args.out)
    with open(args.out, "a", newline="", encoding="utf-8") as f:
        w = csv.DictWriter(f, fieldnames=FIELDS, extrasaction="ignore")
        if new:
            w.writeheader()
        w.writerows(rows)
    shown = ["part", "mode", "cpu_s", "wall_s", "peak_gb", "check_s", "uniform_check_s",
             "mdp_pass_s", "uniform_pass_s", "transitions_s", "self_loops_s", "max_diff",
             "load"]
    print("| " + " | ".join(shown) + " |")
    print("|" + "---|" * len(shown))
    for r in rows:
        print("| " + " | ".join(str(r.get(k, "")) for k in shown) + " |")


if __name__ == "__main__":
    main()
