"""`afsmc report` against `afsmc verify` on the same instance (issue 45's target: the
report takes at most 1.5x verify's time), each run under `/usr/bin/time -v`, one after
the other in this session.

    .venv/bin/python benchmarks/report_time.py [--instances default,scenario2]
        [--repeat N] [--out benchmarks/report_time.csv] [--table]

Rows (wall and CPU seconds, peak GB of the largest process) are appended to the CSV and
printed as a markdown table with each report's wall and CPU time over the median of the
verify runs of its instance. docs/benchmarks.md ("The assurance case") records them.
"""

from __future__ import annotations

import argparse
import os
import statistics
import sys
import tempfile

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, ROOT)

from benchmarks.explicit import append_rows, csv_options, shown, timed_row  # noqa: E402

UAV = os.path.join(ROOT, "examples", "uav.afsm")
INSTANCES = {"default": [], "scenario2": ["@" + os.path.join(ROOT, "examples",
                                                              "uav-scenario2.args")]}
FIELDS = ["measured", "load", "instance", "command", "status", "wall_s", "cpu_s", "peak_gb"]


def run_one(instance: str, command: str, timeout: float) -> dict[str, object]:
    with tempfile.TemporaryDirectory(prefix="afsmc-bench-") as tmp:
        args = (["verify", UAV, *INSTANCES[instance], "--json"] if command == "verify"
                else ["report", UAV, *INSTANCES[instance], "-o", os.path.join(tmp, "r.html")])
        _, row = timed_row(args, timeout, {"instance": instance, "command": command})
    if command == "report" and str(row["status"]).startswith("error (exit 0)"):
        row["status"] = "ok"  # the report prints no JSON
    return row


def table(rows: list[dict[str, object]]) -> str:
    out = ["| instance | command | wall s | CPU s | peak GB | wall / verify | CPU / verify |",
           "|---|---|---|---|---|---|---|"]
    for inst in dict.fromkeys(str(r["instance"]) for r in rows):
        mine = [r for r in rows if r["instance"] == inst and r["status"] == "ok"]
        base = [r for r in mine if r["command"] == "verify"]
        if not base:
            continue
        wall = statistics.median(float(str(r["wall_s"])) for r in base)
        cpu = statistics.median(float(str(r["cpu_s"])) for r in base)
        for r in mine:
            ratio = ("" if r["command"] == "verify" else
                     f"{float(str(r['wall_s'])) / wall:.2f}x")
            cratio = ("" if r["command"] == "verify" else
                      f"{float(str(r['cpu_s'])) / cpu:.2f}x")
            out.append(f"| {inst} | {r['command']} | {r['wall_s']} | {r['cpu_s']} | "
                       f"{r['peak_gb']} | {ratio} | {cratio} |")
    return "\n".join(out)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--instances", default="default,scenario2")
    ap.add_argument("--repeat", type=int, default=1)
    csv_options(ap, "report_time.csv")
    args = ap.parse_args()
    if shown(args, table):
        return
    runs = [(f"{inst} {cmd}", lambda i=inst, c=cmd: run_one(i, c, args.timeout))
            for inst in args.instances.split(",") for _ in range(args.repeat)
            for cmd in ("verify", "report")]
    print(table(append_rows(args.out, FIELDS, runs)))


if __name__ == "__main__":
    main()
