"""Running one fuzz input through afsmc's commands, in process, and judging the answer.

Each input is written to a file and given to `check`, `fmt --diff` and, for a file that
checks, `compile` (PRISM, JANI and DOT on standard output), each through `afsmc.cli.main`
as the command line runs it. A file that fails its check fails `compile` the same way
(both load it), so `compile` of such a file is run only now and then.

The properties: no exit 3 (an internal error), no traceback on standard error, and an
answer within CPU_LIMIT seconds of CPU time per command; and `fmt` never refuses a file
that parses with E190 (its safety net: the layout would not parse back the same). `AFSMC_TRACEBACK` is set, so an
internal error raises here with its traceback instead of writing a crash file. The time
limit is on CPU time (SIGPROF), not wall time, so a loaded machine does not make an input
look slow, and it leaves SIGALRM to pytest-timeout.
"""

from __future__ import annotations

import argparse
import contextlib
import io
import os
import random
import signal
import tempfile
import time
import traceback
from collections.abc import Iterator
from dataclasses import dataclass, field
from pathlib import Path

CPU_LIMIT = 10.0  # seconds of CPU per command and input


class Timeout(BaseException):  # not an Exception: main must not catch it
    """The CPU limit of one command ran out."""


@dataclass
class Failure:
    kind: str  # "exit 3", "traceback", "timeout" or "formatter" (fmt's E190)
    argv: list[str]
    detail: str


@dataclass
class Verdict:
    failures: list[Failure] = field(default_factory=list)
    codes: dict[str, int] = field(default_factory=dict)  # command -> exit code
    cpu: float = 0.0  # seconds, all commands
    syntax_error: bool = False  # check reported an E1xx

    @property
    def ok(self) -> bool:
        return not self.failures


_PARSER: list[argparse.ArgumentParser] = []  # built once, by the real build_parser


@contextlib.contextmanager
def _fast_main() -> Iterator[None]:
    """afsmc.cli.main builds its argparse parser anew on every call (importing each
    command); the fuzzer calls it 100,000s of times, so the parser is built once, and used
    only for the fuzzer's own calls: a parser kept for good would hold the commands'
    functions as they were, and a later test that replaces one would not reach it."""
    from afsmc import cli

    real = cli.build_parser
    if not _PARSER:
        _PARSER.append(real())
    cli.build_parser = lambda: _PARSER[0]  # type: ignore[assignment]
    try:
        yield
    finally:
        cli.build_parser = real  # type: ignore[method-assign]


@contextlib.contextmanager
def _cpu_limit(seconds: float) -> Iterator[None]:
    def expire(signum: int, frame: object) -> None:
        raise Timeout

    previous = signal.signal(signal.SIGPROF, expire)
    signal.setitimer(signal.ITIMER_PROF, seconds)
    try:
        yield
    finally:
        signal.setitimer(signal.ITIMER_PROF, 0)
        signal.signal(signal.SIGPROF, previous)


def run_main(argv: list[str], cpu_limit: float = CPU_LIMIT) -> tuple[int | None, str, Failure | None]:
    """`afsmc ARGV` in process: the exit code (None if it did not end), standard error,
    and what went wrong if anything did."""
    from afsmc.cli import main

    out, err = io.StringIO(), io.StringIO()
    code: int | None = None
    failure = None
    old = os.environ.get("AFSMC_TRACEBACK")
    os.environ["AFSMC_TRACEBACK"] = "1"
    try:
        with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err), \
                _fast_main(), _cpu_limit(cpu_limit):
            try:
                code = main(argv)
            except SystemExit as exc:  # argparse's usage errors
                code = exc.code if isinstance(exc.code, int) else 2
    except Timeout:
        failure = Failure("timeout", argv, f"no answer within {cpu_limit} s of CPU")
    except Exception as exc:  # what main would have reported as an internal error
        failure = Failure("exit 3", argv, "".join(traceback.format_exception(exc)))
    finally:
        if old is None:
            del os.environ["AFSMC_TRACEBACK"]
        else:
            os.environ["AFSMC_TRACEBACK"] = old
    stderr = err.getvalue()
    if code in (130, 143):
        # main turned the fuzzer's own Ctrl-C or SIGTERM into an exit code: stop the run
        raise KeyboardInterrupt
    if failure is None and code == 3:
        failure = Failure("exit 3", argv, stderr)
    if failure is None and "Traceback (most recent call last)" in stderr:
        failure = Failure("traceback", argv, stderr)
    return code, stderr, failure


def judge(data: bytes, workdir: str | Path, rng: random.Random | None = None,
          cpu_limit: float = CPU_LIMIT, compile_share: float = 0.1,
          fmt_share: float = 1.0) -> Verdict:
    """Run the commands on `data` (written to WORKDIR/fuzz.afsm). `compile` runs on every
    file that checks and on `compile_share` of the others; `fmt` on every file without a
    syntax error and on `fmt_share` of the others (its parse is check's); both drawn from
    `rng`."""
    path = os.path.join(workdir, "fuzz.afsm")
    with open(path, "wb") as f:
        f.write(data)
    draw = (rng or random.Random(0)).random
    verdict = Verdict()
    start = time.process_time()
    code, stderr, failure = run_main(["check", path], cpu_limit)
    verdict.codes["check"] = -1 if code is None else code
    verdict.syntax_error = "error[E1" in stderr
    if failure:
        verdict.failures.append(failure)
    if not verdict.syntax_error or draw() < fmt_share:
        code, stderr, failure = run_main(["fmt", "--diff", path], cpu_limit)
        verdict.codes["fmt"] = -1 if code is None else code
        if failure is None and "error[E190]" in stderr:
            # the formatter's safety net: its output would not parse, or would mean
            # something else; a bug in fmt, even if reported with a code
            failure = Failure("formatter", ["fmt", "--diff", path], stderr)
        if failure:
            verdict.failures.append(failure)
    if verdict.codes["check"] == 0 or draw() < compile_share:
        for target in ("prism", "jani", "dot"):
            argv = ["compile", path, "-t", target, "-o", "-"]
            code, _, failure = run_main(argv, cpu_limit)
            verdict.codes[target] = -1 if code is None else code
            if failure:
                verdict.failures.append(failure)
    verdict.cpu = time.process_time() - start
    return verdict


def workdir() -> tempfile.TemporaryDirectory[str]:
    return tempfile.TemporaryDirectory(prefix="afsmc-fuzz-")
