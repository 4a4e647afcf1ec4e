"""`afsmc sim-check FILE`: re-run the simulation behind every `from sim ...` constant and
report whether the value in the file still agrees with it; `--update` rewrites the
drifted ones in place (see docs/monte-carlo.md for the rules)."""

from __future__ import annotations

import argparse
import math
import os
import sys

from afsmc.api.sim_check import sim_check_file
from afsmc.commands.common import (
    add_consts,
    add_seed,
    fail,
    integer,
    overrides,
    print_json,
    report,
)
from afsmc.diagnostics import CompileError
from afsmc.files import check_writable
from afsmc.sim.evidence import Evidence
from afsmc.simlib import registry, sandbox

MAX_RUNS = 10**9  # runs per simulator; the free memory usually bounds them sooner
MAX_TIMEOUT = 86_400.0  # seconds per simulator: a day


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("file", metavar="FILE", nargs="?", help="the .afsm file")
    add_consts(p)
    p.add_argument("--runs", type=integer(2, MAX_RUNS), default=10_000, metavar="N",
                   help=f"simulation runs per simulator, 2 to {MAX_RUNS:,}, and no more than "
                        f"the samples of which ({sandbox.BYTES_PER_RUN} bytes a run) fit in "
                        f"{sandbox.MEMORY_SHARE:.0%} of the free memory (default 10000)")
    add_seed(p)
    p.add_argument("--timeout", type=_seconds, default=sandbox.DEFAULT_TIMEOUT,
                   metavar="SECONDS",
                   help="stop a simulator that runs longer than this, per constant, at most "
                        f"{MAX_TIMEOUT:g}; each runs in its own process (default "
                        f"{sandbox.DEFAULT_TIMEOUT:g})")
    add_judging(p, "runs'")
    p.add_argument("--data-root", metavar="DIR",
                   help="the folder `from data` files must lie under (default: the spec's "
                        "folder); paths stay relative to the spec's folder")
    p.add_argument("--json", action="store_true", help="print the evidence as JSON")
    p.add_argument("--list", action="store_true",
                   help="list the registered simulator outputs and exit")


def add_judging(p: argparse.ArgumentParser, whose: str) -> None:
    """--confidence and --update, of the commands that judge constants by samples (`whose`
    samples: "runs'", "logs'")."""
    p.add_argument("--confidence", type=level, metavar="C",
                   help="confidence of the statistical tests of the constants that state none "
                        "(`with confidence = C` in the file wins; default 0.999); an interval "
                        f"probability must cover the {whose} Clopper-Pearson interval at it")
    p.add_argument("--update", action="store_true",
                   help="rewrite drifted constants in FILE in place, with a provenance comment")


def run(args: argparse.Namespace) -> int:
    if args.list:
        return _list(args)
    if args.file is None:
        print("afsmc sim-check: error: FILE is required (or --list)", file=sys.stderr)
        return 2
    if args.data_root is not None and not os.path.isdir(args.data_root):
        print(f"afsmc sim-check: error: --data-root {args.data_root} is not a folder",
              file=sys.stderr)
        return 2
    budget = sandbox.memory_budget()
    fit = sandbox.runs_that_fit(budget)
    if fit is not None and budget is not None and args.runs > fit:
        print(f"afsmc sim-check: error: --runs {args.runs:,} is more than the {fit:,} runs "
              f"whose samples fit in the memory sim-check may use ({budget / 2**30:.1f} GB, "
              f"{sandbox.MEMORY_SHARE:.0%} of the memory free now, at "
              f"{sandbox.BYTES_PER_RUN} bytes per run): lower --runs, or free memory to "
              "raise the limit", file=sys.stderr)
        return 2
    def say(line: str) -> None:
        print(line, file=sys.stderr)

    try:
        if args.update:  # a file it cannot rewrite is said before the runs, not after them
            check_writable(args.file)
        res = sim_check_file(args.file, overrides(args), runs=args.runs, seed=args.seed,
                             timeout=args.timeout, update=args.update, budget=budget,
                             confidence=args.confidence, progress=say,
                             data_root=args.data_root)
    except CompileError as exc:
        return fail(exc, args.json, wrapped=True)
    if args.json:
        print_json(res.to_json())
    else:
        table(res.evidence)
    if not res.evidence:
        print(f"{args.file}: no constant is backed by a simulation ('from sim ...')",
              file=sys.stderr)
    if res.updated:
        print(f"sim-check: updated {len(res.updated)} constant(s) in {args.file}: "
              + ", ".join(f"{e.name} = {e.suggestion}" for e in res.updated), file=sys.stderr)
    if res.diagnostics and not args.json:
        report(res.diagnostics)
    return 0 if res.ok else 1


def level(text: str) -> float:
    try:
        value = float(text)
    except ValueError:
        value = math.nan
    if not 0.0 < value < 1.0:
        raise argparse.ArgumentTypeError(f"expected a confidence in (0, 1), got {text!r}")
    return value


def _seconds(text: str) -> float:
    try:
        value = float(text)
    except ValueError:
        value = math.nan
    if not (math.isfinite(value) and 0 < value <= MAX_TIMEOUT):
        raise argparse.ArgumentTypeError(f"expected a number of seconds in (0, {MAX_TIMEOUT:g}], "
                                         f"got {text!r}")
    return value


def _list(args: argparse.Namespace) -> int:
    """--list: the registered simulator outputs."""
    if args.file is not None:
        print(f"afsmc sim-check: error: --list lists every simulator output; it takes no "
              f"FILE (got {args.file})", file=sys.stderr)
        return 2
    if args.json:
        print_json({"outputs": [{"ref": ref, "kind": registry.kind(ref)}
                                for ref in registry.available()]})
        return 0
    for ref in registry.available():
        print(f"{ref}  ({registry.kind(ref)})")
    return 0


def table(results: list[Evidence], origin: str = "simulation", runs: str = "runs") -> None:
    """The judged constants, a row each, and a line of totals (`origin`: the column of
    their source; `runs`: what a sample is called)."""
    if not results:
        return
    head = ("constant", origin, "declared", "mean", "CI of mean", "F(lo), F(hi)",
            "hull", "verdict")
    rows = [head]
    for e in results:
        cdf = f"{e.cdf_lo:.4f}, {e.cdf_hi:.4f}" if e.cdf_lo is not None and e.cdf_hi is not None \
            else "-"
        hull = f"[{e.hull[0]}, {e.hull[1]}]" if e.hull else "-"
        rows.append((e.name, e.ref, e.declared, f"{e.mean:.4g}",
                     f"[{e.mean_low:.4g}, {e.mean_high:.4g}]", cdf, hull,
                     {"inconclusive": f"too few {runs}", "drifted": "DRIFTED"}.get(e.verdict,
                                                                               e.verdict)))
    widths = [max(len(r[i]) for r in rows) for i in range(len(head))]
    for r in rows:
        print("  ".join(cell.ljust(w) for cell, w in zip(r, widths, strict=True)).rstrip())
    conf = {e.confidence for e in results}
    few = sum(e.inconclusive for e in results)
    sims = [e for e in results if e.seed is not None]
    data = len(results) - len(sims)
    where = ([f"{sims[0].runs} runs, seed {sims[0].seed}"] if sims else []) + (
        [f"{data} from {'data files' if origin == 'simulation' else origin}"] if data else [])
    print(f"\n{len(results)} constant(s), {sum(not e.consistent for e in results)} drifted"
          + (f", {few} with too few {runs} to judge" if few else "") + "; "
          + ", ".join(where) + ", confidence "
          + ", ".join(f"{c:g}" for c in sorted(conf))
          + ("; probabilities: Clopper-Pearson intervals"
             if any(e.method for e in results) else ""))
