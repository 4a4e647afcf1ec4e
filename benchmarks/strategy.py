"""What `--strategy --witness 10` add to `afsmc verify -p success` (issue 32's target: at
most +50% time and memory on scenario 2), each run under `/usr/bin/time -v`.

    .venv/bin/python benchmarks/strategy.py [--instances 4x4-t300,scenario2]
        [--routes default,storm,memory,stream] [--reference 4x4-obj2-t300] [--out benchmarks/strategy.csv]

Per instance and route, two commands one after the other: `verify ... -p success --json`
(base) and the same with `--strategy --witness 10`. Route `default` is what a user gets
(afsmc's own exploration and backward pass); `storm` adds `--solver topological`: Storm's
build, solver, scheduler and path generator, the oracle; `memory` keeps afsmc's
exploration in memory (`--no-scratch`) and `stream` writes it layer by layer through the
system temp directory (`--scratch`), the strategies and paths read from the same files. The reference instance runs
first (the whole file, default route): its time tells how busy the machine was. Rows go
to the CSV (the values, the strategy tables' sizes and the paths' mass included) and are
printed as a markdown table with each extraction's CPU and memory against its base.
"""

from __future__ import annotations

import argparse
import os
import sys
import tempfile

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, ROOT)

from benchmarks.explicit import append_rows, csv_options, run_one, shown, timed_row  # noqa: E402
from benchmarks.run import INSTANCES, UAV  # noqa: E402

LOCAL: dict[str, list[str]] = {
    "4x4-t300": ["--const", "WIDTH=4", "--const", "HEIGHT=4", "--const", "T_LIMIT=300",
                 "--const", "DEADLINE=300"],
}
ROUTES: dict[str, list[str]] = {"default": [], "storm": ["--solver", "topological"],
                                "memory": ["--no-scratch"],
                                "stream": ["--scratch", tempfile.gettempdir()]}
RUNS: dict[str, list[str]] = {"base": [], "extract": ["--strategy", "--witness", "10"]}
FIELDS = ["measured", "load", "instance", "route", "run", "status", "wall_s", "cpu_s",
          "peak_gb", "states", "engine", "solver", "min", "max", "strategy_rows",
          "witnesses", "witness_mass"]


def measure(instance: str, route: str, run: str, timeout: float) -> dict[str, object]:
    args = ["verify", UAV, *(LOCAL.get(instance) or INSTANCES[instance]), "-p", "success",
            "--json", *ROUTES[route], *RUNS[run]]
    out, row = timed_row(args, timeout, {"instance": instance, "route": route, "run": run},
                         peak_digits=3)
    if out is not None:
        m = out["model"]
        props = out["properties"]
        assert isinstance(m, dict) and isinstance(props, list)
        p = props[0]
        ws = p.get("witnesses") or []
        row |= {"states": m.get("states"), "engine": m.get("engine", ""),
                "solver": m.get("solver", ""), "min": p.get("min"), "max": p.get("max"),
                "strategy_rows": sum(len(v) for v in (p.get("strategy") or {}).values()),
                "witnesses": len(ws), "witness_mass": sum(w["probability"] for w in ws)}
    return row


def _num(r: dict[str, object], key: str) -> float:
    return float(str(r.get(key) or 0))


def _versus(r: dict[str, object], b: dict[str, object] | None) -> tuple[str, str]:
    """The run's CPU and peak memory against its base's, in per cent."""
    if r["run"] == "base" or b is None or not _num(b, "cpu_s") or not _num(b, "peak_gb"):
        return "", ""
    return (f"{100 * (_num(r, 'cpu_s') / _num(b, 'cpu_s') - 1):+.1f}%",
            f"{100 * (_num(r, 'peak_gb') / _num(b, 'peak_gb') - 1):+.1f}%")


def table(rows: list[dict[str, object]]) -> str:
    """Markdown, each extraction against the base of its instance and route."""
    base: dict[tuple[object, object], dict[str, object]] = {}
    lines = ["| instance | route | run | engine, solver | wall s | CPU s | peak GB | "
             "CPU vs base | peak vs base | strategy rows | paths (mass) | load |",
             "|---|---|---|---|---|---|---|---|---|---|---|---|"]
    for r in rows:
        if r["run"] == "base":
            base[(r["instance"], r["route"])] = r
        cpu, peak = _versus(r, base.get((r["instance"], r["route"])))
        cells = [r["instance"], r["route"], r["run"], f"{r.get('engine', '')}, "
                 f"{r.get('solver', '')}", f"{_num(r, 'wall_s'):.1f}", f"{_num(r, 'cpu_s'):.1f}",
                 f"{_num(r, 'peak_gb'):.3f}", cpu, peak, int(_num(r, "strategy_rows")),
                 f"{int(_num(r, 'witnesses'))} ({_num(r, 'witness_mass'):.4f})", r["load"]]
        lines.append("| " + " | ".join(str(c) for c in cells) + " |")
    return "\n".join(lines)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--instances", default="4x4-t300,scenario2")
    ap.add_argument("--routes", default="default")
    ap.add_argument("--reference", default="4x4-obj2-t300",
                    help="instance run first, the whole file ('' for none)")
    csv_options(ap, "strategy.csv")
    args = ap.parse_args()
    if shown(args, table):
        return
    if args.reference:
        ref = run_one(args.reference, "whole", "explicit", [], args.timeout)
        print(f"reference {args.reference}: {ref['wall_s']} s wall, {ref['cpu_s']} s CPU",
              file=sys.stderr)
    rows = append_rows(args.out, FIELDS, [
        (f"{i} {route} {run}",
         lambda i=i, route=route, run=run: measure(i, route, run, args.timeout))  # type: ignore[misc]
        for i in args.instances.split(",") for route in args.routes.split(",") for run in RUNS])
    print(table(rows))


if __name__ == "__main__":
    main()
