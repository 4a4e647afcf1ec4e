"""`afsmc sweep FILE --const T=0:900:25 --property success [--plot fig.png] [-o out.csv]`.

An open constant takes a range (`start:stop:step`, stop included) or a list (`a,b,c`);
several such constants sweep their grid (every combination, long-format CSV and JSON);
or `--bound 0:40:5` sweeps the step bound of the properties (F<=k, C<=k, I=k; a property
without one is an error, E410).
"""

from __future__ import annotations

import argparse
import math
import os
import sys
from collections.abc import Callable

from afsmc.api.sweep import sweep_file
from afsmc.commands.common import (
    JOBS_HELP,
    MAX_JOB_TASKS,
    add_file,
    answer_json,
    dask_address,
    fail,
    integer,
    refuse_jobs,
    usage_error,
)
from afsmc.commands.verify import (
    add_storm_options,
    progress_printer,
    refuse_bisim_on_symbolic,
    storm_options,
)
from afsmc.diagnostics import CompileError, Diagnostic, Severity, codes
from afsmc.files import PLOT_SUFFIXES, check_writable, write_atomic
from afsmc.verify.reports import sweep_verdicts
from afsmc.verify.reports.sweep import without_kept_note
from afsmc.verify.reports.sweep_result import SweepResult
from afsmc.verify.reports.sweep_values import MAX_POINTS, Number, parse_values


def add_arguments(p: argparse.ArgumentParser) -> None:
    add_file(p)
    p.add_argument("--const", "-c", action="append", default=[], metavar="NAME=VALUES",
                   help="an open constant's value; a range start:stop:step (stop included) or a "
                        "list a,b,c sweeps it: the x axis; several ranges sweep their grid "
                        "(every combination, the first varying slowest)")
    p.add_argument("--bound", metavar="RANGE",
                   help="sweep the step bound k of the properties (F<=k, G<=k, U<=k, C<=k, I=k; "
                        "each must have one) instead")
    add_storm_options(p)
    p.add_argument("-o", "--output", metavar="FILE",
                   help="write the points to FILE: JSON if it ends in .json, else CSV; "
                        "'-' is stdout")
    p.add_argument("--json", action="store_true", help="print the points as one JSON object")
    p.add_argument("--plot", metavar="FILE.png|FILE.svg",
                   help="draw min, max and uniform curves (matplotlib); for several constants, "
                        "heat maps of the first two (small multiples over the others)")
    p.add_argument("--jobs", "-j", type=integer(1, MAX_JOB_TASKS), metavar="N",
                   help="parallel processes on this machine (default: the number of cores; "
                        f"{JOBS_HELP}); "
                        "with --dask, it sizes the tasks instead: points that share one model "
                        "go out in N chunks (4 x N for a time bound), others one per point")
    p.add_argument("--dask", metavar="ADDRESS", type=dask_address,
                   help="run the points on this Dask scheduler (e.g. tcp://10.0.0.5:8786); "
                        "its workers need afsmc installed")


def split_consts(items: list[str]) -> tuple[dict[str, str], dict[str, list[Number]]]:
    """`N=2,T=0:900:25` and `T=100,200,300` -> fixed constants and the swept ones.

    A constant given twice is a usage error, except that a range or list replaces one
    fixed value of the same constant (`@preset.args --const DEADLINE=150:500:25`)."""
    given: list[tuple[str, list[str]]] = []
    for item in items:
        for part in item.split(","):
            part = part.strip()
            if not part:
                continue
            if "=" in part:
                name, value = (s.strip() for s in part.split("=", 1))
                if not name:
                    usage_error(f"--const {item}: expected NAME=VALUES")
                if not value:  # as the other commands say it (parse_override)
                    usage_error(f"--const: expected NAME=VALUES, got {part!r} (no value)")
                given.append((name, [value]))
            elif not given:
                usage_error(f"--const {item}: expected NAME=VALUES")
            else:
                given[-1][1].append(part)
    fixed: dict[str, str] = {}
    swept: dict[str, list[Number]] = {}
    for name, values in given:
        if len(values) == 1 and ":" not in values[0]:
            if name in fixed:
                usage_error(f"--const {name} is given twice ({name}={fixed[name]} and "
                            f"{name}={values[0]})")
            fixed[name] = values[0]
            continue
        if name in swept:
            usage_error(f"--const {name} is given two ranges")
        try:
            swept[name] = parse_values(",".join(values))
        except ValueError as exc:
            usage_error(f"--const {name}: {exc}")
    for name in swept:
        fixed.pop(name, None)
    return fixed, swept


def run(args: argparse.Namespace) -> int:
    refuse_bisim_on_symbolic(args)
    refuse_jobs(args.jobs, args.dask)
    fixed, swept = split_consts(args.const)
    if args.bound is not None:
        if swept:
            usage_error("sweep either one constant or --bound, not both")
        try:
            values = parse_values(args.bound)
        except ValueError as exc:
            usage_error(f"--bound: {exc}")
        if any(isinstance(x, bool) for x in values):
            usage_error(f"--bound {args.bound}: a step bound is a whole number, not true/false")
        variable, kind = "bound", "bound"
    else:
        if not swept:
            usage_error("give a constant a range (--const T=0:900:25) or use --bound")
        points = math.prod(len(v) for v in swept.values())
        if points > MAX_POINTS:
            usage_error(f"the grid of {' x '.join(swept)} has {points:,} points; at most "
                        f"{MAX_POINTS:,}")
        ((variable, values),) = swept.items() if len(swept) == 1 else (("", []),)
        kind = "const"
    if args.plot and os.path.splitext(args.plot)[1].lower() not in PLOT_SUFFIXES:
        usage_error(f"--plot {args.plot}: the name must end in .png or .svg")
    if args.plot is not None and args.output and os.path.realpath(args.plot) == os.path.realpath(args.output):
        usage_error(f"-o and --plot name the same file ({args.output}): the plot would replace "
                    "the CSV")
    to_stdout = args.output == "-"
    if to_stdout:
        if args.json:
            usage_error("-o - and --json both print to stdout; give one")
        args.output = None  # stdout, as without -o
    elif args.output is not None and not args.output:
        usage_error("-o needs a file name ('-' for stdout)")
    # The file's format follows its name; --json is what goes to stdout.
    file_json = (args.output or "").lower().endswith(".json")
    progress = progress_printer(args)

    def write(res: SweepResult) -> None:
        if args.output:
            text = answer_json("sweep", res.to_json()) + "\n" if file_json else res.to_csv()
            write_atomic(args.output, text, protect=(args.file,))
            if progress:
                progress(f"wrote {args.output}")
        if args.plot is not None:
            res.plot(args.plot, protect=(args.file,))
            if progress:
                progress(f"wrote {args.plot}")

    try:
        # A sweep can take hours: an output it could not write is said before it starts.
        if args.output:
            check_writable(args.output, protect=(args.file,))
        if args.plot is not None:
            check_writable(args.plot, protect=(args.file,))
        res = sweep_file(args.file, variable if len(swept) <= 1 else swept, values, kind=kind,
                         consts=fixed, properties=args.property, formulas=args.formula,
                         jobs=args.jobs, dask=args.dask, progress=progress,
                         options=storm_options(args)).raw
        write(res)
    except CompileError as exc:
        if not isinstance(exc.partial, SweepResult) or not exc.partial.points:
            return fail(exc, args.json, wrapped=True)
        return _failed_in_part(exc, exc.partial, write, args, to_stdout)
    except OSError as exc:  # the Dask scheduler is unreachable, or no process could start
        # (writing the outputs fails as E003 in write_atomic)
        return fail(CompileError([Diagnostic(codes.E413, Severity.ERROR, f"sweep failed: {exc}",
                                             None, hint="is a Dask scheduler running at "
                                             f"{args.dask}?" if args.dask else None)]),
                    args.json, wrapped=True)
    if args.json:
        print(answer_json("sweep", res.to_json()))
    elif to_stdout or (not args.output and not args.plot):
        sys.stdout.write(res.to_csv())
    if not args.json:
        # the symmetry reduction as verify's heading says it, once for the points alike
        said = dict.fromkeys(p.symmetry for p in res.points if p.symmetry is not None)
        for line in [*sweep_verdicts.summary(res), *said]:
            print(f"afsmc: {line}", file=sys.stderr)
    if progress:
        n = len(res.points)
        progress(f"{n} point{'' if n == 1 else 's'} in {res.seconds:.1f} s")
    return 0


def _failed_in_part(exc: CompileError, res: SweepResult, write: Callable[[SweepResult], None],
                    args: argparse.Namespace, to_stdout: bool) -> int:
    """Some points or queries failed: the others are written where the result would have
    gone (a failed query's cells empty, its JSON values null), then the errors; exit 1."""
    diags = without_kept_note(exc)
    try:
        write(res)
    except CompileError as bad:  # the outputs could not be written: the note keeps the points
        return fail(CompileError([*bad.diagnostics, *exc.diagnostics], res), args.json,
                    wrapped=True)
    if not args.json and (to_stdout or (not args.output and not args.plot)):
        sys.stdout.write(res.to_csv())
    return fail(CompileError(diags, res), args.json, wrapped=True)  # --json: points as data
