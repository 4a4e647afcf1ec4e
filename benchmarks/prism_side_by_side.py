"""afsmc against PRISM on the same emitted model, each run under `/usr/bin/time -v`.

    bash benchmarks/prism_build.sh                  # once: PRISM 4.10.1 into .bench/prism
    .venv/bin/python benchmarks/prism_side_by_side.py [--instance scenario2]
        [--engines sparse,explicit] [--prism .bench/prism/prism/bin/prism]
        [--reference 4x4-obj2-t300] [--out benchmarks/prism.csv]

The instance is compiled once (`afsmc compile`, the floor/ceil MDP with every reduction);
PRISM then checks the emitted model and its properties file (the min and the max of each of
`uav.afsm`'s seven properties: 14 queries) with each engine, and afsmc checks the same
queries (`afsmc verify ... --no-uniform --json`, the default solver: it builds the same
model from the same lowered commands). Before them, afsmc runs the reference instance once:
its time, next to the others in the same session, tells how busy the machine was.

Every run's values are compared with afsmc's (the largest difference is printed), rows are
appended to the CSV with the values, and a markdown table is printed. PRISM is optional
(nothing in the tests needs it); the figures go to docs/benchmarks.md.
"""

from __future__ import annotations

import argparse
import csv
import json
import os
import re
import subprocess
import sys
import tempfile
import time

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, ROOT)

from benchmarks.acyclic import values_of  # noqa: E402
from benchmarks.run import INSTANCES, UAV  # noqa: E402

FIELDS = ["measured", "load", "instance", "tool", "status", "wall_s", "cpu_s", "peak_gb",
          "states", "values"]
DEFAULT_PRISM = os.path.join(ROOT, ".bench", "prism", "prism", "bin", "prism")


def cpu_of(stderr: str) -> float:
    """User + system seconds of every process, from `/usr/bin/time -v`'s report."""
    return sum(float(m) for m in re.findall(r"(?:User|System) time \(seconds\): (\S+)", stderr))


def wall_and_peak(stderr: str) -> tuple[float, float]:
    """Wall seconds and peak resident GB from `/usr/bin/time -v`'s report."""
    wall = re.search(r"Elapsed \(wall clock\) time \(h:mm:ss or m:ss\): (\S+)", stderr)
    rss = re.search(r"Maximum resident set size \(kbytes\): (\d+)", stderr)
    secs = 0.0
    if wall:
        for part in wall.group(1).split(":"):
            secs = secs * 60 + float(part)
    return secs, int(rss.group(1)) / 1e6 if rss else 0.0


def compile_model(instance: str, folder: str) -> tuple[str, str]:
    env = dict(os.environ, PYTHONPATH=ROOT + os.pathsep + os.environ.get("PYTHONPATH", ""))
    subprocess.run([sys.executable, "-m", "afsmc", "compile", UAV, *INSTANCES[instance],
                    "-o", folder + os.sep], check=True, env=env, capture_output=True)
    return os.path.join(folder, "uav.prism"), os.path.join(folder, "uav.props")


def prop_names(props: str) -> list[str]:
    with open(props, encoding="utf-8") as f:
        return re.findall(r'^"([^"]+)":', f.read(), re.M)


def run_prism(prism: str, engine: str, model: str, props: str, mem: str,
              timeout: float) -> dict[str, object]:
    cmd = ["/usr/bin/time", "-v", prism, model, props, f"-{engine}", "-javamaxmem", mem,
           "-cuddmaxmem", "4g"]
    load = os.getloadavg()[0]
    row: dict[str, object] = {"tool": f"PRISM -{engine}", "load": round(load, 1)}
    try:
        p = subprocess.run(cmd, capture_output=True, text=True, timeout=timeout, check=False)
    except subprocess.TimeoutExpired:
        return row | {"status": "timeout", "wall_s": timeout}
    wall, peak = wall_and_peak(p.stderr)
    results = [float(r) for r in re.findall(r"^Result: (\S+)", p.stdout, re.M)]
    states = re.search(r"^States:\s+(\d+)", p.stdout, re.M)
    names = prop_names(props)
    values = {n.rsplit("_", 1)[0] + "." + n.rsplit("_", 1)[1]: v
              for n, v in zip(names, results, strict=False)}
    ok = p.returncode == 0 and len(results) == len(names)
    return row | {"status": "ok" if ok else f"exit {p.returncode}: {p.stdout[-300:]}",
                  "wall_s": round(wall, 1), "cpu_s": round(cpu_of(p.stderr), 1),
                  "peak_gb": round(peak, 2), "states": int(states.group(1)) if states else "",
                  "values": json.dumps(values)}


def run_afsmc(instance: str, timeout: float) -> dict[str, object]:
    env = dict(os.environ, PYTHONPATH=ROOT + os.pathsep + os.environ.get("PYTHONPATH", ""))
    cmd = ["/usr/bin/time", "-v", sys.executable, "-m", "afsmc", "verify", UAV,
           *INSTANCES[instance], "--no-uniform", "--json"]
    row: dict[str, object] = {"tool": "afsmc --no-uniform", "load": round(os.getloadavg()[0], 1)}
    try:
        p = subprocess.run(cmd, capture_output=True, text=True, timeout=timeout, env=env,
                           check=False)
    except subprocess.TimeoutExpired:
        return row | {"status": "timeout", "wall_s": timeout}
    wall, peak = wall_and_peak(p.stderr)
    row |= {"status": "ok" if p.returncode == 0 else f"exit {p.returncode}",
            "wall_s": round(wall, 1), "cpu_s": round(cpu_of(p.stderr), 1),
            "peak_gb": round(peak, 2)}
    try:
        out = json.loads(p.stdout)
    except json.JSONDecodeError:
        return row | {"status": f"error (exit {p.returncode}): {p.stderr.strip()[-200:]}"}
    m = out["model"]
    return row | {"states": m.get("states"), "values": json.dumps(values_of(out)),
                  "tool": f"afsmc --no-uniform ({m.get('engine', '')}, {m.get('solver', '')})"}


def table(rows: list[dict[str, object]], base: dict[str, float]) -> str:
    lines = ["| instance | tool | wall s | CPU s | peak GB | states | max diff from afsmc | load |",
             "|---|---|---|---|---|---|---|---|"]
    for r in rows:
        vals = json.loads(str(r.get("values") or "{}"))
        diff = max((abs(vals[k] - base[k]) for k in vals if k in base), default=float("nan"))
        states = f"{int(str(r['states'])):,}" if r.get("states") else ""
        lines.append(f"| {r['instance']} | {r['tool']} | {float(str(r['wall_s'])):.1f} | "
                     f"{float(str(r.get('cpu_s') or 0)):.1f} | {float(str(r.get('peak_gb') or 0)):.2f} | {states} | {diff:.1e} | "
                     f"{r['load']} |")
    return "\n".join(lines)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--instance", default="scenario2", choices=list(INSTANCES))
    ap.add_argument("--engines", default="sparse", help="PRISM engines, comma-separated")
    ap.add_argument("--prism", default=os.environ.get("PRISM", DEFAULT_PRISM))
    ap.add_argument("--reference", default="4x4-obj2-t300",
                    help="instance afsmc checks first, to read the machine's day ('' for none)")
    ap.add_argument("--javamaxmem", default="20g")
    ap.add_argument("--timeout", type=float, default=3600)
    ap.add_argument("--out", default=os.path.join(ROOT, "benchmarks", "prism.csv"))
    args = ap.parse_args()
    if not os.access(args.prism, os.X_OK):
        sys.exit(f"prism_side_by_side: no PRISM at {args.prism}; "
                 "build it with `bash benchmarks/prism_build.sh` or give --prism")
    rows: list[dict[str, object]] = []
    if args.reference:
        rows.append({"instance": args.reference} | run_afsmc(args.reference, args.timeout))
    rows.append({"instance": args.instance} | run_afsmc(args.instance, args.timeout))
    base = json.loads(str(rows[-1].get("values") or "{}"))
    with tempfile.TemporaryDirectory(prefix="afsmc-prism-") as folder:
        model, props = compile_model(args.instance, folder)
        for engine in [e for e in args.engines.split(",") if e]:
            rows.append({"instance": args.instance} | run_prism(
                args.prism, engine, model, props, args.javamaxmem, args.timeout))
    stamp = time.strftime("%Y-%m-%d %H:%M")
    new = not os.path.exists(args.out)
    with open(args.out, "a", newline="", encoding="utf-8") as f:
        w = csv.DictWriter(f, FIELDS, extrasaction="ignore")
        if new:
            w.writeheader()
        for r in rows:
            w.writerow({"measured": stamp} | r)
    print(table(rows, base))


if __name__ == "__main__":
    main()
