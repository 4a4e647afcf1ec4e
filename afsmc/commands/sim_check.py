"""`afsmc sim-check FILE`: re-run the simulation behind every `from sim ...` constant and
report whether the value in the file still agrees with it; `--update` rewrites the
drifted ones in place (see docs/monte-carlo.md for the rules)."""

from __future__ import annotations

import argparse
import dataclasses
import datetime
import math
import os
import sys
import time

import numpy as np

from afsmc.check.sim_sources import data_kind
from afsmc.commands.common import add_consts, add_seed, fail, overrides, print_json, report
from afsmc.compiler import Checked, load
from afsmc.diagnostics import CompileError, Diagnostic, Severity, codes
from afsmc.files import write_atomic
from afsmc.model import ir
from afsmc.sim.evidence import Evidence, judge, rewrite
from afsmc.simlib import datafile, registry, sandbox


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("file", metavar="FILE", nargs="?", help="the .afsm file")
    add_consts(p)
    p.add_argument("--runs", type=int, default=10_000, metavar="N",
                   help="simulation runs per simulator (default 10000)")
    add_seed(p)
    p.add_argument("--timeout", type=_seconds, default=sandbox.DEFAULT_TIMEOUT,
                   metavar="SECONDS",
                   help="stop a simulator that runs longer than this, per constant; each runs "
                        f"in its own process (default {sandbox.DEFAULT_TIMEOUT:g})")
    p.add_argument("--confidence", type=_level, metavar="C",
                   help="confidence of the statistical tests of the constants that state none "
                        "(`with confidence = C` in the file wins; default 0.999); an interval "
                        "probability must cover the runs' Clopper-Pearson interval at it")
    p.add_argument("--update", action="store_true",
                   help="rewrite drifted constants in FILE in place, with a provenance comment")
    p.add_argument("--json", action="store_true", help="print the evidence as JSON")
    p.add_argument("--list", action="store_true",
                   help="list the registered simulator outputs and exit")


def run(args: argparse.Namespace) -> int:
    if args.list:
        return _list(args)
    if args.file is None:
        print("afsmc sim-check: error: FILE is required (or --list)", file=sys.stderr)
        return 2
    if args.runs < 2:
        print("afsmc sim-check: error: --runs must be at least 2", file=sys.stderr)
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
    try:
        with open(args.file, encoding="utf-8", newline="") as f:
            text = f.read()  # newline="": --update must keep every other byte
    except (OSError, UnicodeDecodeError):
        text = None
    checked = _load(args, text)
    if isinstance(checked, int):
        return checked
    sourced = [c for c in checked.model.constants if c.source is not None]
    results = _judge_all(args, sourced, budget)
    if isinstance(results, int):
        return results
    by_name = {c.name: c for c in sourced}
    drifted = [e for e in results if not e.consistent]
    # No value its own rule accepts (an int whose accepted range holds no integer):
    # --update would write a value the next sim-check rejects again.
    unfit = [Diagnostic(
        codes.E508, Severity.ERROR,
        f"constant '{e.name}' has drifted from {_origin(e)} (mean {e.mean:.4g}), and "
        f"no {by_name[e.name].type.value} fits the rule: it accepts {e.accept}",
        by_name[e.name].span, hint="widen its `tolerance`, or declare the constant double")
        for e in drifted if not e.fits]
    drifted = [e for e in drifted if e.fits]
    updated = False
    if args.update and drifted:
        assert text is not None
        failed = _update(args, text, drifted, by_name)
        if failed is not None:
            return failed
        updated = True
    # Nothing to reject at this many runs: said, rather than called consistent.
    few = [Diagnostic(
        codes.W503, Severity.WARNING, f"constant '{e.name}': {e.runs} runs of '{e.ref}' are too "
        f"few to judge it (the rule accepts {e.accept})", by_name[e.name].span,
        hint="raise --runs: the quantiles of the rule need more samples to be bounded")
        for e in results if e.inconclusive]
    diags = unfit + ([] if updated else [Diagnostic(
        codes.E502, Severity.ERROR,
        f"constant '{e.name}' = {e.declared} has drifted from {_origin(e)} "
        f"(mean {e.mean:.4g}; the rule accepts {e.accept})", by_name[e.name].span,
        hint=f"the simulation suggests {e.suggestion}; `afsmc sim-check --update` rewrites it")
        for e in drifted])
    if args.json:
        print_json({"file": args.file, "runs": args.runs, "seed": args.seed,
                    "updated": [e.name for e in drifted] if updated else [],
                    "constants": [e.to_json() for e in results],
                    "diagnostics": [d.to_json() for d in diags + few]})
    else:
        _table(results)
    if not sourced:
        print(f"{args.file}: no constant is backed by a simulation ('from sim ...')",
              file=sys.stderr)
    if updated:
        print(f"sim-check: updated {len(drifted)} constant(s) in {args.file}: "
              + ", ".join(f"{e.name} = {e.suggestion}" for e in drifted), file=sys.stderr)
    if (diags or few) and not args.json:
        report(diags + few)
    return 1 if diags else 0


def _origin(e: Evidence) -> str:
    """Where a constant's evidence comes from, for a message."""
    return f"simulation '{e.ref}'" if e.seed is not None else e.ref


def _level(text: str) -> float:
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
    if not (math.isfinite(value) and value > 0):
        raise argparse.ArgumentTypeError(f"expected a positive number of seconds, got {text!r}")
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


def _load(args: argparse.Namespace, text: str | None) -> Checked | int:
    """The checked model, or the exit code of its errors. When the only errors are params
    without a value (E206), the model without its checks, if no simulated constant reads
    those params."""
    try:
        return load(args.file, overrides(args), text=text)
    except CompileError as exc:
        errors = [d for d in exc.diagnostics if d.is_error]
        if not errors or any(d.code != codes.E206 for d in errors):
            return fail(exc, args.json, wrapped=True)
        # Only params without a value: the simulated constants may not need them.
        try:
            checked = load(args.file, overrides(args), text=text, run_checks=False,
                           open_params=True)
        except CompileError:
            return fail(exc, args.json, wrapped=True)
    missing, reads = checked.open_params, checked.open_reads
    needed = sorted({p for c in checked.model.constants if c.source is not None
                     for p in reads.get(c.name, ())})
    if needed:
        return fail(CompileError([missing[p] for p in needed]), args.json, wrapped=True)
    open_ = sorted(missing)
    has, it = ("has", "it") if len(open_) == 1 else ("have", "them")
    print(f"sim-check: {', '.join(open_)} {has} no value, and no simulated constant "
          f"depends on {it}: the simulated constants are judged without the model's other "
          "checks (`afsmc check --const ...` runs those)", file=sys.stderr)
    return checked


def _judge_all(args: argparse.Namespace, sourced: list[ir.Constant],
               budget: int | None) -> list[Evidence] | int:
    """Each simulated constant judged against its simulation, run in a child process
    (afsmc.simlib.sandbox), with progress on stderr; the exit code of E505 if a simulator
    fails in any way: an exception, an exit, a hang past --timeout, too much memory."""
    results: list[Evidence] = []
    started = time.monotonic()
    for i, c in enumerate(sourced, 1):
        assert c.source is not None
        if c.source.column is not None:  # a data file: its rows are the runs
            print(f"sim-check: [{i}/{len(sourced)}] {c.name} <- {c.source.display} "
                  f"({time.monotonic() - started:.1f} s)", file=sys.stderr)
            try:
                results.append(_from_data(args, c))
            except CompileError as exc:
                return fail(exc, args.json, wrapped=True)
            continue
        print(f"sim-check: [{i}/{len(sourced)}] {c.name} <- {c.source.ref} "
              f"({args.runs} runs, {time.monotonic() - started:.1f} s)", file=sys.stderr)
        try:
            x = sandbox.sample(c.source.ref, args.runs, args.seed, timeout=args.timeout,
                               budget=budget)
            bad = int(x.size - np.count_nonzero(np.isfinite(x)))
            if bad:
                raise sandbox.SimulatorFailure(f"{bad:,} of its {x.size:,} samples are not "
                                               "finite numbers (inf or nan)")
            with np.errstate(all="ignore"):  # a sum past 1e308 is inf, and said so
                results.append(judge(c, args.runs, args.seed, samples=x,
                                     confidence=args.confidence))
        except Exception as exc:  # a broken third-party simulator: report, don't crash
            return fail(CompileError([Diagnostic(
                codes.E505, Severity.ERROR, f"simulator '{c.source.ref}' failed: {exc}",
                c.source.span)]), args.json, wrapped=True)
    return results


def _from_data(args: argparse.Namespace, c: ir.Constant) -> Evidence:
    """A constant backed by a data file judged by the rule of its shape, the file's values
    standing for the runs (a `prob`'s column holds outcomes)."""
    assert c.source is not None
    x = datafile.read(args.file, c, outcomes=c.declared_type == "prob")
    e = judge(c, len(x), 0, samples=x, confidence=args.confidence,
              kind=data_kind(c))
    return dataclasses.replace(e, ref=c.source.display, seed=None)


def _update(args: argparse.Namespace, text: str, drifted: list[Evidence],
            by_name: dict[str, ir.Constant]) -> int | None:
    """--update: rewrite the drifted constants in FILE, if the new text checks as
    `afsmc check` would check it; the exit code if it cannot (the file unchanged)."""
    date = _today()
    changes = {e.name: (e.suggestion, f"{e.ref}, {e.runs} runs, seed {e.seed}, {date}"
                        if e.seed is not None else f"{e.ref}, {e.runs} rows, {date}")
               for e in drifted}
    new = rewrite(text, args.file, changes)
    refused = _refuse(args, text, new, drifted, by_name)
    if refused is not None:
        return fail(CompileError(refused), args.json, wrapped=True)
    # Rewriting the input is the point here: no `protect`; keep its line endings and mode.
    try:
        write_atomic(args.file, new, newline=None)
    except CompileError as exc:  # E003: the file cannot be written (it is left as it was)
        return fail(exc, args.json, wrapped=True)
    return None


def _refuse(args: argparse.Namespace, old: str, new: str, drifted: list[Evidence],
            by_name: dict[str, ir.Constant]) -> list[Diagnostic] | None:
    """E509 at each drifted constant if the rewritten file has an error the file as it is
    does not have (checked as `afsmc check` checks it), else None."""
    def errors(text: str) -> list[Diagnostic]:
        try:
            load(args.file, overrides(args), text=text)
        except CompileError as exc:
            return [d for d in exc.diagnostics if d.is_error]
        return []
    after = errors(new)
    if not after:
        return None
    before = {(d.code, d.message) for d in errors(old)}
    fresh = [d for d in after if (d.code, d.message) not in before]
    if not fresh:
        return None  # the file had these errors already (params without a value: E206)
    first = fresh[0]
    return [Diagnostic(
        codes.E509, Severity.ERROR,
        f"--update would write {e.name} = {short_text(e.suggestion)}, which does not check: "
        f"{first.code} {short_text(first.message, 100)}; {args.file} is left unchanged",
        by_name[e.name].span,
        hint=f"the simulation's mean is {e.mean:.4g}: check simulator '{e.ref}', or set the "
             "value by hand") for e in drifted]


def short_text(value: str, most: int = 40) -> str:
    return value if len(value) <= most else f"{value[:most]}... ({len(value):,} characters)"


def _today() -> str:
    # SOURCE_DATE_EPOCH (reproducible builds) pins the date in the provenance comment.
    epoch = os.environ.get("SOURCE_DATE_EPOCH")
    when = (datetime.datetime.fromtimestamp(int(epoch), datetime.UTC) if epoch and epoch.isdigit()
            else datetime.datetime.now(datetime.UTC))
    return when.date().isoformat()


def _table(results: list[Evidence]) -> None:
    if not results:
        return
    head = ("constant", "simulation", "declared", "mean", "CI of mean", "F(lo), F(hi)",
            "hull", "verdict")
    rows = [head]
    for e in results:
        cdf = f"{e.cdf_lo:.4f}, {e.cdf_hi:.4f}" if e.cdf_lo is not None and e.cdf_hi is not None \
            else "-"
        hull = f"[{e.hull[0]}, {e.hull[1]}]" if e.hull else "-"
        rows.append((e.name, e.ref, e.declared, f"{e.mean:.4g}",
                     f"[{e.mean_low:.4g}, {e.mean_high:.4g}]", cdf, hull,
                     {"inconclusive": "too few runs", "drifted": "DRIFTED"}.get(e.verdict,
                                                                               e.verdict)))
    widths = [max(len(r[i]) for r in rows) for i in range(len(head))]
    for r in rows:
        print("  ".join(cell.ljust(w) for cell, w in zip(r, widths, strict=True)).rstrip())
    conf = {e.confidence for e in results}
    few = sum(e.inconclusive for e in results)
    sims = [e for e in results if e.seed is not None]
    data = len(results) - len(sims)
    where = ([f"{sims[0].runs} runs, seed {sims[0].seed}"] if sims else []) + (
        [f"{data} from data files"] if data else [])
    print(f"\n{len(results)} constant(s), {sum(not e.consistent for e in results)} drifted"
          + (f", {few} with too few runs to judge" if few else "") + "; "
          + ", ".join(where) + ", confidence "
          + ", ".join(f"{c:g}" for c in sorted(conf))
          + ("; probabilities: Clopper-Pearson intervals"
             if any(e.method for e in results) else ""))
