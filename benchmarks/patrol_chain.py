"""Patrol's corridor as a long chain: `verify examples/patrol.afsm --const CELLS=n` by the
default route (`--solver auto`: afsmc's explorer first, which hands a cyclic or narrow model
to Storm) against `--solver topological` (Storm's build and solver), each run under
`/usr/bin/time -v`.

    .venv/bin/python benchmarks/patrol_chain.py [--cells 500,1000,2000,4000]
        [--out benchmarks/patrol_chain.csv] [--table]

The issue-51 target: CELLS=4000 in at most 2x the time of --solver topological. Rows are
appended to the CSV (values included) and printed as a markdown table with the ratio of
each auto run's CPU time to the topological run's of the same size, and the largest
difference between their values.
"""

from __future__ import annotations

import argparse
import json
import os
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, ROOT)

from benchmarks.acyclic import max_diff, values_of  # noqa: E402
from benchmarks.explicit import append_rows, csv_options, shown, timed_row  # noqa: E402

PATROL = os.path.join(ROOT, "examples", "patrol.afsm")
SOLVERS = ("auto", "topological")
FIELDS = ["measured", "load", "cells", "solver", "status", "wall_s", "cpu_s", "peak_gb",
          "states", "values"]


def run_one(cells: int, solver: str, timeout: float) -> dict[str, object]:
    args = ["verify", PATROL, "--const", f"CELLS={cells}", "--solver", solver, "--json"]
    out, row = timed_row(args, timeout, {"cells": cells, "solver": solver})
    if out is not None:
        m = out["model"]
        assert isinstance(m, dict)
        row |= {"states": m.get("states"), "values": json.dumps(values_of(out))}
    return row


def table(rows: list[dict[str, object]]) -> str:
    """Markdown: each auto run against the last topological run of its size."""
    storm = {str(r["cells"]): r for r in rows if r["solver"] == "topological"}
    lines = ["| CELLS | states | solver | wall s | CPU s | CPU / topological | max diff | load |",
             "|---|---|---|---|---|---|---|---|"]
    for r in rows:
        ref = storm.get(str(r["cells"])) if r["solver"] == "auto" else None
        cells = [str(r["cells"]), f"{int(float(str(r.get('states') or 0))):,}", str(r["solver"]),
                 str(r["wall_s"]), str(r["cpu_s"]), "", "", str(r["load"])]
        if ref is not None:
            cells[5] = f"{_cpu(r) / max(_cpu(ref), 1e-9):.2f}"
            cells[6] = f"{max_diff(_values(r), _values(ref)):.1e}"
        lines.append("| " + " | ".join(cells) + " |")
    return "\n".join(lines)


def _cpu(row: dict[str, object]) -> float:
    return float(str(row["cpu_s"]))


def _values(row: dict[str, object]) -> dict[str, float | None]:
    out: dict[str, float | None] = json.loads(str(row.get("values") or "{}"))
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--cells", default="500,1000,2000,4000")
    csv_options(ap, "patrol_chain.csv")
    args = ap.parse_args()
    if shown(args, table):
        return
    plan = [(int(n), s) for n in args.cells.split(",") for s in reversed(SOLVERS)]
    rows = append_rows(args.out, FIELDS, [
        (f"CELLS={n} {s}", lambda n=n, s=s: run_one(n, s, args.timeout))  # type: ignore[misc]
        for n, s in plan])
    print(table(rows))


if __name__ == "__main__":
    main()
