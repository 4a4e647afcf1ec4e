"""`afsmc report FILE [--const ...] -o report.html`: the assurance case of a mission, one
self-contained HTML page (or Markdown with --format md) from one verification
(afsmc.report)."""

from __future__ import annotations

import argparse
import datetime
import os
import sys

from afsmc.commands.common import (
    add_baseline_options,
    add_consts,
    add_file,
    fail,
    overrides,
)
from afsmc.commands.verify import (
    add_storm_options,
    positive,
    progress_printer,
    refuse_bisim_on_symbolic,
    storm_options,
)
from afsmc.compiler import load
from afsmc.diagnostics import CompileError
from afsmc.files import write_atomic
from afsmc.report import baseline as base
from afsmc.report import html, markdown
from afsmc.report.case import build, command

FORMATS = ("html", "md")


def add_arguments(p: argparse.ArgumentParser) -> None:
    add_file(p)
    add_consts(p)
    p.add_argument("-o", "--output", metavar="FILE",
                   help="where to write the report (default: <stem>.report.html or .md in "
                        "the current directory; - for standard output)")
    p.add_argument("--format", choices=FORMATS, default=None,
                   help="html (default; one page with the diagram inline) or md (Markdown "
                        "for a repository's docs); by default from -o's suffix")
    p.add_argument("--recheck", type=positive, metavar="RUNS",
                   help="re-run every simulation behind a `from sim` constant with RUNS "
                        "runs (as `afsmc sim-check --runs RUNS`); default: not re-checked")
    p.add_argument("--no-sensitivity", dest="sensitivity", action="store_false",
                   help="leave out \"What matters most\" (each requirement's derivative by "
                        "every figure: two more verifications per figure)")
    p.add_argument("--no-worst-case", dest="worst_case", action="store_false",
                   help="leave out \"The worst case\" (the strategies: on a large model, "
                        "verify --strategy costs a slower build)")
    p.add_argument("--no-causes", dest="causes", action="store_false",
                   help="leave out \"How it fails\" (the causes: another build of the model)")
    add_baseline_options(p)
    add_storm_options(p)
    p.set_defaults(json=False)


def generated_line() -> str:
    """The one line that differs between two reports of the same input: when it was made
    (SOURCE_DATE_EPOCH, if set, fixes it)."""
    epoch = os.environ.get("SOURCE_DATE_EPOCH")
    when = (datetime.datetime.fromtimestamp(int(epoch), datetime.UTC) if epoch and
            epoch.isdigit() else datetime.datetime.now(datetime.UTC))
    return f"Generated {when.strftime('%Y-%m-%d %H:%M:%S UTC')}."


def _format(args: argparse.Namespace) -> str:
    if args.format:
        return str(args.format)
    if args.output and args.output.endswith(".md"):
        return "md"
    return "html"


def run(args: argparse.Namespace) -> int:
    fmt = _format(args)
    out = args.output or os.path.splitext(os.path.basename(args.file))[0] + f".report.{fmt}"
    refuse_bisim_on_symbolic(args)
    say = progress_printer(args) if args.progress else None
    try:
        old = None
        if args.baseline:
            old = base.read(args.baseline, load(args.file, overrides(args)).model.name)
        case = build(args.file, overrides(args), options=storm_options(args),
                     properties=args.property, recheck=args.recheck or 0,
                     command=command(args.file, overrides(args), args.property,
                                     args.formula, args.engine), generated=generated_line(),
                     baseline=old, baseline_name=args.baseline or "",
                     tolerance=args.tolerance, formulas=args.formula,
                     sensitivity=args.sensitivity, worst_case=args.worst_case,
                     causes=args.causes, progress=say)
        text = (html if fmt == "html" else markdown).page(case)
        if out == "-":
            sys.stdout.write(text)
        else:
            write_atomic(out, text, protect=(args.file,))
            print(f"wrote {out}", file=sys.stderr)
    except CompileError as exc:
        return fail(exc)
    return 1 if case.baseline is not None and case.baseline.worse else 0
