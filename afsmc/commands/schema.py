"""`afsmc schema NAME`: print the JSON Schema of `afsmc NAME --json` (verify, sweep,
regions, simulate), as docs/schemas/NAME.schema.json holds it."""

from __future__ import annotations

import argparse
import sys

from afsmc.answer import NAMES


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("name", metavar="NAME", choices=NAMES,
                   help="the command whose --json output the schema describes: "
                        + ", ".join(NAMES))


def run(args: argparse.Namespace) -> int:
    from afsmc.answer.schema import text

    sys.stdout.write(text(args.name))
    return 0
