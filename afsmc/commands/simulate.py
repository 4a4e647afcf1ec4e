"""`afsmc simulate FILE --runs N`: Monte Carlo simulation of the machine itself (the
lowered guarded commands, vectorised with numpy), estimating every declared property
with a confidence interval. See docs/monte-carlo.md."""

from __future__ import annotations

import argparse
import dataclasses
import json
import math
import os
import sys
from typing import Any

from afsmc.api.simulate import Estimates, Simulation, estimates, prepare
from afsmc.api.simulate import run as run_simulation
from afsmc.commands.common import (
    JOBS_HELP,
    MAX_JOB_TASKS,
    add_consts,
    add_file,
    add_seed,
    answer_json,
    dask_address,
    fail,
    integer,
    overrides,
    refuse_jobs,
    report,
    usage_error,
)
from afsmc.commands.render.simulate_strategy import followed_text
from afsmc.commands.sim_check import level
from afsmc.diagnostics import CompileError, codes
from afsmc.files import check_writable, read_source, write_atomic
from afsmc.interrupt import Stopped
from afsmc.sim import logs
from afsmc.sim.run import (
    BATCH,
    LOWERING,
    MAX_BATCH_SIZE,
    MAX_BATCHES,
    STRATEGIES,
    Outcome,
    batch_count,
)
from afsmc.text import literal, num

MAX_RUNS = MAX_BATCHES * MAX_BATCH_SIZE
MAX_STEPS = 10**9  # steps of one run: past it, a run that has not ended is undecided
MAX_TRACES = 100_000  # sample runs kept (a robot log for `conform`), each of up to --max-steps states


def add_arguments(p: argparse.ArgumentParser) -> None:
    add_file(p)
    add_consts(p)
    p.add_argument("--runs", type=integer(1, MAX_RUNS), default=100_000, metavar="N",
                   help=f"number of runs, 1 to {MAX_RUNS:,} (default 100000); more than "
                        f"{MAX_BATCHES:,} batches of --batch-size runs are refused")
    add_seed(p)
    p.add_argument("--resolve", type=_strategy, default="uniform",
                   metavar="{" + ",".join(STRATEGIES) + "}",
                   help="interval constants: uniform floor/ceil choice (default), or always "
                        "the floor (floor, lo) or the ceiling (ceil, hi): one fixed strategy; "
                        "`afsmc verify` gives the MDP's min and max")
    p.add_argument("--at", choices=("draw", "mid", "min", "max"), default="draw",
                   help="interval probabilities (const prob P = [lo, hi]): each run draws "
                        "its own p, uniform in [lo, hi], when it starts (draw, the default); "
                        "or every run at the midpoint (mid), the lower end (min) or the upper "
                        "end (max)")
    p.add_argument("--confidence", type=level, default=0.999, metavar="C",
                   help="confidence level of the intervals, in (0, 1) (default 0.999)")
    p.add_argument("--max-steps", type=integer(1, MAX_STEPS), default=100_000, metavar="K",
                   help=f"stop a run after K steps, 1 to {MAX_STEPS:,}; undecided runs widen "
                        "the interval (default 100000)")
    p.add_argument("--jobs", "-j", type=integer(1, MAX_JOB_TASKS), default=1, metavar="J",
                   help=f"worker processes (default 1; {JOBS_HELP}); the estimate does not "
                        "depend on it")
    p.add_argument("--dask", metavar="ADDRESS", type=dask_address,
                   help="spread the batches over the Dask cluster at ADDRESS")
    p.add_argument("--batch-size", type=integer(1, MAX_BATCH_SIZE), default=BATCH, metavar="B",
                   help=f"runs per batch, each with its own seed, 1 to {MAX_BATCH_SIZE:,} "
                        f"(default {BATCH})")
    p.add_argument("--traces", type=integer(0, MAX_TRACES), default=0, metavar="K",
                   help="print K sample runs in mission terms (modes, actions, variables), "
                        f"0 to {MAX_TRACES:,}")
    p.add_argument("--traces-out", metavar="PATH",
                   help="save the traces to PATH: as the robot's log (docs/robot.md) for a "
                        "name ending in .jsonl (one step a line) or .csv, else as JSON (a "
                        "list of runs of states)")
    p.add_argument("--json", action="store_true", help="print the estimates as JSON")
    p.add_argument("--strategy", metavar="min:NAME|max:NAME",
                   help="resolve the interval constants as Storm's min or max strategy of "
                        "property NAME does, state by state (extracted by Storm first; "
                        "instead of --resolve)")


def run(args: argparse.Namespace) -> int:
    refuse_jobs(args.jobs, args.dask)
    count = batch_count(args.runs, args.batch_size)
    if count > MAX_BATCHES:
        print(f"afsmc simulate: error: --runs {args.runs:,} in batches of {args.batch_size:,} "
              f"is {count:,} batches, more than {MAX_BATCHES:,} (each has a seed, made "
              f"before the runs); raise --batch-size (at most {MAX_BATCH_SIZE:,}) or lower "
              "--runs", file=sys.stderr)
        return 2
    if args.traces_out in ("", "-"):
        print(f"afsmc simulate: error: --traces-out {args.traces_out!r}: give a file name "
              "(--traces K prints the sample runs)", file=sys.stderr)
        return 2
    if args.traces_out and not args.traces:
        print("afsmc simulate: error: --traces-out needs --traces K with K >= 1 (the number "
              "of runs to save)", file=sys.stderr)
        return 2
    if args.traces > args.runs:
        print(f"afsmc simulate: error: --traces {args.traces} asks for more sample runs than "
              f"--runs {args.runs} makes", file=sys.stderr)
        return 2
    if args.dask and args.jobs != 1:
        print("afsmc simulate: error: --jobs sets local worker processes; with --dask the "
              "cluster's workers run the batches: give one of them", file=sys.stderr)
        return 2
    try:
        if args.traces_out:  # said before the runs, not after them
            check_writable(args.traces_out, protect=(args.file,))
        text = read_source(args.file)
        if args.strategy and args.resolve != "uniform":
            usage_error("--strategy resolves the interval constants itself: give it or "
                        "--resolve, not both")

        def say(text: str) -> None:  # Storm extracting the strategy
            if not args.json:
                print(f"simulate: {text}", file=sys.stderr)

        sim = prepare(args.file, text, overrides(args), resolve=args.resolve,
                      max_steps=args.max_steps, at=args.at, strategy=args.strategy,
                      traces=args.traces, progress=say)
        last = [-1]

        def progress(done: int, total: int) -> None:
            pct = 100 * done // total
            if total >= 4 * args.batch_size and pct // 10 != last[0]:
                last[0] = pct // 10
                print(f"simulate: {done}/{total} runs ({pct}%)", file=sys.stderr)

        if not args.json:
            report(sim.warnings)
        try:
            est = run_simulation(sim, args.runs, seed=args.seed, confidence=args.confidence,
                                 jobs=args.jobs, dask=args.dask, traces=args.traces,
                                 batch_size=args.batch_size, progress=progress)
        except Stopped as exc:
            # The runs that finished are not lost to a Ctrl-C: the CLI prints the note and,
            # for --json, the estimates as data.
            part = exc.partial
            if not isinstance(part, Outcome):
                raise
            kept = estimates(dataclasses.replace(sim, policy=None), part, seed=args.seed,
                             confidence=args.confidence, traced=args.traces > 0)
            raise Stopped(notes=[_so_far(part, args)],
                          partial=_Partial(kept.to_json())) from exc
        if args.traces_out:
            write_atomic(args.traces_out, _traces_file(args.traces_out, est.traces),
                         protect=(args.file,))
    except CompileError as exc:
        return fail(exc, args.json, wrapped=True)
    _finish(sim, est, args)
    return 0


def _traces_file(path: str, traces: list[list[dict[str, Any]]]) -> str:
    """The sample runs as `--traces-out PATH` writes them: the robot's log format, which
    `afsmc conform` reads, for PATH.jsonl and PATH.csv; else a JSON list of runs."""
    ext = os.path.splitext(path)[1].lower()
    if ext == ".jsonl":
        return logs.jsonl(traces)
    if ext == ".csv":
        return logs.csv_text(traces)
    return json.dumps(traces, indent=1) + "\n"


def _finish(sim: Simulation, est: Estimates, args: argparse.Namespace) -> None:
    """Print the estimates (and the strategy the runs followed, if any)."""
    if args.json:
        print(answer_json("simulate", est.to_json()))
    else:
        _print(est.raw, args, sim.model.is_nondeterministic,
               endless=any(d.code == codes.W602 for d in est.warnings),
               prob_intervals=bool(sim.model.prob_intervals), scheduler=est.scheduler)
        followed_text(est.policy)


class _Partial:
    """What an interrupted run had, for the CLI's --json object."""

    def __init__(self, obj: dict[str, Any]) -> None:
        self.obj = obj

    def to_json(self) -> dict[str, Any]:
        return self.obj


def _so_far(part: Outcome, args: argparse.Namespace) -> str:
    lines = [f"the {part.runs:,} of {args.runs:,} runs that finished estimate "
             f"({args.confidence:g} confidence, seed {args.seed}):"]
    for e in part.estimates:
        value = "n/a" if math.isnan(e.estimate) else num(e.estimate)
        undecided = f", {e.undecided} undecided" if e.undecided else ""
        lines.append(f"  {e.name} = {value} [{num(e.low)}, {num(e.high)}]{undecided}")
    return "\n".join(lines)


def _strategy(text: str) -> str:
    if text in ("min", "max"):
        raise argparse.ArgumentTypeError(
            f"{text!r}: a simulation follows one fixed strategy and cannot find the MDP's "
            f"P{text} over the interval choices; `afsmc verify` gives it. For every interval "
            "at its floor or its ceiling, use lo or hi")
    if text not in STRATEGIES:
        raise argparse.ArgumentTypeError(
            f"invalid choice: {text!r} (choose from {', '.join(STRATEGIES)})")
    return text


def _print(out: Outcome, args: argparse.Namespace, intervals: bool, endless: bool,
           prob_intervals: bool = False, scheduler: str | None = None) -> None:
    if args.traces:
        print(_traces_text(out.traces))
    name = args.file  # as given, as verify names it
    # --resolve means nothing to a model without interval constants: do not suggest it did
    how = {"lo": "at their floor", "hi": "at their ceiling"}.get(LOWERING[args.resolve],
                                                                  args.resolve)
    resolved = f"interval constants {how}" if intervals else "no interval constants"
    if args.strategy:
        resolved = f"interval constants by the {args.strategy} strategy"
    if prob_intervals:
        resolved += ", " + {"draw": "interval probabilities drawn once per run (uniform)",
                            "mid": "interval probabilities at their midpoints",
                            "min": "interval probabilities at their lower ends",
                            "max": "interval probabilities at their upper ends"}[args.at]
    print(f"{name}: {out.runs} runs, {resolved}, seed {args.seed}, "
          f"{args.confidence:g} confidence")
    if scheduler:  # a composed mission's agents interleave: the rule that picks who moves
        print(f"who moves next: {scheduler}")
    width = max([len(e.name) for e in out.estimates] + [8])
    values = ["n/a" if math.isnan(e.estimate) else num(e.estimate) for e in out.estimates]
    vwidth = max([len(v) for v in values] + [1])  # the intervals start in one column
    for e, value in zip(out.estimates, values, strict=True):
        why = [f"{e.undecided} undecided at --max-steps"] if e.undecided else []
        if e.undecided and endless:
            # a run in a mode it cannot end from may never be decided (more steps may still
            # help the others, and a target inside the loop)
            why.append("some modes cannot reach an end (W602): a run there may stay "
                       "undecided whatever --max-steps; `afsmc verify` gives the exact value")
        if e.no_spread:
            raise_ = [o for o, short in (("--runs", out.runs < 2),
                                         ("--max-steps", e.undecided > 0)) if short]
            why.append(f"no interval from fewer than 2 finished runs: raise "
                       f"{' and '.join(raise_)}")
        if e.reason:  # no run differed: the interval from the reward's range (sim/rare.py)
            why.append(e.reason)
        note = f"  ({'; '.join(why)})" if why else ""
        print(f"  {e.name.ljust(width)}  {value.ljust(vwidth)}  [{num(e.low)}, {num(e.high)}]"
              f"{note}")
    if not out.estimates:
        print("  (no properties declared)")
    rate = out.runs / out.seconds * 60 if out.seconds > 0 else 0.0
    print(f"simulate: {out.steps} steps in {out.seconds:.2f} s ({rate:,.0f} runs/min)",
          file=sys.stderr)


def _traces_text(traces: list[list[dict[str, Any]]]) -> str:
    lines = []
    for i, tr in enumerate(traces, 1):
        lines.append(f"trace {i} ({len(tr) - 1} steps):")
        prev: dict[str, Any] = {}
        for st in tr:
            changed = {k: v for k, v in st["vars"].items() if prev.get(k) != v} if prev \
                else st["vars"]
            vals = " ".join(f"{k}={literal(v)}" for k, v in changed.items())
            act = st.get("action")
            how = f"--{act}" + (f" [hazard {st['hazard']}]" if "hazard" in st else "") + "--> " \
                if act else ""
            lines.append(f"  {st['step']:>4}  {how}{st['mode']}  {vals}".rstrip())
            prev = st["vars"]
    return "\n".join(lines)
