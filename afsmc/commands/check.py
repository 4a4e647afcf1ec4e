"""`afsmc check FILE`: report every problem of a file; exit 1 if any is an error."""

from __future__ import annotations

import argparse

from afsmc.commands.common import add_consts, add_file, fail, overrides, report
from afsmc.compiler import load
from afsmc.diagnostics import CompileError


def add_arguments(p: argparse.ArgumentParser) -> None:
    add_file(p)
    add_consts(p)
    p.add_argument("--json", action="store_true", help="print diagnostics as JSON")
    p.add_argument("--werror", action="store_true", help="treat warnings as errors")


def run(args: argparse.Namespace) -> int:
    try:
        checked = load(args.file, overrides(args))
    except CompileError as exc:
        return fail(exc, args.json)
    report(checked.diagnostics, args.json)
    if args.werror and checked.diagnostics:
        return 1
    return 0
