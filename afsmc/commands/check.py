"""`afsmc check FILE...`: report every problem of each file; exit 1 if any is an error.
`-` reads standard input (as `fmt -` does). `--format json|sarif` writes the diagnostics
on standard output for other programs (`--json` is `--format json`)."""

from __future__ import annotations

import argparse
import sys

from afsmc.api.mission import Mission
from afsmc.commands.common import add_consts, overrides, report, usage_error
from afsmc.diagnostics import CompileError, Diagnostic, Severity
from afsmc.diagnostics.formats import to_sarif
from afsmc.files import decode_source
from afsmc.text import plural

FORMATS = ("text", "json", "sarif")


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("files", nargs="+", metavar="FILE",
                   help="the .afsm files ('-': standard input)")
    add_consts(p)
    p.add_argument("--format", choices=FORMATS, default=None,
                   help="text on standard error (the default), or JSON or SARIF 2.1.0 on "
                        "standard output")
    p.add_argument("--json", action="store_true", help="print diagnostics as JSON "
                   "(--format json)")
    p.add_argument("--werror", action="store_true", help="treat warnings as errors")


def run(args: argparse.Namespace) -> int:
    if args.files.count("-") > 1:
        usage_error("'-' (standard input) is given more than once")
    if args.json and args.format not in (None, "json"):
        usage_error(f"--json is --format json; it cannot go with --format {args.format}")
    fmt = "json" if args.json else args.format or "text"
    args.json = fmt == "json"  # an internal error is reported as JSON too (cli.main)
    # Every file's diagnostics, in the order of the files: one report (one JSON list).
    diags: list[Diagnostic] = []
    checked: list[Mission] = []
    for path in args.files:
        try:
            if path == "-":  # strictly UTF-8, as a file is read
                text = decode_source(sys.stdin.buffer.read(), "<stdin>")
                checked.append(Mission.open("<stdin>", overrides(args), text=text))
            else:
                checked.append(Mission.open(path, overrides(args)))
            diags += checked[-1].check()
        except CompileError as exc:
            diags += exc.diagnostics
    if fmt == "sarif":
        print(to_sarif(diags))
    else:
        report(diags, fmt == "json")
    if any(d.severity is Severity.ERROR for d in diags):
        return 1
    warnings = sum(d.severity is Severity.WARNING for d in diags)
    if fmt == "text" and not warnings:
        # Success says so, in one line: silence could as well be a check that never ran.
        print(clean_summary(args.files, checked), file=sys.stderr)
    if args.werror and warnings:
        if fmt == "text":  # the summary above counts them as warnings: say why exit 1
            print(f"afsmc: --werror: {warnings} warning(s) treated as errors", file=sys.stderr)
        return 1
    return 0


def clean_summary(files: list[str], checked: list[Mission]) -> str:
    """The line `check` prints when no file has an error or a warning: what was checked."""
    if len(checked) != 1:
        return f"{len(checked)} files: no errors, no warnings"
    m = checked[0].model
    name = "<stdin>" if files[0] == "-" else files[0]
    if m.composition is not None:
        agents = m.composition.agents
        sizes = ", ".join([plural(len(agents), "agent"),
                           plural(sum(len(a.model.modes) for a in agents), "mode"),
                           plural(len(m.variables), "variable"),
                           plural(len(m.properties), "property", "properties")])
        return f"{name}: no errors, no warnings (mission {m.name}: {sizes})"
    sizes = ", ".join([plural(len(m.modes), "mode"), plural(len(m.variables), "variable"),
                       plural(len(m.properties), "property", "properties")])
    return f"{name}: no errors, no warnings (machine {m.name}: {sizes})"
