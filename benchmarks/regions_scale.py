"""`afsmc regions` at scale: scenario 2 over two interval probabilities, timed, and its
decided regions checked at sampled points against point-valued `afsmc verify` runs
(docs/benchmarks.md, "Regions on scenario 2 by monotonicity").

    python benchmarks/regions_scale.py [--check N] [--seed S] [--json FILE]

Runs, in a fresh process under /usr/bin/time, `afsmc regions examples/uav.afsm
@examples/uav-scenario2.args --param P_DROP=0.005:0.03 --param P_INIT_FAIL=0.01:0.05
--require 'P>=0.78 [ F "success" ]' --coverage 0.9 --json` (or reads its JSON from
--json FILE instead), prints the coverage, rounds, boxes, the time afsmc reports and
the wall time, CPU time and peak RSS. With --check N, picks N points at random inside
the decided regions (seeded) and runs a point-valued `afsmc verify -p success` at each
(examples/uav.afsm with the two probabilities set to the point): the region's verdict
must be what the point's Pmin says (the requirement is a bare P>= on the MDP: Pmin).
"""

from __future__ import annotations

import argparse
import json
import random
import re
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from benchmarks.lifting_side_by_side import timed  # noqa: E402

SCENARIO2 = ROOT / "examples" / "uav-scenario2.args"
ARGS = [str(ROOT / "examples" / "uav.afsm"), f"@{SCENARIO2}", "--param", "P_DROP=0.005:0.03",
        "--param", "P_INIT_FAIL=0.01:0.05", "--require", 'P>=0.78 [ F "success" ]',
        "--coverage", "0.9"]
THRESHOLD = 0.78


def at_point(values: dict[str, float], tmp: Path) -> Path:
    """examples/uav.afsm with each named probability set to its value."""
    text = (ROOT / "examples" / "uav.afsm").read_text(encoding="utf-8")
    for name, v in values.items():
        text, n = re.subn(rf"^const prob {name}( *)= [^;]+;", rf"const prob {name}\1= {v!r};",
                          text, flags=re.M)
        assert n == 1, name
    path = tmp / "uav_point.afsm"
    path.write_text(text, encoding="utf-8")
    return path


def check(regions: list[dict[str, object]], n: int, seed: int) -> int:
    """Points in decided regions against point-valued verify runs; the disagreements."""
    rng = random.Random(seed)
    decided = [r for r in regions if r["verdict"] != "unknown"]
    wrong = 0
    consts = [w for line in SCENARIO2.read_text(encoding="utf-8").splitlines()
              if not line.startswith("#") for w in line.split()]
    with tempfile.TemporaryDirectory() as tmp:
        for _ in range(n):
            r = rng.choice(decided)
            bounds: dict[str, list[float]] = r["bounds"]  # type: ignore[assignment]
            point = {k: rng.uniform(lo, hi) for k, (lo, hi) in bounds.items()}
            path = at_point(point, Path(tmp))
            out = subprocess.run([sys.executable, "-m", "afsmc", "verify", str(path),
                                  *consts, "-p", "success", "--json"],
                                 capture_output=True, text=True, check=False,
                                 env={"PYTHONPATH": str(ROOT), "PATH": "/usr/bin:/bin"})
            (prop,) = json.loads(out.stdout)["properties"]
            holds = prop["min"] >= THRESHOLD
            agree = holds == (r["verdict"] == "holds")
            wrong += not agree
            print(f"  {point}: Pmin {prop['min']:.6f}, region {r['verdict']}: "
                  f"{'agrees' if agree else 'DISAGREES'}", flush=True)
    return wrong


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--check", type=int, default=0, metavar="N")
    ap.add_argument("--seed", type=int, default=49)
    ap.add_argument("--json", type=Path, help="the regions' JSON of an earlier run")
    args = ap.parse_args()
    if args.json is not None:
        out = json.loads(args.json.read_text(encoding="utf-8"))
    else:
        text, cost = timed([sys.executable, "-m", "afsmc", "regions", *ARGS, "--json"])
        out = json.loads(text)
        print(f"regions: {cost}")
    print(f"coverage {out['coverage']:.1%} (holds {out['holds']:.1%}, fails "
          f"{out['fails']:.1%}) in {out['rounds']} rounds, {len(out['regions'])} regions, "
          f"{out['seconds']:.1f} s reported by afsmc, engine {out['engine']}")
    if args.check:
        wrong = check(out["regions"], args.check, args.seed)
        print(f"{args.check - wrong} of {args.check} points agree")
        return 1 if wrong else 0
    return 0


if __name__ == "__main__":
    sys.exit(main())
