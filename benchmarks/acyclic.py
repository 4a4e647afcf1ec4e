"""The acyclic backward pass against Storm's solver, each run under `/usr/bin/time -v`.

    .venv/bin/python benchmarks/acyclic.py [--instances 4x4-obj2-t300,scenario2]
        [--solvers auto,topological] [--workload whole|paper|minmax] [--engine sparse]
        [--reference 4x4-obj2-t300] [--out benchmarks/acyclic.csv]

Each (instance, solver) runs `afsmc verify ... --json --solver S` as its own command under
`/usr/bin/time -v`, which gives the wall time and the peak resident memory of the largest
process (the Storm child). `--solver topological` is the path afsmc took before the
backward pass (Storm's topological solver on the same sparse model); `auto` takes the
backward pass where the model is acyclic but for self-loops. Before the runs, the
reference instance is checked once with Storm's solver: its time, next to the others in
the same session, tells how busy the machine was (the machine is shared, read ratios).

Workloads: `whole` is the file as the README runs it (7 properties, min, max and uniform),
`paper` the paper's three properties of scenario 1 (success, missed, emergency; min and
max), `minmax` every property, min and max only (`--no-uniform`, the PRISM side-by-side).

Rows are appended to the CSV (values included, so that runs can be compared to the last
digit) and printed as a markdown table with each run's largest difference from the first
solver's values of the same instance and workload.

Scenario 1 (77.6 M states) is for a quiet machine with 20 GB free, on the sparse engine
(`auto` picks hybrid at that size, where there is no backward pass):

    .venv/bin/python benchmarks/acyclic.py --instances scenario1 --solvers auto \\
        --engine sparse --max-states 80000000 --workload whole
"""

from __future__ import annotations

import argparse
import csv
import json
import os
import re
import subprocess
import sys
import time

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, ROOT)

from benchmarks.run import INSTANCES, UAV  # noqa: E402

WORKLOADS: dict[str, list[str]] = {
    "whole": [],
    "paper": ["--no-uniform", "-p", "success", "-p", "missed", "-p", "emergency"],
    "minmax": ["--no-uniform"],
}
FIELDS = ["measured", "load", "instance", "workload", "solver", "engine_opt", "status",
          "wall_s", "peak_gb", "states", "transitions", "build_s", "check_s",
          "uniform_build_s", "uniform_check_s", "solver_used", "values"]


def timed(args: list[str], timeout: float) -> tuple[dict[str, object] | None, float, float, str]:
    """Run `args` under /usr/bin/time -v: (its JSON output, wall s, peak GB, status)."""
    env = dict(os.environ, PYTHONPATH=ROOT + os.pathsep + os.environ.get("PYTHONPATH", ""))
    cmd = ["/usr/bin/time", "-v", sys.executable, "-m", "afsmc", *args]
    try:
        p = subprocess.run(cmd, capture_output=True, text=True, timeout=timeout, env=env,
                           check=False)
    except subprocess.TimeoutExpired:
        return None, timeout, 0.0, "timeout"
    wall = re.search(r"Elapsed \(wall clock\) time \(h:mm:ss or m:ss\): (\S+)", p.stderr)
    rss = re.search(r"Maximum resident set size \(kbytes\): (\d+)", p.stderr)
    secs = 0.0
    if wall:
        for part in wall.group(1).split(":"):
            secs = secs * 60 + float(part)
    peak = int(rss.group(1)) / 1e6 if rss else 0.0
    try:
        out = json.loads(p.stdout)
    except json.JSONDecodeError:
        return None, secs, peak, f"error (exit {p.returncode}): {p.stderr.strip()[-200:]}"
    return out, secs, peak, "ok" if p.returncode == 0 else f"exit {p.returncode}"


def values_of(out: dict[str, object]) -> dict[str, float | None]:
    props = out.get("properties", [])
    assert isinstance(props, list)
    return {f"{p['name']}.{k}": p.get(k) for p in props
            for k in ("min", "max", "uniform", "value") if p.get(k) is not None}


def max_diff(mine: dict[str, float | None], theirs: dict[str, float | None]) -> float:
    """The largest difference between two runs' values, over the values both have."""
    return max((abs(a - b) for k, a in mine.items() if (b := theirs.get(k)) is not None
                and a is not None), default=0.0)


def run_one(instance: str, workload: str, solver: str, engine: list[str],
            timeout: float) -> dict[str, object]:
    args = ["verify", UAV, *INSTANCES[instance], *WORKLOADS[workload], "--json",
            "--solver", solver, *engine]
    load = os.getloadavg()[0]
    out, wall, peak, status = timed(args, timeout)
    row: dict[str, object] = {
        "measured": time.strftime("%Y-%m-%d %H:%M"), "load": round(load, 1),
        "instance": instance, "workload": workload, "solver": solver,
        "engine_opt": " ".join(engine), "status": status, "wall_s": round(wall, 1),
        "peak_gb": round(peak, 2)}
    if out is not None:
        m, t = out["model"], out["timings"]
        assert isinstance(m, dict) and isinstance(t, dict)
        row |= {"states": m.get("states"), "transitions": m.get("transitions"),
                "build_s": t.get("build"), "check_s": t.get("check"),
                "uniform_build_s": t.get("uniform_build"),
                "uniform_check_s": t.get("uniform_check"),
                "solver_used": m.get("solver", ""), "values": json.dumps(values_of(out))}
    return row


def table(rows: list[dict[str, object]]) -> str:
    """Markdown, with each row's largest difference from the first row of its instance
    and workload."""
    first: dict[tuple[object, object], dict[str, float]] = {}
    lines = ["| instance | workload | solver | solver used | wall s | peak GB | states | "
             "build s | check s | uniform build + check s | max diff | load |",
             "|---|---|---|---|---|---|---|---|---|---|---|---|"]
    for r in rows:
        vals = json.loads(str(r.get("values") or "{}"))
        base = first.setdefault((r["instance"], r["workload"]), vals)
        diff = max((abs(vals[k] - base[k]) for k in vals if k in base
                    and vals[k] is not None and base[k] is not None), default=0.0)
        def num(key: str, r: dict[str, object] = r) -> float:
            return float(str(r.get(key) or 0))

        ub = num("uniform_build_s") + num("uniform_check_s")
        lines.append(f"| {r['instance']} | {r['workload']} | {r['solver']} | "
                     f"{r.get('solver_used', '')} | {num('wall_s'):.1f} | {num('peak_gb'):.2f} | "
                     f"{int(num('states')):,} | {num('build_s'):.1f} | {num('check_s'):.1f} "
                     f"| {ub:.1f} | {diff:.1e} | {r['load']} |")
    return "\n".join(lines)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--instances", default="4x4-obj2-t300,scenario2")
    ap.add_argument("--solvers", default="topological,auto")
    ap.add_argument("--workload", default="whole", choices=list(WORKLOADS))
    ap.add_argument("--engine", default="", help="an --engine for verify (default: auto)")
    ap.add_argument("--max-states", default="", help="a --max-states for verify")
    ap.add_argument("--reference", default="4x4-obj2-t300",
                    help="instance checked first with Storm's solver ('' for none)")
    ap.add_argument("--timeout", type=float, default=4 * 3600)
    ap.add_argument("--out", default=os.path.join(ROOT, "benchmarks", "acyclic.csv"))
    ap.add_argument("--table", action="store_true", help="print the CSV's table, run nothing")
    args = ap.parse_args()
    if args.table:
        with open(args.out, encoding="utf-8") as f:
            print(table(list(csv.DictReader(f))))
        return
    engine = (["--engine", args.engine] if args.engine else []) + (
        ["--max-states", args.max_states] if args.max_states else [])
    plan = [(i, s) for i in args.instances.split(",") for s in args.solvers.split(",")]
    if args.reference:
        plan.insert(0, (args.reference, "topological"))
    rows = []
    new = not os.path.exists(args.out)
    with open(args.out, "a", newline="", encoding="utf-8") as f:
        w = csv.DictWriter(f, fieldnames=FIELDS)
        if new:
            w.writeheader()
        for k, (instance, solver) in enumerate(plan):
            workload = "whole" if args.reference and k == 0 else args.workload
            row = run_one(instance, workload, solver, [] if k == 0 and args.reference
                          else engine, args.timeout)
            rows.append(row)
            w.writerow(row)
            f.flush()
            print(f"{instance} {workload} {solver}: {row['status']}, {row['wall_s']} s, "
                  f"{row['peak_gb']} GB", file=sys.stderr)
    print(table(rows))


if __name__ == "__main__":
    main()
