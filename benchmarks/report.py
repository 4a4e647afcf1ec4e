"""Write the measured tables of docs/benchmarks.md from benchmarks/results.csv.

    .venv/bin/python benchmarks/report.py [--csv benchmarks/results.csv] [--doc docs/benchmarks.md]

The document keeps its prose; the parts between `<!-- begin NAME -->` and `<!-- end NAME -->`
are replaced: `growing` (the growing instances), `ratios` (reduced against unreduced and
the other ratios, from the same run), `scenarios` (the paper's scenarios), `values` (the
properties of the scenarios), `perprop` (the per-property runs) and `compile` (compile time
as a share of the whole). The latest row of each (instance, configuration) counts.
"""

from __future__ import annotations

import argparse
import csv
import json
import os
import re
import sys

# run.py sits beside this script, so its directory is on sys.path
from run import SPLIT
from run import UAV_PROPERTIES as PROPS

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
GROWING = ["4x4-obj2-t300", "5x5-obj2-t400"]
SCENARIOS = ["scenario2", "scenario1"]
PAPER = {"scenario1": "116,191,709 states; built in 488 s; 298–813 s per property",
         "scenario2": "35,649,503 states; built in 77 s"}


def _n(v: str) -> str:
    try:
        return f"{int(v):,}"
    except ValueError:
        return v


def _f(v: str, digits: int = 1) -> str:
    try:
        return f"{float(v):.{digits}f}"
    except ValueError:
        return v


def _share(r: dict[str, str]) -> str:
    """Compile time as a share of the whole `afsmc verify` run (which compiles too)."""
    try:
        c, t = float(r["compile_s"]), float(r["total_s"])
    except (KeyError, ValueError):
        return ""
    return f"{100 * c / t:.2f}%" if t > 0 else ""


def compile_summary(rows: list[dict[str, str]]) -> str:
    shares = [(float(r["compile_s"]) / float(r["total_s"]), r)
              for r in rows if r["status"] == "ok" and r.get("compile_s") and r.get("total_s")]
    if not shares:
        return "No completed run yet."
    worst, r = max(shares, key=lambda x: x[0])
    return (f"Compilation (parse, check, lower, reduce, emit PRISM) is at most "
            f"{100 * worst:.2f}% of the end-to-end time in every completed row above "
            f"(largest share: {r['instance']}, {r['config']}, {float(r['compile_s']):.3f} s "
            f"of {float(r['total_s']):.1f} s).")


def table(rows: list[dict[str, str]]) -> str:
    head = ["instance", "config", "status", "compile s", "compile share", "states", "transitions", "bisim quotient",
            "build s", "check s", "uniform build + check s", "total s", "peak GB", "engine",
            "measured"]
    out = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    for r in rows:
        uni = ""
        if r.get("uniform_build_s") and r.get("uniform_check_s"):
            uni = f"{float(r['uniform_build_s']) + float(r['uniform_check_s']):.1f}"
        status = r["status"]
        if status != "ok" and r.get("progress"):
            status += f" ({r['progress'].split(' | ')[-1].removeprefix('afsmc: ')})"
        cells = [r["instance"], r["config"], status, _f(r["compile_s"], 3), _share(r),
                 _n(r["states"]),
                 _n(r["transitions"]), _n(r["quotient_states"]), _f(r["build_s"]),
                 _f(r["check_s"]), uni, _f(r["total_s"]), _f(r["peak_gb"], 2), r["engine"],
                 r.get("when", "")]
        out.append("| " + " | ".join(cells) + " |")
    return "\n".join(out)


def _sum(a: float | None, b: float | None) -> float | None:
    return a + b if a is not None and b is not None else None


def ratios(latest: dict[tuple[str, str], dict[str, str]], instances: list[str]) -> str:
    out = ["| instance | states: reduced / unreduced | total time: reduced / unreduced | "
           "bisim quotient / reduced states | check time: bisim / plain | hybrid / sparse total time | "
           "hybrid check time: value iteration / topological |",
           "|---|---|---|---|---|---|---|"]
    for inst in instances:
        def get(config: str, key: str, inst: str = inst) -> float | None:
            r = latest.get((inst, config))
            if r is None or r["status"] != "ok" or not r.get(key):
                return None
            return float(r[key])

        def ratio(a: float | None, b: float | None, digits: int = 2) -> str:
            return f"{a / b:.{digits}f}" if a is not None and b else ""

        cells = [inst,
                 ratio(get("sparse", "states"), get("sparse-noreduce", "states")),
                 ratio(get("sparse", "total_s"), get("sparse-noreduce", "total_s")),
                 ratio(get("sparse-bisim", "quotient_states"), get("sparse", "states"), 3),
                 ratio(max(get("sparse-bisim", "check_s") or 0, 0.01) if get("sparse-bisim", "check_s") is not None else None,
                       max(get("sparse", "check_s") or 0, 0.01)),
                 ratio(get("hybrid", "total_s"), get("sparse", "total_s"), 1),
                 # the checks of the MDP and of the uniform DTMC
                 ratio(_sum(get("hybrid", "check_s"), get("hybrid", "uniform_check_s")),
                       _sum(get("hybrid-topological", "check_s"),
                            get("hybrid-topological", "uniform_check_s")))]
        if any(cells[1:]):
            out.append("| " + " | ".join(cells) + " |")
    return "\n".join(out)


def values(latest: dict[tuple[str, str], dict[str, str]]) -> str:
    out = []
    for inst in SCENARIOS:
        done = [latest[(i, c)] for (i, c) in sorted(latest) if i == inst
                and (latest[(i, c)]["status"] == "ok" or c.startswith("hybrid-split ("))
                and latest[(i, c)].get("properties") and c != "sparse-noreduce"]
        if not done:
            continue
        # the most complete run: most properties, then uniform values too
        row = max(done, key=lambda r: (len(json.loads(r["properties"])),
                                       bool(r.get("uniform_check_s"))))
        props = json.loads(row["properties"])
        # Storm's check time of each answer, where the run recorded it
        secs = json.loads(row.get("property_seconds") or "{}")
        out.append(f"**{inst}** (`{row['config']}`):\n")
        head = "| property | min | max | uniform |"
        out.append(head + (" check s (min, max, uniform) |" if secs else ""))
        out.append("|---|---|---|---|" + ("---|" if secs else ""))
        for name, (lo, hi, uni, val) in props.items():
            if val is not None:
                lo = hi = uni = val
            cells = [name] + ["" if x is None else f"{x:.4f}" for x in (lo, hi, uni)]
            if secs:
                t = secs.get(name, [None] * 4)
                cells.append(", ".join("-" if x is None else f"{x:.0f}" for x in
                                       ([t[3]] if t[3] is not None else t[:3])))
            out.append("| " + " | ".join(cells) + " |")
        out.append("")
    return "\n".join(out).strip()


def aggregate(latest: dict[tuple[str, str], dict[str, str]]) -> None:
    """Sum the per-property `hybrid-split-NAME` rows of an instance into one row."""
    instances = sorted({i for (i, c) in latest if c.startswith(SPLIT)})
    for inst in instances:
        parts = [r for (i, c), r in sorted(latest.items()) if i == inst and c.startswith(SPLIT)]
        ok = [r for r in parts if r["status"] == "ok"]
        props: dict[str, object] = {}
        for r in sorted(ok, key=lambda r: PROPS.index(r["config"][len(SPLIT):])
                        if r["config"][len(SPLIT):] in PROPS else 99):
            props |= json.loads(r["properties"])

        def total(key: str, rows: list[dict[str, str]] = ok) -> str:
            vals = [float(r[key]) for r in rows if r.get(key)]
            return f"{sum(vals):.1f}" if vals else ""

        status = "ok" if len(ok) == len(parts) == len(PROPS) else (
            f"{len(ok)} of {len(PROPS)} properties done" + "".join(
                f"; {r['config'][len(SPLIT):]}: {r['status']}" for r in parts if r["status"] != "ok"))
        first = ok[0] if ok else parts[0]
        latest[(inst, "hybrid-split (per property)")] = {
            **first, "config": "hybrid-split (per property)", "status": status,
            "build_s": total("build_s"), "check_s": total("check_s"),
            "uniform_build_s": total("uniform_build_s"), "uniform_check_s": total("uniform_check_s"),
            "total_s": total("total_s", parts),
            "peak_gb": f"{max(float(r['peak_gb']) for r in parts if r.get('peak_gb')):.2f}",
            "properties": json.dumps(props), "progress": "",
            "when": max(r.get("when", "") for r in parts)}


def per_property(latest: dict[tuple[str, str], dict[str, str]]) -> str:
    """One row per property of the per-property runs (scenario 1)."""
    out = ["| instance | property | status | builds + checks s (min, max, uniform) | peak GB | "
           "min | max | uniform |", "|---|---|---|---|---|---|---|---|"]
    for (inst, config), r in sorted(latest.items(), key=lambda kv: (
            kv[0][0], PROPS.index(kv[0][1][len(SPLIT):]) if kv[0][1][len(SPLIT):] in PROPS else 99)):
        if not config.startswith(SPLIT):
            continue
        name = config[len(SPLIT):]
        vals = json.loads(r["properties"]).get(name, [None] * 4) if r.get("properties") else [None] * 4
        cells = [inst, name, r["status"][:90], _f(r["total_s"]), _f(r["peak_gb"], 2)]
        cells += ["" if x is None else f"{x:.4f}" for x in vals[:3]]
        out.append("| " + " | ".join(cells) + " |")
    return "\n".join(out) if len(out) > 2 else "No per-property run yet."



def replace(doc: str, name: str, text: str) -> str:
    pattern = re.compile(rf"(<!-- begin {name} -->\n)(?:.*?\n)?(<!-- end {name} -->)", re.S)
    if not pattern.search(doc):
        raise SystemExit(f"docs: no <!-- begin {name} --> ... <!-- end {name} --> block")
    return pattern.sub(lambda m: m.group(1) + text + "\n" + m.group(2), doc)


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--csv", default=os.path.join(ROOT, "benchmarks", "results.csv"))
    ap.add_argument("--doc", default=os.path.join(ROOT, "docs", "benchmarks.md"))
    args = ap.parse_args()
    with open(args.csv, newline="", encoding="utf-8") as f:
        rows = list(csv.DictReader(f))
    latest: dict[tuple[str, str], dict[str, str]] = {}
    for r in rows:
        latest[(r["instance"], r["config"])] = r
    per_prop = per_property(latest)
    aggregate(latest)
    latest = {k: v for k, v in latest.items() if not k[1].startswith(SPLIT)}
    ordered = sorted(latest.values(), key=lambda r: (
        (GROWING + SCENARIOS).index(r["instance"]) if r["instance"] in GROWING + SCENARIOS else 99,
        r["config"]))
    with open(args.doc, encoding="utf-8") as f:
        doc = f.read()
    doc = replace(doc, "growing", table([r for r in ordered if r["instance"] in GROWING]))
    doc = replace(doc, "ratios", ratios(latest, GROWING + SCENARIOS))
    doc = replace(doc, "scenarios", table([r for r in ordered if r["instance"] in SCENARIOS]))
    doc = replace(doc, "values", values(latest))
    doc = replace(doc, "perprop", per_prop)
    shown = [r for r in ordered if r["instance"] in GROWING + SCENARIOS]
    doc = replace(doc, "compile", compile_summary(shown))
    tmp = args.doc + ".tmp"
    with open(tmp, "w", encoding="utf-8") as f:
        f.write(doc)
    os.replace(tmp, args.doc)
    print(f"wrote {args.doc}", file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main())
