"""Throughput of `afsmc simulate`: complete runs per minute.

    .venv/bin/python benchmarks/simulate.py [FILE ...] [--runs N] [--jobs J ...]

Defaults: examples/uav.afsm (default instance), examples/patrol.afsm and the test mission,
1,000,000 runs, 1 and 2 worker processes. Prints one line per (file, jobs) and checks that
the estimates do not depend on the number of workers.
"""

from __future__ import annotations

import argparse
import os
import sys
import time

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, ROOT)

from afsmc.files import read_source  # noqa: E402
from afsmc.sim.run import job_for, simulate  # noqa: E402

DEFAULT = [os.path.join(ROOT, "examples", "uav.afsm"), os.path.join(ROOT, "examples", "patrol.afsm"),
           os.path.join(ROOT, "tests", "golden", "cases", "sim_mission", "mission.afsm")]


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("files", nargs="*", default=[f for f in DEFAULT if os.path.exists(f)])
    ap.add_argument("--runs", type=int, default=1_000_000)
    ap.add_argument("--jobs", type=int, nargs="+", default=[1, 2])
    ap.add_argument("--seed", type=int, default=0)
    args = ap.parse_args()
    print(f"{'file':<14} {'jobs':>4} {'runs':>9} {'seconds':>8} {'runs/min':>12} {'steps/s':>11}")
    for path in args.files:
        job = job_for(path, read_source(path), {}, "uniform", 100_000)
        first = None
        for jobs in args.jobs:
            start = time.perf_counter()
            out = simulate(job, args.runs, args.seed, jobs=jobs)
            secs = time.perf_counter() - start  # wall clock, including worker start-up
            print(f"{os.path.basename(path):<14} {jobs:>4} {args.runs:>9} {secs:>8.2f} "
                  f"{args.runs / secs * 60:>12,.0f} {out.steps / secs:>11,.0f}", flush=True)
            if first is None:
                first = out.estimates
            elif out.estimates != first:
                print("  ! estimates differ between worker counts", file=sys.stderr)
                return 1
        for e in first or []:
            print(f"    {e.name}: {e.estimate:.6g} [{e.low:.6g}, {e.high:.6g}]")
    return 0


if __name__ == "__main__":
    sys.exit(main())
