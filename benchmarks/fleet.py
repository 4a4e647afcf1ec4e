"""A fleet of N alike robots sharing K chargers, verified with and without `--symmetry`
(issue 46), each run under `/usr/bin/time -v`.

    .venv/bin/python benchmarks/fleet.py [--robots 2,3,4,5,6] [--whole-up-to 5]
        [--max-states 3000000] [--out benchmarks/fleet.csv] [--table]

The mission is `FLEET` below with its robots written out (`agents r1 = Robot(), ...`,
labels and rewards over all of them), N robots, K = 2 chargers. Each N runs `verify
--json` with `--symmetry`, and with `--no-symmetry` for N up to --whole-up-to; a larger N without
it runs under `--max-states` (it stops at E405, and the row says so). The rows go to the
CSV (states, times, peak memory, every value) and are printed as a markdown table with
the largest difference between the two runs' values of one N.
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import tempfile

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, ROOT)

from benchmarks.explicit import append_rows, csv_options, shown, timed_row  # noqa: E402

FLEET = """\
// A fleet of alike warehouse robots sharing a few chargers (benchmarks/fleet.py).
machine fleet;

compose interleaving;

const int ORDERS   = 2;        // orders each robot must pick
const int B_FULL   = 3;        // battery, in picks' worth
const int B_LOW    = 1;        // take a charger at or below this, if one is free
const int K        = 2;        // chargers
const int DRAIN    = [1, 2];   // battery a failed grasp costs
const prob P_GRASP = 0.9;      // a pick succeeds
const prob P_PLUG  = 0.95;     // a charge completes (else the robot tries again)

var free : [0..K] init K;  // chargers free

agent Robot() {
    var b    : [0..B_FULL] init B_FULL clamp;
    var done : [0..ORDERS] init 0;

    mode Work     = 0 initial;
    mode Charging = 1;
    mode Finished = 2 final;
    mode Stranded = 3 final;

    action Pick in Work when done < ORDERS && (b > B_LOW || b > 0 && free == 0) {
        P_GRASP:     done += 1, b -= 1;
        1 - P_GRASP: b -= DRAIN;
    }
    action Charge in Work when done < ORDERS && b <= B_LOW && b > 0 && free > 0 {
        goto Charging, free := free - 1;
    }
    action Flat in Work when done < ORDERS && b == 0 {
        goto Stranded;
    }
    action Stop in Work when done == ORDERS {
        goto Finished;
    }
    action Unplug in Charging {
        P_PLUG:     goto Work, b := B_FULL, free := min(free + 1, K);
        1 - P_PLUG: b := b;
    }
}
"""


def fleet(n: int) -> str:
    """The mission with `n` robots written out."""
    robots = [f"r{i}" for i in range(1, n + 1)]
    lines = [FLEET, "agents " + ", ".join(f"{r} = Robot()" for r in robots) + ";", "",
             "label finished = " + " && ".join(f"{r}.mode == Finished" for r in robots) + ";",
             "label stranded = " + " || ".join(f"{r}.mode == Stranded" for r in robots) + ";",
             "", "rewards picks {", *(f"    [{r}.Pick] true : 1;" for r in robots), "}", "",
             'property shift  = P=? [ F "finished" ];',
             'property strand = P<=0.5 [ F "stranded" ];',
             'property picks  = R{"picks"}=? [ F "finished" || "stranded" ];', ""]
    return "\n".join(lines)


FIELDS = ["measured", "load", "robots", "symmetry", "status", "wall_s", "cpu_s", "peak_gb",
          "states", "transitions", "build_s", "check_s", "values"]


def measure(n: int, symmetry: bool, max_states: int | None, timeout: float,
            folder: str) -> dict[str, object]:
    path = os.path.join(folder, f"fleet{n}.afsm")
    with open(path, "w", encoding="utf-8") as f:
        f.write(fleet(n))
    args = ["verify", path, "--json", "--symmetry" if symmetry else "--no-symmetry",
            *(["--max-states", str(max_states)] if max_states is not None else [])]
    out, row = timed_row(args, timeout, {"robots": n, "symmetry": symmetry}, peak_digits=3)
    if out is not None and isinstance(out.get("model"), dict):
        m, tm = out["model"], out["timings"]
        assert isinstance(m, dict) and isinstance(tm, dict)
        props = out["properties"]
        assert isinstance(props, list)
        row |= {"states": m.get("states"), "transitions": m.get("transitions"),
                "build_s": tm.get("build"), "check_s": tm.get("check"),
                "values": json.dumps({p["name"]: [p.get("min"), p.get("max")]
                                      for p in props})}
    return row


def table(rows: list[dict[str, object]]) -> str:
    lines = ["| robots | symmetry | states | wall s | CPU s | peak GB | build + check s | "
             "max diff | status |", "|---|---|---|---|---|---|---|---|---|"]
    whole: dict[str, dict[str, list[float]]] = {}
    for r in rows:
        if str(r["symmetry"]) == "False" and r.get("values"):
            whole[str(r["robots"])] = json.loads(str(r["values"]))
    for r in rows:
        diff = ""
        ref = whole.get(str(r["robots"]))
        if ref is not None and r.get("values") and str(r["symmetry"]) == "True":
            mine = json.loads(str(r["values"]))
            diff = f"{max(abs(a - b) for k in ref for a, b in zip(ref[k], mine[k], strict=True)):.1e}"
        states = f"{int(str(r['states'])):,}" if r.get("states") else "–"
        bc = (f"{float(str(r['build_s'])):.2f} + {float(str(r['check_s'])):.2f}"
              if r.get("build_s") else "–")
        lines.append(f"| {r['robots']} | {'yes' if str(r['symmetry']) == 'True' else 'no'} | "
                     f"{states} | {r['wall_s']} | {r['cpu_s']} | {r['peak_gb']} | {bc} | "
                     f"{diff} | {r['status']} |")
    return "\n".join(lines)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--robots", default="2,3,4,5,6")
    ap.add_argument("--whole-up-to", type=int, default=5)
    ap.add_argument("--max-states", type=int, default=3_000_000)
    csv_options(ap, "fleet.csv")
    args = ap.parse_args()
    if shown(args, table):
        return
    with tempfile.TemporaryDirectory(prefix="afsmc-fleet-") as folder:
        runs = []
        for n in (int(x) for x in args.robots.split(",")):
            limit = None if n <= args.whole_up_to else args.max_states
            runs += [(f"N={n} whole", lambda n=n, limit=limit: measure(
                        n, False, limit, args.timeout, folder)),
                     (f"N={n} symmetry", lambda n=n: measure(n, True, None, args.timeout,
                                                             folder))]
        rows = append_rows(args.out, FIELDS, runs)
    print(table(rows))


if __name__ == "__main__":
    main()
