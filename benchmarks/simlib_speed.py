"""Speed of the built-in small-scale simulators (afsmc/simlib): seconds for 100,000 runs.

    .venv/bin/python benchmarks/simlib_speed.py [--runs N] [--repeat K]

Prints one line per simulator: the median of K timed runs (after one untimed warm-up),
and the runs per second. docs/simulation.md quotes the slowest. Timings belong here, not
in a unit test, where a slow machine gives a slow number, not a failure.
"""

from __future__ import annotations

import argparse
import os
import statistics
import sys
import time

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, ROOT)

import numpy as np  # noqa: E402

from afsmc.simlib import uav  # noqa: E402


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--runs", type=int, default=100_000)
    ap.add_argument("--repeat", type=int, default=3)
    args = ap.parse_args()
    print(f"{'simulator':<24} {'seconds':>8} {'runs/s':>12}")
    for sim in uav.SIMULATORS:
        sim.run(1_000, np.random.default_rng(0))  # warm-up: imports, caches
        times = []
        for k in range(args.repeat):
            t0 = time.perf_counter()
            sim.run(args.runs, np.random.default_rng(k + 1))
            times.append(time.perf_counter() - t0)
        s = statistics.median(times)
        print(f"{sim.name:<24} {s:>8.3f} {args.runs / s:>12,.0f}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
