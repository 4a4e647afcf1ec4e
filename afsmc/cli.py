"""The `afsmc` command line. Thin: each subcommand lives in afsmc/commands/<name>.py
with `add_arguments(parser)` and `run(args) -> int`.

Exit codes: 0 ok, 1 diagnostics (errors in the input, a failed check), 2 usage, 3 a bug in
afsmc (an internal error; its traceback goes to a file).
"""

from __future__ import annotations

import argparse
import importlib
import json
import os
import re
import shlex
import signal
import sys
import tempfile
import threading
import traceback
from collections.abc import Sequence
from typing import Any, TextIO

from afsmc import __version__
from afsmc.diagnostics import CompileError, Diagnostic, Severity, codes, render_all
from afsmc.heap import leave_to_exit
from afsmc.interrupt import JsonResult, Stopped
from afsmc.stack import run_deep

# name -> one-line help; the module afsmc.commands.<name> implements it
COMMANDS: dict[str, str] = {
    "check": "check an .afsm file and report every problem",
    "compile": "compile an .afsm file to PRISM, JANI, Graphviz DOT, or a controller (Python, C)",
    "verify": "check an .afsm file's properties with Storm (min/max/uniform for intervals)",
    "sweep": "evaluate a property over a range of a constant or a time bound; CSV, JSON, plots",
    "regions": "split a parameter box into regions where a requirement holds, fails or is unknown",
    "fmt": "rewrite .afsm files in the canonical layout (--check: only list them)",
    "lsp": "run the language server (LSP over stdio) for editors",
    "diagram": "render a mission diagram (SVG, PNG or PDF) with Graphviz",
    "report": "write a mission's assurance case: one HTML page (or Markdown) for a reviewer",
    "sim-check": "re-run the simulations behind `from sim` constants and judge them",
    "simulate": "Monte Carlo simulation of the machine: estimate its properties",
    "conform": "check logged runs against the spec: steps it does not allow, drifted figures",
    "explain": "explain a diagnostic code (e.g. E301) with a wrong and a right example, or list all",
    "schema": "print the JSON Schema of a command's --json output (verify, sweep, regions, simulate, conform)",
}


class _Parser(argparse.ArgumentParser):
    """`afsmc verify uav.afsm @scenario1.args`: arguments from a file, one or more per
    line, split as a shell would (quotes group, `#` starts a comment); used for the
    scenario presets in examples/."""

    _reading: tuple[str, ...] = ()  # the argument files being expanded, outermost first

    def __init__(self, *args: Any, **kwargs: Any) -> None:
        super().__init__(*args, **kwargs)
        # argparse takes `-5` for a value but `-5:10` or `-1,0` for an option ("--bound:
        # expected one argument"); no option of afsmc starts with a digit. (A private
        # attribute of argparse's, read by its _parse_optional since Python 3.2.)
        if hasattr(self, "_negative_number_matcher"):
            self._negative_number_matcher = re.compile(
                r"^-(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?(?:[:,][-+.\d:,eE]*)?$")

    def _read_args_from_files(self, arg_strings: list[str]) -> list[str]:
        # argparse reports a missing file as a usage error, but lets a file that is not
        # text in the locale's encoding raise UnicodeDecodeError: the same usage error.
        # argparse expands an argument file's own @FILE lines recursively: a file that names
        # itself (or a cycle) would recurse until Python's limit.
        chars = self.fromfile_prefix_chars or ""
        files = [a[1:] for a in arg_strings if a[:1] and a[0] in chars]
        for name in files:
            if os.path.realpath(name) in self._reading:
                self.error(f"the argument file {name!r} includes itself (through "
                           f"{' -> '.join(os.path.basename(f) for f in self._reading)})")
            try:
                with open(name) as f:  # as argparse opens it
                    f.read()
            except UnicodeDecodeError as exc:
                self.error(f"the argument file {name!r} is not text ({exc.reason} at "
                           f"byte {exc.start})")
            except OSError as exc:  # argparse would print the bare "[Errno 2] ..."
                self.error(f"cannot read the argument file {name!r}: {exc.strerror or exc}")
        if not files:
            return super()._read_args_from_files(arg_strings)
        # Expanding one list at a time: the files of this list are the ones being read for
        # the nested calls argparse makes on their contents.
        outer = self._reading
        out: list[str] = []
        try:
            for arg in arg_strings:
                if arg[:1] and arg[0] in chars:
                    self._reading = (*outer, os.path.realpath(arg[1:]))
                out += super()._read_args_from_files([arg])
                self._reading = outer
        finally:
            self._reading = outer
        return out

    def convert_arg_line_to_args(self, arg_line: str) -> list[str]:
        try:
            return shlex.split(arg_line, comments=True)
        except ValueError as exc:  # an unbalanced quote
            self.error(f"in an argument file, the line {arg_line.rstrip()!r}: {exc}")


def build_parser() -> argparse.ArgumentParser:
    parser = _Parser(
        prog="afsmc", fromfile_prefix_chars="@",
        description="Compiler for autonomous probabilistic finite-state machines (.afsm).")
    parser.add_argument("--version", action="version", version=f"afsmc {__version__}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    for name, help_text in COMMANDS.items():
        module = f"afsmc.commands.{name.replace('-', '_')}"
        try:
            mod = importlib.import_module(module)
        except ModuleNotFoundError as exc:
            if exc.name != module:
                raise
            continue  # a command whose module is not there (yet) is not offered
        p = sub.add_parser(name, help=help_text, description=help_text,
                           fromfile_prefix_chars="@")
        mod.add_arguments(p)
        p.set_defaults(_run=mod.run)
        commands[name] = p
    return parser


commands: dict[str, argparse.ArgumentParser] = {}  # each command's parser, by name


def _run(args: argparse.Namespace) -> int:
    try:
        code: int = args._run(args)
    except RecursionError:
        # A backstop: the parser (E113) and the resolver (E246) refuse what nests too deeply
        # for the recursion limit of afsmc.stack, so this should not happen.
        from afsmc.commands.common import fail

        return fail(CompileError([Diagnostic(
            codes.E114, Severity.ERROR, f"{_inputs(args)}: an expression is "
            "nested too deeply for afsmc", None,
            hint="shorten the longest expressions (long chains of operators or formulas "
            "that use each other)")]), getattr(args, "json", False),
            wrapped=args.command in ("verify", "sweep"))
    return code


def entry() -> int:
    """The `afsmc` command and `python -m afsmc`: `main`, then the process ends."""
    code = main()
    leave_to_exit()
    return code


def main(argv: Sequence[str] | None = None) -> int:
    parser = build_parser()
    args, extra = parser.parse_known_args(argv)
    if extra:
        # argparse says it with the top-level usage; the command's own is the one that
        # helps, unless the argument came before the command's name
        given = list(sys.argv[1:] if argv is None else argv)
        command = getattr(args, "command", None) or ""
        at = given.index(command) if command in given else 0
        where = commands.get(command, parser) if extra[0] not in given[:at] else parser
        where.error(f"unrecognized arguments: {' '.join(extra)}")
    if not getattr(args, "command", None):
        parser.print_help(sys.stderr)
        return 2
    previous = _on_sigterm()
    stdout = sys.stdout
    sys.stdout = _GuardedStdout(stdout)
    try:
        code: int = run_deep(lambda: _run(args))
        sys.stdout.flush()  # a full disk shows here, not as a traceback at the exit
    except StdoutError as exc:
        return _stdout_failed(exc, stdout)
    except KeyboardInterrupt as exc:
        terminated = _by_sigterm(exc)
        print("afsmc: terminated" if terminated else "afsmc: interrupted", file=sys.stderr)
        stopped = exc if isinstance(exc, Stopped) else None  # what was finished by then
        notes = stopped.notes if stopped else []
        errors: list[Diagnostic] = stopped.errors if stopped else []
        if errors:
            print(render_all(errors), file=sys.stderr)
        for note in notes:
            print(f"afsmc: {note}", file=sys.stderr)
        if getattr(args, "json", False):
            # --json promises one JSON object on stdout, a Ctrl-C included
            obj: dict[str, object] = {
                "interrupted": True, "diagnostics": [d.to_json() for d in errors] + [
                    {"code": codes.N412, "severity": "note", "message": n} for n in notes]}
            partial = stopped.partial if stopped else None  # the answers so far, as data
            if isinstance(partial, JsonResult):
                obj |= partial.to_json()
            print(json.dumps(obj, indent=2))
        return 128 + signal.SIGTERM if terminated else 130
    except BrokenPipeError:
        return 0
    except Exception as exc:  # a bug in afsmc: a report, not a traceback
        if os.environ.get("AFSMC_TRACEBACK"):
            raise
        return _internal_error(exc, getattr(args, "json", False))
    finally:
        sys.stdout = stdout
        if previous is not None:
            signal.signal(signal.SIGTERM, previous)
    return code


def _inputs(args: argparse.Namespace) -> str:
    """The input file(s) a command was given, for a message about them: `check` and `fmt`
    take several."""
    files = getattr(args, "files", None) or [getattr(args, "file", None) or "the input"]
    return ", ".join(str(f) for f in files)


class StdoutError(Exception):
    """Standard output failed (a full disk, a closed descriptor). Not an OSError, so that
    no command's handler for its own OSErrors (E413, E507) takes it for one of those."""


class _GuardedStdout:
    """sys.stdout while a command runs: its write errors become StdoutError, which main
    reports as E003 rather than as a bug in afsmc (a BrokenPipeError, `| head`, stays)."""

    def __init__(self, stream: TextIO | None) -> None:
        self._stream = stream  # None: the process started with descriptor 1 closed

    def write(self, text: str) -> int:
        if self._stream is None:  # print() would drop the results without a word
            raise StdoutError("standard output is closed")
        try:
            return self._stream.write(text)
        except BrokenPipeError:
            raise
        except OSError as exc:
            raise StdoutError(exc.strerror or str(exc)) from exc

    def flush(self) -> None:
        if self._stream is None or self._stream.closed:  # (the LSP closes it at its exit)
            return  # multiprocessing flushes before it starts a process
        try:
            self._stream.flush()
        except BrokenPipeError:
            raise
        except OSError as exc:
            raise StdoutError(exc.strerror or str(exc)) from exc

    def __getattr__(self, name: str) -> Any:
        if self._stream is None:
            raise AttributeError(name)
        return getattr(self._stream, name)


def _stdout_failed(exc: StdoutError, stdout: TextIO | None) -> int:
    """E003 on stderr (--json cannot reach a stdout that fails), exit 1. Descriptor 1 then
    points at /dev/null, so that Python's last flush at the exit prints no traceback."""
    from afsmc.commands.common import color_enabled

    print(render_all([Diagnostic(codes.E003, Severity.ERROR, f"cannot write to standard output: "
                                 f"{exc}; the results are lost", None,
                                 hint="write them to a file with -o where the command has "
                                 "it, or free space where standard output goes")],
                     color_enabled()), file=sys.stderr)
    try:
        fd = stdout.fileno() if stdout is not None else None
    except (OSError, ValueError):  # not a file (a test's capture)
        fd = None
    if fd is not None:
        null = os.open(os.devnull, os.O_WRONLY)
        os.dup2(null, fd)
        os.close(null)
    return 1


def _internal_error(exc: Exception, as_json: bool) -> int:
    """A bug in afsmc, not in the input: say so in one line, keep the traceback in a file
    for the report (AFSMC_TRACEBACK=1 prints it instead), exit 3."""
    fd, path = tempfile.mkstemp(prefix="afsmc-crash-", suffix=".txt")
    with os.fdopen(fd, "w", encoding="utf-8") as f:
        f.write(f"afsmc {__version__}, argv {sys.argv!r}\n")
        traceback.print_exception(exc, file=f)
    # One line, however many lines or characters the exception's text has (the file has it all).
    what = " ".join(str(exc).split())
    what = what if len(what) <= 200 else what[:200] + "..."
    message = (f"internal error (a bug in afsmc, not in your input): {type(exc).__name__}: "
               f"{what}; the traceback is in {path}; please report it with that file")
    print(f"afsmc: {message}", file=sys.stderr)
    if as_json:
        print(json.dumps({"diagnostics": [
            {"code": codes.E009, "severity": "error", "message": message}]}, indent=2))
    return 3


class Terminated(KeyboardInterrupt):
    """SIGTERM (`kill`, a CI timeout): stop as for a Ctrl-C, so that the Storm process is
    stopped and the answers verify had by then are printed, not lost."""


def _by_sigterm(exc: BaseException) -> bool:
    """Was this interrupt a SIGTERM? (The guard re-raises it as its own Interrupted.)"""
    seen: BaseException | None = exc
    while seen is not None:
        if isinstance(seen, Terminated):
            return True
        seen = seen.__cause__ or seen.__context__
    return False


def _raise_terminated(signum: int, frame: object) -> None:
    raise Terminated


def _on_sigterm() -> Any:
    """Handle SIGTERM like SIGINT while a command runs; returns the handler to restore
    (None where Python lets only the main thread set one)."""
    if threading.current_thread() is not threading.main_thread():
        return None
    return signal.signal(signal.SIGTERM, _raise_terminated)


if __name__ == "__main__":
    sys.exit(main())
