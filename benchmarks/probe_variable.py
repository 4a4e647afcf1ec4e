"""How much could an exact reduction gain by merging the values of one variable?

    .venv/bin/python benchmarks/probe_variable.py [--var b] [--const NAME=VALUE ...]

Compiles examples/uav.afsm (with the given constants) to PRISM, builds the sparse model
with Storm, checks every property of the file in every state, and counts the classes of
states that agree in every variable but the probed one(s) and in all property values.
States merged by an exact reduction have equal values for every property, so the count is
a lower bound on the states any merge of that variable's values can leave. docs/benchmarks.md
records the battery (`b`) probe. Loops over every state in Python: minutes for a few
million states.
"""

from __future__ import annotations

import argparse
import collections
import json
import os
import sys
import tempfile

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, ROOT)

import numpy as np  # noqa: E402
import stormpy  # noqa: E402

from afsmc.backends import prism  # noqa: E402
from afsmc.compiler import load, lowered  # noqa: E402

UAV = os.path.join(ROOT, "examples", "uav.afsm")


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--var", action="append", help="variable(s) to drop (default: b)")
    ap.add_argument("--const", action="append", default=[], metavar="NAME=VALUE")
    args = ap.parse_args()
    drop = set(args.var or ["b"])
    consts = dict(c.split("=", 1) for c in args.const)
    out = prism.emit(lowered(load(UAV, consts).model))
    with tempfile.TemporaryDirectory() as tmp:
        model_file = os.path.join(tmp, "m.prism")
        with open(model_file, "w", encoding="utf-8") as f:
            f.write(out.model)
        prog = stormpy.parse_prism_program(model_file).substitute_constants()
    props = stormpy.parse_properties(out.properties, prog)
    opts = stormpy.BuilderOptions([p.get_raw_formula() for p in props])
    opts.set_build_state_valuations()
    model = stormpy.build_model(prog, options=opts)
    print(f"{model.nr_states} states, {model.nr_transitions} transitions", flush=True)
    values = np.round(np.stack([np.array(stormpy.model_checking(model, p).get_value_vector())
                                for p in props], axis=1), 11)
    classes: dict[tuple[object, ...], set[tuple[float, ...]]] = collections.defaultdict(set)
    valuations = model.state_valuations  # a copy per access: fetch it once
    for s in range(model.nr_states):
        state = json.loads(str(valuations.to_json(s)))
        rest = tuple(v for k, v in sorted(state.items()) if k not in drop)
        classes[rest].add(tuple(values[s].tolist()))
    n = sum(len(c) for c in classes.values())
    print(f"dropping {', '.join(sorted(drop))}: {n} classes, "
          f"at most {model.nr_states / n:.2f}x fewer states")
    return 0


if __name__ == "__main__":
    sys.exit(main())
