"""afsmc's exploration (afsmc.verify.explorer.explore_graph.explore) with its bookkeeping
compiled (AFSMC_KERNELS=numba: afsmc.verify.kernels.hashing) against the numpy reference
(AFSMC_KERNELS=numpy), alternately, each in a fresh process.

    .venv/bin/python benchmarks/explore_kernels.py [--instance scenario2] [--repeat 2]

Each run explores the MDP of `afsmc verify` on the instance (the queries' targets and
rewards planned as verify plans them) and prints the exploration's CPU time (user +
system of that process, numba's import and its cached kernels' loading excluded: they are
taken once per process, before it), the process's peak resident memory, the counts, and a
digest of every array explored: equal digests are the same states, in the same order,
with the same successors, probabilities, rewards and labels, bit for bit. CPU time, not
wall time, is the figure to compare on a shared machine.
"""

from __future__ import annotations

import argparse
import hashlib
import json
import os
import resource
import subprocess
import sys
import time
from typing import Any

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, ROOT)

INSTANCES = {
    "scenario2": {"OBJECTS": "2", "T_LIMIT": "500", "DEADLINE": "500", "WIDTH": "7",
                  "HEIGHT": "7", "ALPHA": "0.085"},
    "7x7-obj2-t300": {"OBJECTS": "2", "T_LIMIT": "300", "DEADLINE": "300", "WIDTH": "7",
                      "HEIGHT": "7", "ALPHA": "0.085"},
}


def _digest(x: Any, h: Any) -> None:
    """Every array reachable from `x` (dataclasses, dicts, lists) into the hash `h`."""
    import dataclasses

    import numpy as np

    if isinstance(x, np.ndarray):
        h.update(str((x.dtype, x.shape)).encode())
        h.update(np.ascontiguousarray(x).tobytes())
    elif dataclasses.is_dataclass(x):
        for f in dataclasses.fields(x):
            _digest(getattr(x, f.name), h)
    elif isinstance(x, dict):
        for k in sorted(x):
            h.update(str(k).encode())
            _digest(x[k], h)
    elif isinstance(x, (list, tuple)):
        for v in x:
            _digest(v, h)
    else:
        h.update(repr(x).encode())


def child(instance: str) -> dict[str, Any]:
    """One exploration in this process (AFSMC_KERNELS set by the parent)."""
    import numpy as np

    from afsmc.backends.prism import property_variants
    from afsmc.compiler import load, lowered
    from afsmc.verify import kernels
    from afsmc.verify.engines import explicit
    from afsmc.verify.explorer import explore, explore_graph

    low = lowered(load(os.path.join(ROOT, "examples", "uav.afsm"), INSTANCES[instance]).model,
                  "nondet")
    names = tuple(n for p in low.model.properties for n, _ in property_variants(low, p))
    plan = explicit.plan(low, names)
    c = explore.compile_model(low, plan.targets, plan.rewards)
    if kernels.enabled(kernels.THRESHOLD):  # numba imported and its kernels loaded first
        from afsmc.verify.kernels import hashing

        hashing.KeySet().add(np.arange(3, dtype=np.int64))
        hashing.Regions(np.arange(3, dtype=np.int64), 63).find(np.arange(3, dtype=np.int64))
        hashing.encode(np.array([0.5]), np.zeros(1, np.uint32), np.array([0.5]))
    before = os.times()
    found = explore_graph.explore(c)
    after = os.times()
    h = hashlib.sha256()
    _digest(found.arrays, h)
    return {"cpu": (after.user - before.user) + (after.system - before.system),
            "sys": after.system - before.system,
            "peak_gb": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1e6,
            "states": found.states, "choices": found.choices,
            "transitions": found.transitions, "digest": h.hexdigest()[:16]}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--instance", default="scenario2", choices=sorted(INSTANCES))
    ap.add_argument("--repeat", type=int, default=2)
    ap.add_argument("--child", help=argparse.SUPPRESS)
    args = ap.parse_args()
    if args.child:
        print(json.dumps(child(args.instance)))
        return
    print("| run | kernels | exploration CPU s (of it system) | process wall s | peak GB | "
          "states | transitions | digest |")
    print("|---|---|---|---|---|---|---|---|")
    for i in range(args.repeat):
        for mode in ("numpy", "numba"):
            env = {**os.environ, "AFSMC_KERNELS": mode, "PYTHONPATH": ROOT}
            started = time.monotonic()
            out = subprocess.run([sys.executable, __file__, "--instance", args.instance,
                                  "--child", mode], env=env, check=True, capture_output=True,
                                 text=True).stdout
            r = json.loads(out.strip().splitlines()[-1])
            print(f"| {i + 1} | {mode} | {r['cpu']:.1f} ({r['sys']:.1f}) | "
                  f"{time.monotonic() - started:.0f} | "
                  f"{r['peak_gb']:.2f} | {r['states']:,} | {r['transitions']:,} | "
                  f"`{r['digest']}` |", flush=True)


if __name__ == "__main__":
    main()
