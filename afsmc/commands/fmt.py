"""`afsmc fmt FILE... [--check] [--diff]`: rewrite .afsm files in the canonical layout.

Files are rewritten in place, atomically; `-` reads standard input and prints the result.
A file that does not parse is left untouched and its syntax error is reported.
A rewritten file keeps its permission bits and its line endings (CRLF stays CRLF); line
endings alone never make a file "not formatted".
"""

from __future__ import annotations

import argparse
import difflib
import sys

from afsmc.commands.common import report
from afsmc.diagnostics import CompileError, split_lines
from afsmc.files import read_source, write_atomic
from afsmc.syntax.fmt import format_text, line_ending
from afsmc.text import plural


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("files", nargs="+", metavar="FILE", help="the .afsm files ('-': standard input)")
    p.add_argument("--check", action="store_true",
                   help="change nothing; list the files that are not formatted (on standard "
                        "error: which lines would change) and exit 1 if any")
    p.add_argument("--diff", action="store_true",
                   help="change nothing; print what would change as a unified diff (with "
                        "--check, also exit 1 if anything would)")


def changed_lines(text: str, out: str) -> list[tuple[int, int]]:
    """The line ranges of `text` (1-based, inclusive) that formatting changes; a pure
    insertion counts as the line before it."""
    a, b = text.splitlines(), out.splitlines()
    spans = []
    for op, i1, i2, _, _ in difflib.SequenceMatcher(None, a, b, autojunk=False).get_opcodes():
        if op != "equal":
            spans.append((max(i1, 1) if i1 == i2 else i1 + 1, max(i2, 1)))
    return spans


def what_changes(path: str, text: str, out: str) -> str:
    """`fmt --check`'s line for a file it would reformat: where, and how to see and apply it."""
    spans = changed_lines(text, out)
    where = ", ".join(f"{lo}" if lo == hi else f"{lo}-{hi}" for lo, hi in spans[:8])
    more = f" and {len(spans) - 8} more places" if len(spans) > 8 else ""
    n = sum(hi - lo + 1 for lo, hi in spans)
    return (f"afsmc: {path}: the layout of {plural(n, 'line')} would change (line"
            f"{'s' if n > 1 else ''} {where}{more}); 'afsmc fmt --diff {path}' shows how, "
            f"'afsmc fmt {path}' rewrites it")


def run(args: argparse.Namespace) -> int:
    status = 0
    changed = 0
    for path in args.files:
        try:
            raw = sys.stdin.read() if path == "-" else read_source(path, newline="")
            text = raw.replace("\r\n", "\n").replace("\r", "\n")
            eol = line_ending(raw)
            out = format_text(text, "<stdin>" if path == "-" else path)
        except CompileError as exc:
            report(exc.diagnostics)
            status = 1
            continue
        if args.diff:
            name = "<stdin>" if path == "-" else path
            # In the file's own line endings, as fmt would write it: a CRLF file's patch
            # applies to it.
            patch = difflib.unified_diff(
                split_lines(raw), split_lines(out.replace("\n", eol)),
                f"{name} (as it is)", f"{name} (formatted)") if out != text else iter(())
            for line in patch:
                # a last line without its newline, marked as diff marks it (else it ran into
                # the next line of the patch)
                sys.stdout.write(line if line.endswith(("\n", "\r")) else
                                 line + "\n\\ No newline at end of file\n")
            changed += out != text
            if args.check and out != text:
                status = 1
        elif args.check:
            if out != text:
                print(path)
                print(what_changes("<stdin>" if path == "-" else path, text, out),
                      file=sys.stderr)
                changed += 1
                status = 1
        elif path == "-":
            sys.stdout.write(out)
        elif out != text:
            try:
                # In place: keep the file's permission bits and its line endings.
                write_atomic(path, out, newline=eol)
            except CompileError as exc:
                report(exc.diagnostics)
                status = 1
                continue
            print(f"reformatted {path}", file=sys.stderr)
    if args.check or args.diff:
        total = len(args.files)
        print(f"afsmc: {changed} of {plural(total, 'file')} would be reformatted" if changed
              else f"afsmc: {plural(total, 'file')} checked, all formatted" if status == 0
              else "afsmc: no file would be reformatted (a file has an error above)",
              file=sys.stderr)
    return status
