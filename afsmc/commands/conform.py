"""`afsmc conform FILE LOGS...`: replay logged runs (the robot's, in the format of
docs/robot.md) against the spec: every step it does not allow, and every probability and
interval constant estimated from the steps and judged as sim-check judges a simulation;
`--update` rewrites the drifted figures in place."""

from __future__ import annotations

import argparse
import sys

from afsmc.api.conform import Conformance, conform_file
from afsmc.commands.common import add_consts, answer_json, fail, overrides, report
from afsmc.commands.sim_check import add_judging, table
from afsmc.diagnostics import CompileError
from afsmc.files import check_writable


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("file", metavar="FILE", help="the .afsm file")
    p.add_argument("logs", metavar="LOG", nargs="+",
                   help="logged runs: JSON Lines (one step a line), or CSV for a name "
                        "ending in .csv (docs/robot.md, 'The log format')")
    add_consts(p)
    add_judging(p, "logs'")
    p.add_argument("--json", action="store_true",
                   help="print the result as JSON (schema: afsmc schema conform)")


def run(args: argparse.Namespace) -> int:
    try:
        if args.update:  # a file it cannot rewrite is said before the logs are read
            check_writable(args.file)
        res = conform_file(args.file, overrides(args), args.logs, update=args.update,
                           confidence=args.confidence)
    except CompileError as exc:
        return fail(exc, args.json, wrapped=True)
    if args.json:
        print(answer_json("conform", res.to_json()))
        return 0 if res.ok else 1
    _text(res)
    if res.updated:
        print(f"conform: updated {len(res.updated)} constant(s) in {args.file}: "
              + ", ".join(f"{e.name} = {e.suggestion}" for e in res.updated), file=sys.stderr)
    if res.diagnostics:
        report(res.diagnostics)
    return 0 if res.ok else 1


def _text(res: Conformance) -> None:
    print(f"{res.path}: {res.steps:,} steps in {res.runs:,} run(s) of {len(res.logs)} log(s); "
          f"{len(res.violations)} not allowed by the spec")
    if res.ambiguous:
        print(f"({res.ambiguous:,} steps' changes fit several outcomes: not counted as "
              "evidence of which)")
    if res.evidence:
        print()
        table(res.evidence, "logs", "trials")
    if res.unexercised:
        print(f"not exercised by the logs: {', '.join(res.unexercised)}")
