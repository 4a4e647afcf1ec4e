"""`afsmc compile FILE [-t prism|jani|dot] [-o DIR|FILE]`."""

from __future__ import annotations

import argparse
import contextlib
import os
import sys
from collections.abc import Callable

from afsmc.commands.common import add_consts, add_file, add_resolve, fail, overrides, report
from afsmc.compiler import Checked, load, write_atomic
from afsmc.diagnostics import CompileError

# target -> (function from a checked model and args to {suffix: text}), registered below
TARGETS: dict[str, Callable[[Checked, argparse.Namespace], dict[str, str]]] = {}


def _prism(checked: Checked, args: argparse.Namespace) -> dict[str, str]:
    from afsmc.backends.prism import emit
    from afsmc.model.lower import lower

    out = emit(lower(checked.model, args.resolve))
    return {".prism": out.model, ".props": out.properties}


TARGETS["prism"] = _prism


def target(name: str) -> Callable[[Callable[[Checked, argparse.Namespace], dict[str, str]]],
                                  Callable[[Checked, argparse.Namespace], dict[str, str]]]:
    """Register another backend under `-t name`."""
    def deco(fn: Callable[[Checked, argparse.Namespace], dict[str, str]]) -> Callable[
            [Checked, argparse.Namespace], dict[str, str]]:
        TARGETS[name] = fn
        return fn
    return deco


def _load_targets() -> None:
    # Backends that register themselves; absent ones are simply not offered.
    for mod in ("afsmc.backends.jani", "afsmc.backends.dot"):
        with contextlib.suppress(ImportError):
            __import__(mod)


def add_arguments(p: argparse.ArgumentParser) -> None:
    _load_targets()
    add_file(p)
    p.add_argument("-t", "--target", default="prism", choices=sorted(TARGETS),
                   help="output language (default: prism)")
    p.add_argument("-o", "--output", metavar="DIR|FILE",
                   help="output directory, or file name (its suffix is replaced per output); "
                        "default: the current directory; '-' prints to stdout")
    add_consts(p)
    add_resolve(p)


def outputs_for(path: str, output: str | None, suffixes: list[str]) -> dict[str, str]:
    stem = os.path.splitext(os.path.basename(path))[0]
    if output is None or os.path.isdir(output) or output.endswith(os.sep):
        directory = output or "."
        return {s: os.path.join(directory, stem + s) for s in suffixes}
    base, _ = os.path.splitext(output)
    return {s: base + s for s in suffixes}


def run(args: argparse.Namespace) -> int:
    try:
        checked = load(args.file, overrides(args))
        report(checked.diagnostics)
        files = TARGETS[args.target](checked, args)
        if args.output == "-":
            for text in files.values():
                sys.stdout.write(text)
            return 0
        paths = outputs_for(args.file, args.output, list(files))
        for suffix, text in files.items():
            write_atomic(paths[suffix], text, protect=(args.file,))
            print(f"wrote {paths[suffix]}", file=sys.stderr)
    except CompileError as exc:
        return fail(exc)
    return 0
