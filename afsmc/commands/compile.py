"""`afsmc compile FILE [-t prism|jani|dot|python|c] [-o DIR|FILE]`."""

from __future__ import annotations

import argparse
import os
import sys

from afsmc.api.mission import CONTROLLERS, Mission, available_targets, target_notes
from afsmc.commands.common import (
    add_consts,
    add_file,
    add_reductions,
    add_resolve,
    fail,
    overrides,
    reductions,
    report,
    usage_error,
)
from afsmc.controllers.c import with_header
from afsmc.diagnostics import CompileError
from afsmc.files import check_writable, write_atomic
from afsmc.lower.reduce import Reductions


def add_arguments(p: argparse.ArgumentParser) -> None:
    add_file(p)
    p.add_argument("-t", "--target", default="prism", choices=sorted(available_targets()),
                   help="output language (default: prism); python and c write the mission's "
                        "controller for the robot (docs/robot.md), from the model before the "
                        "reductions")
    p.add_argument("-o", "--output", metavar="DIR|FILE",
                   help="output directory, or file name (PRISM: a suffix such as .prism is "
                        "replaced by each file's); default: the current directory; '-' prints to stdout "
                        "(PRISM: the model, then '// ==== NAME.props' and the properties)")
    add_consts(p)
    add_resolve(p)
    add_reductions(p)


def outputs_for(path: str, output: str | None, suffixes: list[str]) -> dict[str, str]:
    stem = os.path.splitext(os.path.basename(path))[0]
    if output is None or os.path.isdir(output) or output.endswith(os.sep):
        directory = output or "."
        return {s: os.path.join(directory, stem + s) for s in suffixes}
    base, ext = os.path.splitext(output)
    if len(suffixes) == 1 and ext:
        return {suffixes[0]: output}  # one file (JANI, DOT): the name as given, x.json or g.gv
    # Only an output's own suffix is replaced: `-o out/patrol.cells-4` is not `out/patrol`.
    if ext not in (*suffixes, *KNOWN_SUFFIXES):
        base = output
    return {s: base + s for s in suffixes}


KNOWN_SUFFIXES = (".prism", ".props", ".pm", ".nm")  # PRISM's, replaced by its two files


def run(args: argparse.Namespace) -> int:
    if args.output == "":
        usage_error("-o: an empty name (give a directory, a file name, or '-' for stdout)")
    if args.output not in (None, "-") and os.path.exists(args.output) \
            and not (os.path.isdir(args.output) or os.path.isfile(args.output)):
        # `-o /dev/null` wrote /dev/null.prism and /dev/null.props
        usage_error(f"-o {args.output}: not a directory or a regular file (the outputs are "
                    "named after it); '-' prints them")
    if args.target == "dot" and args.output not in (None, "-") and \
            os.path.splitext(args.output)[1].lower() in (".svg", ".png", ".pdf"):
        # DOT text in x.svg is no picture; `diagram` runs Graphviz for one
        usage_error(f"-o {args.output}: 'compile -t dot' writes Graphviz's DOT text, not a "
                    f"picture; 'afsmc diagram {args.file} -o {args.output}' draws it")
    try:
        mission = Mission.open(args.file, overrides(args))
        try:
            # a controller is the robot's logic: its variables, never the reduced model's
            low = mission.lowered(args.resolve, Reductions.none() if args.target in
                                  CONTROLLERS else reductions(args))
        except CompileError:
            report(mission.diagnostics)
            raise
        report([*mission.diagnostics, *target_notes(args.target, low)])
        files = available_targets()[args.target](low)
        if args.output == "-":
            stem = os.path.splitext(os.path.basename(args.file))[0]
            for i, (suffix, text) in enumerate(files.items()):
                if i:  # where one file ends and the next begins (PRISM: model, properties)
                    sys.stdout.write(f"\n// ==== {stem}{suffix}\n")
                sys.stdout.write(text)
            return 0
        paths = outputs_for(args.file, args.output, list(files))
        if args.target == "c":  # the source includes the header by the name it is given
            files = with_header(files, os.path.basename(paths[".h"]))
        # Every output is checked before the first is written: nothing half-done.
        for path in paths.values():
            check_writable(path, protect=(args.file,))
        for suffix, text in files.items():
            write_atomic(paths[suffix], text, protect=(args.file,))
            print(f"wrote {paths[suffix]}", file=sys.stderr)
    except CompileError as exc:
        return fail(exc)
    return 0
