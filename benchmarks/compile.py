"""How long `afsmc compile` takes on the UAV example: in process (parse, resolve, check,
lower, reduce, emit PRISM and JANI) and as a command (including Python's start-up).

    .venv/bin/python benchmarks/compile.py [--repeat N]

Prints a markdown table (median of N runs) for the default instance and both of the
paper's scenario presets; docs/benchmarks.md records the figures.
"""

from __future__ import annotations

import argparse
import os
import statistics
import subprocess
import sys
import tempfile
import time

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, ROOT)

from afsmc.backends import jani, prism  # noqa: E402
from afsmc.compiler import load, lowered  # noqa: E402

UAV = os.path.join(ROOT, "examples", "uav.afsm")
PRESETS = {"default": None, "scenario2": "uav-scenario2.args", "scenario1": "uav-scenario1.args"}


def consts(preset: str | None) -> dict[str, str]:
    out: dict[str, str] = {}
    if preset is None:
        return out
    with open(os.path.join(ROOT, "examples", preset), encoding="utf-8") as f:
        for line in f:
            for word in line.split("#", 1)[0].split():
                if "=" in word and not word.startswith("--"):
                    k, v = word.split("=", 1)
                    out[k] = v
    return out


def in_process(c: dict[str, str]) -> dict[str, float]:
    t0 = time.perf_counter()
    model = load(UAV, c).model
    t1 = time.perf_counter()
    low = lowered(model, "nondet")
    t2 = time.perf_counter()
    prism.emit(low)
    t3 = time.perf_counter()
    jani.dumps(jani.emit(low))
    t4 = time.perf_counter()
    return {"load+check": t1 - t0, "lower+reduce": t2 - t1, "prism": t3 - t2, "jani": t4 - t3,
            "total": t4 - t0}


def command(preset: str | None, out: str) -> float:
    args = [sys.executable, "-m", "afsmc.cli", "compile", UAV, "-o", out]
    if preset:
        args.append("@" + os.path.join(ROOT, "examples", preset))
    t0 = time.perf_counter()
    subprocess.run(args, check=True, capture_output=True, cwd=ROOT)
    return time.perf_counter() - t0


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--repeat", type=int, default=5)
    args = ap.parse_args()
    print("| instance | load + check | lower + reduce | PRISM | JANI | in process | `afsmc compile` command |")
    print("|---|---|---|---|---|---|---|")
    with tempfile.TemporaryDirectory() as tmp:
        for name, preset in PRESETS.items():
            c = consts(preset)
            runs = [in_process(c) for _ in range(args.repeat)]
            med = {k: statistics.median(r[k] for r in runs) for k in runs[0]}
            cmd = statistics.median(command(preset, tmp + "/") for _ in range(args.repeat))
            print(f"| {name} | {med['load+check']:.3f} s | {med['lower+reduce']:.3f} s | "
                  f"{med['prism']:.3f} s | {med['jani']:.3f} s | {med['total']:.3f} s | {cmd:.2f} s |")
    return 0


if __name__ == "__main__":
    sys.exit(main())
