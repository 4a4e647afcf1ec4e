"""How the streamed route (`verify --scratch`) grows with the model: the UAV on the 7x7
arena of the paper's scenarios at increasing time limits and numbers of objects, each run
under `/usr/bin/time -v`, with a straight-line fit of time, memory and scratch bytes
against the transitions.

    .venv/bin/python benchmarks/stream_growth.py [--sizes t300,t400,scenario2,o3-t600]
        [--scratch DIR] [--out benchmarks/stream_growth.csv] [--table]

Each size runs `afsmc verify examples/uav.afsm <its constants> --json --scratch DIR`
(DIR: the system temp directory by default), the whole file: seven properties' min, max
and uniform value. Recorded per run: states, transitions, wall and CPU seconds (user +
system, of every process), peak resident memory of the largest process, and the bytes
of layers on the scratch disk (from the engine's reason), and the load average before
it. Rows are appended to the CSV; the table printed (and `--table`, from the CSV) ends
with the least-squares line of each measure against the transitions: its slope per
transition, intercept and R^2, so that linear growth shows as R^2 near 1.

    .venv/bin/python benchmarks/stream_growth.py \\
        --sizes t300,t400,scenario2,o3-t600,o3-t750,scenario1

A size `aS-oN-tT` takes an S x S arena instead (the billion-state run of
docs/benchmarks.md is `a12-o3-t1750`). `--table` fits every row of the CSV, whatever
the code that measured it: give it a CSV of one session's rows to fit one version.
"""

from __future__ import annotations

import argparse
import os
import re
import sys
import tempfile

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, ROOT)

from benchmarks.explicit import _scratch_mb, append_rows, csv_options, shown, timed_row  # noqa: E402
from benchmarks.run import UAV  # noqa: E402


def _uav(objects: int, t_limit: int, arena: int = 7) -> list[str]:
    """The 7x7 arena (or `arena` x `arena`) and alpha of the paper's scenarios
    (examples/uav-scenario2.args), with `objects` objects and a time limit (and deadline)
    of `t_limit` s."""
    return [f"--const=WIDTH={arena},HEIGHT={arena},ALPHA=0.085,OBJECTS={objects},"
            f"T_LIMIT={t_limit},DEADLINE={t_limit}"]


# the paper's two scenarios: (objects, time limit)
SCENARIOS: dict[str, tuple[int, int]] = {"scenario2": (2, 500), "scenario1": (3, 900)}


def size_of(name: str) -> tuple[int, int, int]:
    """A size's objects, time limit and arena side: `scenario1`, `scenario2`, `tT` (2
    objects, time limit T, the 7x7 arena), `oN-tT` (N objects) or `aS-oN-tT` (an S x S
    arena)."""
    if name in SCENARIOS:
        return (*SCENARIOS[name], 7)
    m = re.fullmatch(r"(?:a(\d+)-)?(?:o(\d+)-)?t(\d+)", name)
    if m is None:
        raise SystemExit(f"stream_growth: unknown size {name!r} (scenario1, scenario2, tT, "
                         "oN-tT or aS-oN-tT)")
    return int(m.group(2) or 2), int(m.group(3)), int(m.group(1) or 7)
FIELDS = ["measured", "load", "size", "objects", "t_limit", "status", "wall_s", "cpu_s",
          "peak_gb", "states", "transitions", "scratch_mb"]
# column, name, its unit, and the factor and unit of its slope per transition
MEASURES = [("wall_s", "wall", "s", 1e6, "µs"), ("cpu_s", "CPU", "s", 1e6, "µs"),
            ("peak_gb", "peak memory", "GB", 1e9, "bytes"),
            ("scratch_mb", "scratch", "MB", 1e6, "bytes")]


def run_one(size: str, scratch: str, timeout: float) -> dict[str, object]:
    objects, t_limit, arena = size_of(size)
    args = ["verify", UAV, *_uav(objects, t_limit, arena), "--json", "--scratch", scratch]
    out, row = timed_row(args, timeout, {"size": size, "objects": objects,
                                         "t_limit": t_limit})
    if out is not None and isinstance(out.get("model"), dict):
        m = out["model"]
        assert isinstance(m, dict)
        row |= {"states": m.get("states"), "transitions": m.get("transitions"),
                "scratch_mb": _scratch_mb(m)}
    return row


def fit(xs: list[float], ys: list[float]) -> tuple[float, float, float]:
    """The least-squares line y = a x + b through the points: a, b and R^2."""
    n = len(xs)
    mx, my = sum(xs) / n, sum(ys) / n
    sxx = sum((x - mx) ** 2 for x in xs)
    sxy = sum((x - mx) * (y - my) for x, y in zip(xs, ys, strict=True))
    a = sxy / sxx if sxx else 0.0
    b = my - a * mx
    ss = sum((y - my) ** 2 for y in ys)
    res = sum((y - (a * x + b)) ** 2 for x, y in zip(xs, ys, strict=True))
    return a, b, (1 - res / ss) if ss else 1.0


def table(rows: list[dict[str, object]]) -> str:
    """The runs as markdown, by transitions (those that did not finish last), then each
    measure's line against the transitions (over the runs that finished)."""
    rows = sorted(rows, key=lambda r: float(str(r.get("transitions") or "inf")))
    lines = ["| size | objects | T_LIMIT | states | transitions | wall s | CPU s | peak GB | "
             "scratch MB | load |", "|---|---|---|---|---|---|---|---|---|---|"]
    done = [r for r in rows if r.get("status") == "ok" and r.get("transitions")]
    for r in rows:
        lines.append(f"| {r['size']} | {r['objects']} | {r['t_limit']} | "
                     f"{int(float(str(r.get('states') or 0))):,} | "
                     f"{int(float(str(r.get('transitions') or 0))):,} | {r['wall_s']} | "
                     f"{r['cpu_s']} | {r['peak_gb']} | {r.get('scratch_mb') or '-'} | "
                     f"{r['load']} |")
    if len(done) < 2:
        return "\n".join(lines)
    xs = [float(str(r["transitions"])) for r in done]
    lines += ["", "| measure | per transition | intercept | R^2 |", "|---|---|---|---|"]
    for key, name, unit, scale, per in MEASURES:
        a, b, r2 = fit(xs, [float(str(r.get(key) or 0)) for r in done])
        lines.append(f"| {name} | {a * scale:.3g} {per} | {b:.3g} {unit} | {r2:.4f} |")
    return "\n".join(lines)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--sizes", default="t300,t400,scenario2,o3-t600",
                    help="comma-separated, smallest first: scenario1, scenario2, tT (2 "
                         "objects, time limit T) or oN-tT (N objects)")
    ap.add_argument("--scratch", default=tempfile.gettempdir(),
                    help="the --scratch directory (default: the system temp directory)")
    csv_options(ap, "stream_growth.csv")
    args = ap.parse_args()
    if shown(args, table):
        return
    rows = append_rows(args.out, FIELDS, [
        (size, lambda size=size: run_one(size, args.scratch, args.timeout))  # type: ignore[misc]
        for size in args.sizes.split(",")])
    print(table(rows))


if __name__ == "__main__":
    main()
