"""afsmc's own exploration (engine "explicit") against Storm's sparse build, each run under
`/usr/bin/time -v`.

    .venv/bin/python benchmarks/explicit.py [--instances 4x4-obj2-t300,scenario2]
        [--paths explicit,storm] [--workload whole|paper|minmax]
        [--reference 4x4-obj2-t300] [--out benchmarks/explicit.csv]

Each (instance, path) runs `afsmc verify ... --json` as its own command under
`/usr/bin/time -v`: the wall time, the CPU time (user + system, of every process: on a
shared machine it says more than the wall time) and the peak resident memory of the
largest process. `explicit` is the default (`--solver auto`: afsmc explores the model and
solves every P [F] and R [F] query by one backward pass); `storm` is `--solver
topological`, Storm's sparse build and its own solver, the oracle (a `--engine` may be
given for both, e.g. sparse with a `--max-states` for scenario 1). The reference instance
runs first, with the explicit path: its time, next to the others, tells how busy the
machine was. Rows are appended to the CSV (values included) and printed as a markdown
table with each run's largest difference from the first run of its instance and workload.

    .venv/bin/python benchmarks/explicit.py --instances scenario1 --paths explicit
    .venv/bin/python benchmarks/explicit.py --instances scenario1 --paths explicit \\
        --workload paper
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
from collections.abc import Callable

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, ROOT)

from benchmarks.acyclic import WORKLOADS, values_of  # noqa: E402
from benchmarks.run import INSTANCES, UAV  # noqa: E402

# "explicit" is the default (in memory, through the disk from route.STREAM_FROM states);
# "stream": afsmc's exploration through a scratch directory in the system's temp directory
# (verify --scratch), the layers on disk; its scratch_mb is the bytes it wrote there;
# "memory": never through the disk (--no-scratch)
PATHS: dict[str, list[str]] = {"explicit": [], "storm": ["--solver", "topological"],
                               "stream": ["--scratch", tempfile.gettempdir()],
                               "memory": ["--no-scratch"]}
FIELDS = ["measured", "load", "instance", "workload", "path", "status", "wall_s", "cpu_s",
          "peak_gb", "states", "transitions", "build_s", "check_s", "uniform_build_s",
          "uniform_check_s", "engine_used", "solver_used", "values", "scratch_mb"]


def _seconds(text: str) -> float:
    secs = 0.0
    for part in text.split(":"):
        secs = secs * 60 + float(part)
    return secs


def timed(args: list[str], timeout: float) -> tuple[dict[str, object] | None, dict[str, float],
                                                    str]:
    """Run `args` under /usr/bin/time -v: its JSON output, {wall, cpu, peak GB}, status."""
    env = dict(os.environ, PYTHONPATH=ROOT + os.pathsep + os.environ.get("PYTHONPATH", ""))
    cmd = ["/usr/bin/time", "-v", sys.executable, "-m", "afsmc", *args]
    try:
        p = subprocess.run(cmd, capture_output=True, text=True, timeout=timeout, env=env,
                           check=False)
    except subprocess.TimeoutExpired:
        return None, {"wall": timeout, "cpu": 0.0, "peak": 0.0}, "timeout"
    found = {key: re.search(pattern, p.stderr) for key, pattern in (
        ("wall", r"Elapsed \(wall clock\) time \(h:mm:ss or m:ss\): (\S+)"),
        ("user", r"User time \(seconds\): (\S+)"), ("sys", r"System time \(seconds\): (\S+)"),
        ("rss", r"Maximum resident set size \(kbytes\): (\d+)"))}
    got = {k: m.group(1) for k, m in found.items() if m is not None}
    times = {"wall": _seconds(got.get("wall", "0")),
             "cpu": float(got.get("user", 0)) + float(got.get("sys", 0)),
             "peak": int(got.get("rss", 0)) / 1e6}
    try:
        out = json.loads(p.stdout)
    except json.JSONDecodeError:
        return None, times, f"error (exit {p.returncode}): {p.stderr.strip()[-200:]}"
    return out, times, "ok" if p.returncode == 0 else f"exit {p.returncode}"


def timed_row(args: list[str], timeout: float, labels: dict[str, object],
              peak_digits: int = 2) -> tuple[dict[str, object] | None, dict[str, object]]:
    """Run `args` under /usr/bin/time -v: its JSON output, and a CSV row of when, the load
    before, `labels`, the status, wall and CPU seconds and peak GB."""
    load = os.getloadavg()[0]
    out, t, status = timed(args, timeout)
    row: dict[str, object] = {
        "measured": time.strftime("%Y-%m-%d %H:%M"), "load": round(load, 1), **labels,
        "status": status, "wall_s": round(t["wall"], 1), "cpu_s": round(t["cpu"], 1),
        "peak_gb": round(t["peak"], peak_digits)}
    return out, row


def run_one(instance: str, workload: str, path: str, extra: list[str],
            timeout: float) -> dict[str, object]:
    args = ["verify", UAV, *INSTANCES[instance], *WORKLOADS[workload], "--json",
            *PATHS[path], *extra]
    out, row = timed_row(args, timeout, {"instance": instance, "workload": workload,
                                         "path": path})
    if out is not None and "model" in out:  # (an interrupted run's JSON has no model)
        m, tm = out["model"], out["timings"]
        assert isinstance(m, dict) and isinstance(tm, dict)
        row |= {"states": m.get("states"), "transitions": m.get("transitions"),
                "build_s": tm.get("build"), "check_s": tm.get("check"),
                "uniform_build_s": tm.get("uniform_build"),
                "uniform_check_s": tm.get("uniform_check"),
                "engine_used": m.get("engine", ""), "solver_used": m.get("solver", ""),
                "values": json.dumps(values_of(out)), "scratch_mb": _scratch_mb(m)}
    return row


def _scratch_mb(model: dict[str, object]) -> float | str:
    """The MB written to the scratch directory, as the engine's reason says ("" if none)."""
    m = re.search(r"through ([\d,.]+) MB of scratch disk", str(model.get("engine_reason", "")))
    return float(m.group(1).replace(",", "")) if m else ""


def table(rows: list[dict[str, object]]) -> str:
    """Markdown, with each row's largest difference from the first row of its instance
    and workload."""
    first: dict[tuple[object, object], dict[str, float]] = {}
    lines = ["| instance | workload | path | engine, solver | wall s | CPU s | peak GB | "
             "states | build + check s | uniform build + check s | scratch MB | max diff | "
             "load |", "|---|---|---|---|---|---|---|---|---|---|---|---|---|"]
    for r in rows:
        vals = json.loads(str(r.get("values") or "{}"))
        base = first.setdefault((r["instance"], r["workload"]), vals)
        diff = max((abs(vals[k] - base[k]) for k in vals if k in base
                    and vals[k] is not None and base[k] is not None), default=0.0)

        def num(key: str, r: dict[str, object] = r) -> float:
            return float(str(r.get(key) or 0))

        lines.append(
            f"| {r['instance']} | {r['workload']} | {r['path']} | {r.get('engine_used', '')}, "
            f"{r.get('solver_used', '')} | {num('wall_s'):.1f} | {num('cpu_s'):.1f} | "
            f"{num('peak_gb'):.2f} | {int(num('states')):,} | "
            f"{num('build_s') + num('check_s'):.1f} | "
            f"{num('uniform_build_s') + num('uniform_check_s'):.1f} | "
            f"{r.get('scratch_mb') or '-'} | {diff:.1e} | "
            f"{r['load']} |")
    return "\n".join(lines)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--instances", default="4x4-obj2-t300,scenario2")
    ap.add_argument("--paths", default="explicit,storm")
    ap.add_argument("--workload", default="whole", choices=list(WORKLOADS))
    ap.add_argument("--engine", default="", help="an --engine for verify (default: auto)")
    ap.add_argument("--max-states", default="", help="a --max-states for verify")
    ap.add_argument("--reference", default="4x4-obj2-t300",
                    help="instance run first, explicit path, whole file ('' for none)")
    csv_options(ap, "explicit.csv")
    args = ap.parse_args()
    if shown(args, table):
        return
    extra = (["--engine", args.engine] if args.engine else []) + (
        ["--max-states", args.max_states] if args.max_states else [])
    plan = [(i, p, args.workload, extra) for i in args.instances.split(",")
            for p in args.paths.split(",")]
    if args.reference:
        plan.insert(0, (args.reference, "explicit", "whole", []))
    rows = append_rows(args.out, FIELDS, [
        (f"{i} {workload} {path}",
         lambda i=i, path=path, workload=workload, more=more: run_one(  # type: ignore[misc]
             i, workload, path, more, args.timeout))
        for i, path, workload, more in plan])
    print(table(rows))


def csv_options(ap: argparse.ArgumentParser, name: str) -> None:
    """--timeout, --out (benchmarks/`name`) and --table."""
    ap.add_argument("--timeout", type=float, default=2 * 3600)
    ap.add_argument("--out", default=os.path.join(ROOT, "benchmarks", name))
    ap.add_argument("--table", action="store_true", help="print the CSV's table, run nothing")


def shown(args: argparse.Namespace, table: Callable[[list[dict[str, object]]], str]) -> bool:
    """With --table: the CSV's rows printed as `table` makes them."""
    if args.table:
        with open(args.out, encoding="utf-8") as f:
            print(table(list(csv.DictReader(f))))
    return bool(args.table)


def append_rows(out: str, fields: list[str],
                runs: list[tuple[str, Callable[[], dict[str, object]]]]) -> list[dict[str, object]]:
    """Each run's row, appended to the CSV `out` as it comes (a header if it is new) and
    reported on stderr."""
    rows = []
    new = not os.path.exists(out)
    if not new:
        with open(out, encoding="utf-8") as f:
            old = list(csv.DictReader(f))
        if old and list(old[0]) != fields:  # a column added since: the file rewritten with it
            with open(out, "w", newline="", encoding="utf-8") as f:
                w = csv.DictWriter(f, fieldnames=fields)
                w.writeheader()
                w.writerows(old)
    with open(out, "a", newline="", encoding="utf-8") as f:
        w = csv.DictWriter(f, fieldnames=fields)
        if new:
            w.writeheader()
        for label, run in runs:
            row = run()
            rows.append(row)
            w.writerow(row)
            f.flush()
            print(f"{label}: {row['status']}, {row['wall_s']} s, {row['cpu_s']} s CPU, "
                  f"{row['peak_gb']} GB", file=sys.stderr)
    return rows


if __name__ == "__main__":
    main()
