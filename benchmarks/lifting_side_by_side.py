"""Bounds over interval probabilities: afsmc's parameter lifting against Storm's
parametric route, side by side, on a UAV instance (docs/benchmarks.md, "Interval
probabilities by parameter lifting").

    python benchmarks/lifting_side_by_side.py [--const NAME=VALUE ...] [-p PROPERTY ...]
        [--storm]

Writes examples/uav.afsm with P_INIT_FAIL, P_DROP_LIFT and P_DROP as their 95% intervals
to a temporary folder and runs, each in a fresh process under /usr/bin/time: the
point-valued `afsmc verify` (the file as it is), the same with the intervals (bounds by
parameter lifting), and with --storm the bounds by Storm's parametric engine alone
(afsmc.verify.engines.parametric.extremes, the route verify falls back to). Prints the wall
time and peak RSS of each, and verify's bounds.
"""

from __future__ import annotations

import argparse
import re
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
INTERVALS = {"P_INIT_FAIL": "[0.0202, 0.0262]", "P_DROP_LIFT": "[0.0452, 0.0538]",
             "P_DROP": "[0.0101, 0.0145]"}
STORM = """
import sys, time
from afsmc.compiler import load, lowered
from afsmc.verify.engines import parametric
m = load(sys.argv[1], dict(a.split("=", 1) for a in sys.argv[3:])).model
props = [p for p in m.properties if not sys.argv[2] or p.name in sys.argv[2].split(",")]
t = time.perf_counter()
for e in parametric.extremes(lowered(m, "nondet"), props):
    print(e.name, e.min_attained, e.max_attained)
print(f"parametric route {time.perf_counter() - t:.1f} s")
"""


def timed(cmd: list[str]) -> tuple[str, str]:
    """The command's stdout, and its wall time, CPU time (user) and peak RSS as
    /usr/bin/time -v says (on a shared machine the CPU time is the steadier figure)."""
    out = subprocess.run(["/usr/bin/time", "-v", *cmd], capture_output=True, text=True,
                         env={"PYTHONPATH": str(ROOT), "PATH": "/usr/bin:/bin"}, check=False)
    wall = re.search(r"Elapsed \(wall clock\) time.*: (\S+)", out.stderr)
    rss = re.search(r"Maximum resident set size \(kbytes\): (\d+)", out.stderr)
    user = re.search(r"User time \(seconds\): (\S+)", out.stderr)
    return out.stdout, (f"wall {wall.group(1) if wall else '?'}, CPU (user) "
                        f"{user.group(1) if user else '?'} s, peak RSS "
                        f"{int(rss.group(1)) // 1024 if rss else 0} MB")


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--const", action="append", default=[], metavar="NAME=VALUE")
    ap.add_argument("-p", "--property", action="append", default=[])
    ap.add_argument("--storm", action="store_true", help="also Storm's parametric route")
    args = ap.parse_args()
    text = (ROOT / "examples" / "uav.afsm").read_text(encoding="utf-8")
    for name, interval in INTERVALS.items():
        text, n = re.subn(rf"^const prob {name}( *)= [0-9.]+ ", rf"const prob {name}\1= {interval} ",
                          text, flags=re.M)
        assert n == 1, name
    flags = [f for c in args.const for f in ("--const", c)] + [
        f for p in args.property for f in ("-p", p)]
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "uav_iv.afsm"
        path.write_text(text, encoding="utf-8")
        verify = [sys.executable, "-m", "afsmc", "verify"]
        _, point = timed([*verify, str(ROOT / "examples" / "uav.afsm"), *flags])
        print(f"point-valued verify: {point}", flush=True)
        out, lifted = timed([*verify, str(path), *flags])
        print(out)
        print(f"verify with the intervals (parameter lifting): {lifted}", flush=True)
        if args.storm:
            out, storm = timed([sys.executable, "-c", STORM, str(path), ",".join(args.property),
                                *args.const])
            print(out)
            print(f"Storm's parametric route alone: {storm}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
