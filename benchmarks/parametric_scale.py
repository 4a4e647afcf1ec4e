"""How far Storm's parametric engine gets on a UAV instance with interval probabilities.

    python benchmarks/parametric_scale.py [--const NAME=VALUE ...] [-p PROPERTY]
        [--intervals P_INIT_FAIL=0.0202:0.0262,...]

Runs the steps of `afsmc verify`'s bounds over interval probabilities
(afsmc.verify.engines.parametric.extremes) one by one on examples/uav.afsm, printing each step's
wall time and the process's peak RSS as it finishes (flushed, so a run stopped from outside
still says how far it got). The point-valued checks are not run: docs/benchmarks.md has
them. Stop it from outside after a time limit (docs/benchmarks.md used 15 minutes).
"""

from __future__ import annotations

import argparse
import re
import resource
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
INTERVALS = "P_INIT_FAIL=0.0202:0.0262,P_DROP_LIFT=0.0452:0.0538,P_DROP=0.0101:0.0145"


def peak_mb() -> float:
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024


def step(name: str, t0: float) -> float:
    now = time.perf_counter()
    print(f"{name}: {now - t0:.1f} s, peak RSS {peak_mb():,.0f} MB", flush=True)
    return now


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--const", action="append", default=[], metavar="NAME=VALUE")
    ap.add_argument("-p", "--property", default="success")
    ap.add_argument("--intervals", default=INTERVALS)
    args = ap.parse_args()
    sys.path.insert(0, str(ROOT))
    from afsmc.compiler import lowered
    from afsmc.verify.core.api import load_with_formulas, select
    from afsmc.verify.engines import parametric
    from afsmc.verify.plan.precision import PARAMETER_PRECISION

    text = (ROOT / "examples" / "uav.afsm").read_text(encoding="utf-8")
    for item in args.intervals.split(","):
        name, rng = item.split("=")
        lo, hi = rng.split(":")
        text, n = re.subn(rf"^const prob {name}( *)= [0-9.]+ ", rf"const prob {name}\1= [{lo}, {hi}] ",
                          text, flags=re.M)
        assert n == 1, name
    consts = dict(c.split("=", 1) for c in args.const)
    with tempfile.TemporaryDirectory() as tmp:
        path = str(Path(tmp) / "uav_iv.afsm")
        Path(path).write_text(text, encoding="utf-8")
        t = t0 = time.perf_counter()
        loaded = load_with_formulas(path, consts, [])
        props = select(loaded.model, [args.property], loaded.adhoc)
        low = lowered(loaded.model, "nondet", None)
        t = step("load and lower", t)
        box = parametric.interval_box(low.model)
        plow = parametric.with_parameters(low, box)
        qs = parametric.queries(plow, props[0])
        src = parametric.source(plow, "prism")
        t = step(f"emit the PRISM model ({len(src.model_text):,} characters)", t)
        built = parametric.Parametric(src, sorted({q.text for q in qs}))
        m = built.model
        t = step(f"build the parametric model ({m.nr_states:,} states, "
                 f"{m.nr_transitions:,} transitions, {m.nr_choices:,} choices)", t)
        parametric.check_box(low, built, box)
        t = step("check the box is well defined", t)
        for q in qs:
            v, at = built.extremal(q, box, PARAMETER_PRECISION)
            t = step(f"{q.end} of {props[0].name}{' (complement)' if q.complement else ''}: "
                     f"{1 - v if q.complement else v:.6f} at {at}", t)
        print(f"total {time.perf_counter() - t0:.1f} s, peak RSS {peak_mb():,.0f} MB")
    return 0


if __name__ == "__main__":
    sys.exit(main())
