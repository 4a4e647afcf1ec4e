"""The long fuzz run (issue 36): N inputs (100,000 by default) through `afsmc check`,
`fmt --diff` and `compile` (PRISM, JANI, DOT), in process, with a CPU limit per command,
counting internal errors (exit 3), tracebacks and time-outs.

    nice .venv/bin/python benchmarks/fuzz.py [--inputs N] [--seed S] [--cpu-limit SEC]
                                             [--summary FILE] [--keep DIR]

The inputs come from tests/fuzz/generate.py, as in the CI test (tests/fuzz/test_fuzz.py),
but fresh ones (a seeded Random, not hypothesis's derandomized draws): walks of the
grammar, generated machines, mutations and splices of the seed files (the examples, the
golden cases and tests/fuzz/corpus/), and seeds with a declaration drawn from the grammar.
`compile` runs on every file that checks and on a tenth of the others (a file that fails
its check fails `compile` the same way); `fmt` on every file without a syntax error and
on a tenth of the others (its parse is `check`'s). E190 from `fmt` (its safety net) counts
as a failure too.
Inputs in the classes fixed elsewhere (huge literals, superlinear sizes and depths:
tests/fuzz/generate.excluded) are counted and not run.

Every failing input is written to --keep (default benchmarks/fuzz-failures/) for the
corpus. The summary (JSON, and a markdown table on standard output) is rewritten every
1,000 inputs, so an interrupted run still leaves its figures.
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import random
import sys
import time
from collections import Counter
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from tests.fuzz import generate, harness  # noqa: E402

MIX = {"grammar": 0.2, "machine": 0.25, "mutation": 0.3, "splice": 0.1, "declaration": 0.15}


def draw(kind: str, rng: random.Random, seeds: list[bytes]) -> bytes:
    if kind == "grammar":
        return generate.from_grammar(rng).encode()
    if kind == "machine":
        return generate.spec(rng).encode()
    if kind == "declaration":
        return generate.with_declaration(rng, rng.choice(seeds))
    if kind == "mutation":
        return generate.mutate(rng, rng.choice(seeds))
    return generate.mutate(rng, generate.splice(rng, rng.choice(seeds), rng.choice(seeds)))


def merge(runs: list[dict[str, Any]]) -> dict[str, Any]:
    """The summaries of several runs as one: counts added, the slowest input kept, and
    each run's seed, size and times listed under "runs"."""
    out: dict[str, Any] = {"runs": [{k: r[k] for k in ("seed", "inputs", "cpu_s", "wall_s",
                                                         "inputs_per_s", "commit") if k in r}
                                    for r in runs]}
    for r in runs:
        for k, v in r.items():
            if k in ("seed", "wall_s", "inputs_per_s", "slowest_input", "commit"):
                continue
            if isinstance(v, dict):
                into = out.setdefault(k, {})
                for kk, vv in v.items():
                    into[kk] = into.get(kk, 0) + vv if isinstance(vv, int) else vv
            elif isinstance(v, (int, float)) and not isinstance(v, bool) \
                    and k != "slowest_input_cpu_s" and k != "cpu_limit_s":
                out[k] = round(out.get(k, 0) + v, 1)
            elif k == "slowest_input_cpu_s":
                if v >= out.get(k, 0):
                    out[k], out["slowest_input"] = v, f"seed {r['seed']}, {r['slowest_input']}"
            else:
                out[k] = v
    for k in ("by_generator", "exit_codes"):
        out[k] = dict(sorted(out.get(k, {}).items()))
    return out


def main() -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--inputs", type=int, default=100_000)
    p.add_argument("--seed", type=int, default=36)
    p.add_argument("--cpu-limit", type=float, default=harness.CPU_LIMIT,
                   help="seconds of CPU per command and input (default: %(default)s)")
    p.add_argument("--summary", default=str(ROOT / "benchmarks" / "fuzz-summary.json"),
                   help="the JSON summary (default: %(default)s, the recorded run)")
    p.add_argument("--keep", default=str(ROOT / "benchmarks" / "fuzz-failures"))
    p.add_argument("--merge", nargs="+", metavar="JSON",
                   help="only combine the summaries of runs with different seeds (run side "
                        "by side) into --summary")
    args = p.parse_args()
    if args.merge:
        runs = [json.loads(Path(f).read_text(encoding="utf-8")) for f in args.merge]
        Path(args.summary).write_text(json.dumps(merge(runs), indent=2) + "\n", encoding="utf-8")
        return 0

    rng = random.Random(args.seed)
    seeds = generate.seeds()
    kinds, weights = list(MIX), list(MIX.values())
    counts: Counter[str] = Counter()
    failures: Counter[str] = Counter()
    by_kind: Counter[str] = Counter()
    codes: Counter[str] = Counter()
    examples: dict[str, str] = {}
    slowest = (0.0, "")
    cpu = 0.0
    started = time.monotonic()

    def summary(done: int) -> dict[str, object]:
        wall = time.monotonic() - started
        return {
            "inputs": done, "seed": args.seed, "cpu_limit_s": args.cpu_limit,
            "excluded": counts["excluded"], "run": done - counts["excluded"],
            "exit3": failures["exit 3"], "tracebacks": failures["traceback"],
            "timeouts": failures["timeout"], "formatter_e190": failures["formatter"],
            "by_generator": dict(sorted(by_kind.items())),
            "exit_codes": dict(sorted(codes.items())),
            "syntax_errors": counts["syntax"], "checked_ok": codes["check 0"],
            "compiled_ok": codes["prism 0"], "commands": counts["commands"],
            "cpu_s": round(cpu, 1), "wall_s": round(wall, 1),
            "inputs_per_s": round(done / wall, 1) if wall else None,
            "slowest_input_cpu_s": round(slowest[0], 3), "slowest_input": slowest[1],
            "failures": examples, "python": platform.python_version(),
        }

    def write(done: int) -> dict[str, object]:
        s = summary(done)
        tmp = args.summary + ".tmp"
        with open(tmp, "w", encoding="utf-8") as f:
            json.dump(s, f, indent=2)
            f.write("\n")
        os.replace(tmp, args.summary)
        return s

    def one(i: int, wd: str) -> None:
        nonlocal cpu, slowest
        kind = rng.choices(kinds, weights)[0]
        data = draw(kind, rng, seeds)
        by_kind[kind] += 1
        if generate.excluded(data):
            counts["excluded"] += 1
            return
        verdict = harness.judge(data, wd, rng, cpu_limit=args.cpu_limit, compile_share=0.1,
                                fmt_share=0.1)
        cpu += verdict.cpu
        counts["commands"] += len(verdict.codes)
        counts["syntax"] += verdict.syntax_error
        codes.update(f"{c} {v}" for c, v in verdict.codes.items())
        if verdict.cpu > slowest[0]:
            slowest = (verdict.cpu, f"input {i} ({kind})")
        for f in verdict.failures:
            failures[f.kind] += 1
            os.makedirs(args.keep, exist_ok=True)
            name = f"{f.kind.replace(' ', '')}-{i}.afsm"
            Path(args.keep, name).write_bytes(data)
            last = f.detail.strip().splitlines()[-1:] or [""]
            examples[name] = f"{' '.join(f.argv[:1] + f.argv[2:])}: {last[0][:300]}"

    done, interrupted = 0, False
    with harness.workdir() as wd:
        try:
            for i in range(1, args.inputs + 1):
                one(i, wd)
                done = i
                if i % 1000 == 0:
                    s = write(i)
                    print(f"{i} inputs, {s['exit3']} exit-3, {s['tracebacks']} tracebacks, "
                          f"{s['timeouts']} time-outs, {s['inputs_per_s']}/s",
                          file=sys.stderr, flush=True)
        except KeyboardInterrupt:  # Ctrl-C: the summary of the inputs run so far
            print(f"interrupted after {done} inputs", file=sys.stderr)
            interrupted = True
    s = write(done)
    print(f"| inputs | run | excluded | exit 3 | tracebacks | time-outs | commands | "
          f"syntax errors | checked | compiled | CPU s | wall s |\n"
          f"|---|---|---|---|---|---|---|---|---|---|---|---|\n"
          f"| {s['inputs']} | {s['run']} | {s['excluded']} | {s['exit3']} | {s['tracebacks']} "
          f"| {s['timeouts']} | {s['commands']} | {s['syntax_errors']} | {s['checked_ok']} | "
          f"{s['compiled_ok']} | {s['cpu_s']} | {s['wall_s']} |")
    if s["exit3"] or s["tracebacks"] or s["timeouts"] or s["formatter_e190"]:
        return 1
    return 130 if interrupted else 0


if __name__ == "__main__":
    sys.exit(main())
