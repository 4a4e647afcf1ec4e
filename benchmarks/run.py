"""The UAV case study at growing scale: compile time, states, transitions, build and check
times and peak memory, per engine and with/without the exact reductions.

    .venv/bin/python benchmarks/run.py [--instances small,default,...] [--configs ...]
                                       [--timeout S] [--memory GB] [--out benchmarks/results.csv]
    .venv/bin/python benchmarks/report.py   # then: the tables of docs/benchmarks.md from the CSV

Each configuration runs `afsmc verify --json` in its own process under a time cap and a
memory cap (the process group is killed when its resident memory passes the cap), so a
configuration that does not fit is recorded as "timeout" or "memory" rather than taking
the machine down. Compile time (parse, check, lower, emit PRISM) is measured in this
process. Results are appended to a CSV as they come and summarised as a markdown table;
compare configurations as ratios within one run (the machine is shared and noisy).
"""

from __future__ import annotations

import argparse
import csv
import json
import os
import signal
import statistics
import subprocess
import sys
import time
from dataclasses import dataclass

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, ROOT)

from afsmc.backends.prism import emit  # noqa: E402
from afsmc.compiler import load, lowered  # noqa: E402
from afsmc.lower.reduce import Reductions  # noqa: E402

UAV = os.path.join(ROOT, "examples", "uav.afsm")
AFSMC = [sys.executable, "-m", "afsmc.cli"]

# name -> (--const values or an @file); growing towards the paper's scenarios. The series
# starts at about a million states: below that a whole run takes seconds, most of it
# starting Python and Storm, and the test suite covers those sizes.
INSTANCES: dict[str, list[str]] = {
    "4x4-obj2-t300": ["--const", "WIDTH=4", "--const", "HEIGHT=4", "--const", "OBJECTS=2",
                      "--const", "T_LIMIT=300"],
    "5x5-obj2-t400": ["--const", "WIDTH=5", "--const", "HEIGHT=5", "--const", "OBJECTS=2",
                      "--const", "T_LIMIT=400"],
    # smaller instances, for a quick look (not in the default series)
    "small": ["--const", "WIDTH=2", "--const", "HEIGHT=2", "--const", "T_LIMIT=100"],
    "default": [],
    "obj2-t300": ["--const", "OBJECTS=2", "--const", "T_LIMIT=300"],
    "scenario2": ["@" + os.path.join(ROOT, "examples", "uav-scenario2.args")],
    "scenario1": ["@" + os.path.join(ROOT, "examples", "uav-scenario1.args")],
}

# name -> extra verify arguments
CONFIGS: dict[str, list[str]] = {
    "sparse": ["--engine", "sparse"],
    "sparse-noreduce": ["--engine", "sparse", "--no-reduce"],
    "sparse-bisim": ["--engine", "sparse", "--bisim"],
    "hybrid": ["--engine", "hybrid"],
    # Storm's default min/max solver instead of afsmc's value iteration on the hybrid engine
    "hybrid-topological": ["--engine", "hybrid", "--solver", "topological"],
    "hybrid-noreduce": ["--engine", "hybrid", "--no-reduce"],
    "auto": ["--engine", "auto"],
    # the paper's headline properties, min and max only: what fits the paper's scenario 1
    "hybrid-headline": ["--engine", "hybrid", "--no-uniform", "--property", "success",
                        "--property", "missed", "--property", "emergency"],
    "hybrid-success": ["--engine", "hybrid", "--no-uniform", "--property", "success"],
    # the same with the engine afsmc picks: the "auto, the paper's properties" row of
    # scenario 1 (measured there with /usr/bin/time -v around the plain command)
    "auto-headline": ["--engine", "auto", "--no-uniform", "--property", "success",
                      "--property", "missed", "--property", "emergency"],
    "auto-headline-topological": ["--engine", "auto", "--no-uniform", "--solver", "topological",
                                  "--property", "success", "--property", "missed",
                                  "--property", "emergency"],
    # every property, min/max and uniform, each query in its own Storm process
    "hybrid-split": ["--engine", "hybrid", "--split"],
}
# The same, one property per configuration (one row each, so that a long run keeps what it
# finished); report.py sums them into one "hybrid-split (per property)" row.
UAV_PROPERTIES = ["success", "missed", "timeout", "emergency", "success_by", "drops",
                  "recharges"]
SPLIT = "hybrid-split-"
for _p in UAV_PROPERTIES:
    CONFIGS[SPLIT + _p] = ["--engine", "hybrid", "--split", "--property", _p]

FIELDS = ["instance", "config", "status", "compile_s", "states", "transitions", "choices",
          "quotient_states", "build_s", "check_s", "uniform_states", "uniform_build_s",
          "uniform_check_s", "total_s", "peak_gb", "engine", "properties", "progress", "when",
          "property_seconds"]


@dataclass
class Row:
    data: dict[str, object]


def _consts(args: list[str]) -> dict[str, str]:
    """The --const values of an instance (expanding an @file as afsmc does)."""
    out: dict[str, str] = {}
    flat: list[str] = []
    for a in args:
        if a.startswith("@"):
            with open(a[1:], encoding="utf-8") as f:
                for line in f:
                    flat += line.split("#", 1)[0].split()
        else:
            flat.append(a)
    it = iter(flat)
    for a in it:
        if a in ("--const", "-c"):
            k, v = next(it).split("=", 1)
            out[k] = v
        elif a.startswith("--const="):
            k, v = a[len("--const="):].split("=", 1)
            out[k] = v
    return out


def compile_time(consts: dict[str, str]) -> float:
    """What `afsmc verify` spends compiling: parse, check, lower, reduce and emit the MDP and
    the uniform DTMC. The median of three runs after one more: the first run of a process
    also pays for imports and for loading the cached parser tables, which belong to
    starting Python (in "total s" as well), not to compiling this model."""
    def once() -> float:
        t0 = time.perf_counter()
        model = load(UAV, consts).model
        emit(lowered(model, "nondet", Reductions()))
        emit(lowered(model, "uniform", Reductions()))
        return time.perf_counter() - t0

    once()
    return statistics.median(once() for _ in range(3))


def _tree_rss(pid: int) -> int:
    """Resident memory of a process and all its descendants, bytes."""
    total = 0
    try:
        children = subprocess.run(["ps", "-o", "pid=,rss=", "--ppid", str(pid)],
                                  capture_output=True, text=True, check=False).stdout
        with open(f"/proc/{pid}/statm", encoding="ascii") as f:
            total += int(f.read().split()[1]) * os.sysconf("SC_PAGE_SIZE")
    except (OSError, ValueError):
        return total
    for line in children.splitlines():
        parts = line.split()
        if len(parts) == 2:
            total += _tree_rss(int(parts[0]))
    return total


def run_one(instance: str, config: str, timeout: float, memory_gb: float) -> dict[str, object]:
    args = [*AFSMC, "verify", UAV, *INSTANCES[instance], *CONFIGS[config], "--json",
            "--progress", "--max-states", "400000000"]
    start = time.perf_counter()
    # stderr (progress lines) goes to a file: on a timeout it says how far the run got
    log = open(os.path.join(ROOT, "benchmarks", f".{instance}-{config}.log"), "w+",  # noqa: SIM115
               encoding="utf-8")
    proc = subprocess.Popen(args, stdout=subprocess.PIPE, stderr=log, text=True,
                            cwd=ROOT, start_new_session=True)
    peak = 0
    status = "ok"
    while proc.poll() is None:
        time.sleep(0.5)
        peak = max(peak, _tree_rss(proc.pid))
        elapsed = time.perf_counter() - start
        if elapsed > timeout or peak > memory_gb * 2**30:
            status = "timeout" if elapsed > timeout else "memory"
            os.killpg(proc.pid, signal.SIGKILL)
            break
    out, _ = proc.communicate()
    total = time.perf_counter() - start
    log.seek(0)
    err = log.read()
    log.close()
    progress = [line for line in err.splitlines() if line.startswith("afsmc:")]
    row: dict[str, object] = {"instance": instance, "config": config, "status": status,
                              "total_s": round(total, 1), "peak_gb": round(peak / 2**30, 2),
                              "when": time.strftime("%Y-%m-%d %H:%M")}
    if status != "ok":
        row["progress"] = " | ".join(progress[-4:])
        return row
    try:
        data = json.loads(out)
    except json.JSONDecodeError:
        row["status"] = "error: " + (err.strip().splitlines() or ["no output"])[-1][:80]
        return row
    if "diagnostics" in data:
        row["status"] = "error: " + data["diagnostics"][0]["message"][:80]
        return row
    m, u, t = data["model"], data.get("uniform_model"), data["timings"]
    row.update(states=m["states"], transitions=m["transitions"], choices=m.get("choices"),
               quotient_states=m.get("quotient_states"), build_s=round(t["build"], 2),
               check_s=round(t["check"], 2), engine=m.get("engine"))
    if u:
        row.update(uniform_states=u["states"], uniform_build_s=round(t.get("uniform_build", 0), 2),
                   uniform_check_s=round(t.get("uniform_check", 0), 2))
    row["properties"] = json.dumps({p["name"]: [p["min"], p["max"], p["uniform"], p["value"]]
                                    for p in data["properties"]}, separators=(",", ":"))
    # Storm's check time of each answer, in the same order
    row["property_seconds"] = json.dumps(
        {p["name"]: [p.get("seconds", {}).get(k) for k in ("min", "max", "uniform", "value")]
         for p in data["properties"]}, separators=(",", ":"))
    return row


def markdown(rows: list[dict[str, object]]) -> str:
    head = ["instance", "config", "status", "compile s", "states", "transitions", "quotient",
            "build s", "check s", "uniform build+check s", "total s", "peak GB", "engine"]
    lines = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    for r in rows:
        ub = r.get("uniform_build_s")
        uc = r.get("uniform_check_s")
        uni = f"{float(ub) + float(uc):.1f}" if ub not in (None, "") and uc not in (None, "") else ""  # type: ignore[arg-type]
        cells = [r.get("instance"), r.get("config"), r.get("status"), r.get("compile_s"),
                 _n(r.get("states")), _n(r.get("transitions")), _n(r.get("quotient_states")),
                 r.get("build_s"), r.get("check_s"), uni, r.get("total_s"), r.get("peak_gb"),
                 r.get("engine")]
        lines.append("| " + " | ".join("" if c in (None, "") else str(c) for c in cells) + " |")
    return "\n".join(lines)


def _n(v: object) -> str:
    try:
        return f"{int(v):,}"  # type: ignore[call-overload]
    except (TypeError, ValueError):
        return ""


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--instances", default="4x4-obj2-t300,5x5-obj2-t400,scenario2",
                    help="comma-separated, of: " + ", ".join(INSTANCES)
                    + " (default: %(default)s)")
    ap.add_argument("--configs", default=",".join(CONFIGS),
                    help="comma-separated, of: " + ", ".join(CONFIGS) + " (default: all)")
    ap.add_argument("--timeout", type=float, default=1800, help="seconds per configuration")
    ap.add_argument("--memory", type=float, default=20, help="GB per configuration")
    ap.add_argument("--out", default=os.path.join(ROOT, "benchmarks", "results.csv"),
                    help="the CSV the rows are appended to (default: %(default)s)")
    args = ap.parse_args()
    for given, known, what in ((args.instances, INSTANCES, "instance"),
                               (args.configs, CONFIGS, "configuration")):
        unknown = [n for n in given.split(",") if n not in known]
        if unknown:
            ap.error(f"unknown {what} {', '.join(unknown)}; known: {', '.join(known)}")
    rows: list[dict[str, object]] = []
    if os.path.exists(args.out):
        with open(args.out, newline="", encoding="utf-8") as f:
            old = list(csv.DictReader(f))
        if old and list(old[0].keys()) != FIELDS:  # written by an older version: widen it
            with open(args.out, "w", newline="", encoding="utf-8") as f:
                w = csv.DictWriter(f, fieldnames=FIELDS)
                w.writeheader()
                w.writerows({k: r.get(k, "") for k in FIELDS} for r in old)
    new = not os.path.exists(args.out)
    with open(args.out, "a", newline="", encoding="utf-8") as f:
        writer = csv.DictWriter(f, fieldnames=FIELDS)
        if new:
            writer.writeheader()
        for instance in args.instances.split(","):
            ctime = round(compile_time(_consts(INSTANCES[instance])), 3)
            for config in args.configs.split(","):
                print(f"{instance} / {config} ...", file=sys.stderr, flush=True)
                row = run_one(instance, config, args.timeout, args.memory)
                row["compile_s"] = ctime
                rows.append(row)
                writer.writerow({k: row.get(k, "") for k in FIELDS})
                f.flush()
                print(f"  {row['status']}: {_n(row.get('states'))} states, "
                      f"{row.get('total_s')} s, {row.get('peak_gb')} GB", file=sys.stderr, flush=True)
    print(markdown(rows))
    return 0


if __name__ == "__main__":
    sys.exit(main())
