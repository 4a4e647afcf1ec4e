"""Arguments and output helpers shared by subcommands."""

from __future__ import annotations

import argparse
import json
import math
import os
import sys
from collections.abc import Callable, Iterable
from dataclasses import replace

from afsmc.diagnostics import CompileError, Diagnostic, render_all
from afsmc.diagnostics import to_json as diags_to_json
from afsmc.interrupt import JsonResult
from afsmc.lower.lowering import RESOLUTIONS
from afsmc.lower.reduce import Reductions
from afsmc.resolve import parse_override


def add_file(p: argparse.ArgumentParser) -> None:
    p.add_argument("file", metavar="FILE", help="the .afsm file")


MAX_SEED = 2**64 - 1  # numpy's generators take no negative seed; a larger one adds nothing
MIN_JOBS_CAP = 4  # --jobs may be this many even on a machine with fewer cores
MAX_JOB_TASKS = 4096  # --jobs with --dask: the tasks a cluster's work is cut into


def integer(lo: int, hi: int) -> Callable[[str], int]:
    """An argparse type: an integer from `lo` to `hi` (`1_000` allowed); outside, a usage
    error (exit 2) that states the bound. Every integer option of afsmc has one."""
    def parse(text: str) -> int:
        try:
            n = int(text.replace("_", ""))
        except ValueError:
            n = lo - 1
        if not lo <= n <= hi:
            raise argparse.ArgumentTypeError(f"expected an integer from {lo:,} to {hi:,}, "
                                             f"got {text!r}")
        return n
    return parse


def number(lo: float, hi: float, *, open_lo: bool = True) -> Callable[[str], float]:
    """An argparse type: a number in (lo, hi] (`open_lo=False`: [lo, hi]); outside, a usage
    error that states the interval."""
    def parse(text: str) -> float:
        try:
            x = float(text)
        except ValueError:
            x = math.nan
        if not (math.isfinite(x) and (lo < x if open_lo else lo <= x) and x <= hi):
            raise argparse.ArgumentTypeError(
                f"expected a number in {'(' if open_lo else '['}{lo:g}, {hi:g}], got {text!r}")
        return x
    return parse


def max_jobs() -> int:
    """The most local worker processes --jobs may ask for: the cores this process may run
    on, or MIN_JOBS_CAP if that is more (each worker holds its own model and Storm)."""
    try:
        cores = len(os.sched_getaffinity(0))
    except (AttributeError, OSError):
        cores = os.cpu_count() or 1
    return max(MIN_JOBS_CAP, cores)


def refuse_jobs(jobs: int | None, dask: str | None) -> None:
    """Exit 2 if --jobs asks for more local processes than max_jobs() (with --dask the
    cluster's workers run the tasks: --jobs only sizes them)."""
    if jobs is not None and dask is None and jobs > max_jobs():
        usage_error(f"--jobs {jobs:,}: at most {max_jobs()} local processes (the cores of "
                    f"this machine, or {MIN_JOBS_CAP} if that is more): more would only "
                    "share the cores, each with its own model in memory")


JOBS_HELP = (f"at most the number of cores, or {MIN_JOBS_CAP} if that is more; with "
             f"--dask at most {MAX_JOB_TASKS:,}")


def add_seed(p: argparse.ArgumentParser) -> None:
    p.add_argument("--seed", type=integer(0, MAX_SEED), default=0, metavar="S",
                   help="random seed, an integer from 0 to 2^64 - 1 (default 0)")


def dask_address(text: str) -> str:
    """`--dask`: a scheduler address, `[scheme://]host:port` (Dask's own parser would fail
    only when connecting, with a traceback)."""
    import re

    if not re.fullmatch(r"(?:[a-z]+://)?(?:\[[0-9a-fA-F:]+\]|[^\s:/\[\]]+):\d+", text):
        raise argparse.ArgumentTypeError(
            f"expected a Dask scheduler address such as tcp://127.0.0.1:8786, got {text!r}")
    return text


def add_consts(p: argparse.ArgumentParser) -> None:
    p.add_argument("--const", "-c", action="append", default=[], metavar="NAME=VALUE",
                   help="give an open constant ('param') a value; repeatable, or NAME=V,NAME=V")


def add_resolve(p: argparse.ArgumentParser, default: str | None = "nondet",
                extra: str = "") -> None:
    """`default=None` lets a command tell whether --resolve was given."""
    # floor/ceil: the paper's words, and simulate's aliases of lo/hi
    p.add_argument("--resolve", choices=RESOLUTIONS, default=default,
                   type=lambda v: {"floor": "lo", "ceil": "hi"}.get(v, v),
                   help="interval constants [lo, hi]: nondeterministic choice (MDP, min/max "
                        "bounds; default), uniform random choice (DTMC), or always lo / hi "
                        "(also written floor / ceil)" + extra)


def add_reductions(p: argparse.ArgumentParser) -> None:
    g = p.add_argument_group("exact state-space reductions (all on by default)")
    g.add_argument("--no-reduce", action="store_true", help="turn every reduction off")
    g.add_argument("--no-dead-reset", action="store_true",
                   help="keep dead variables (no live-variable reset)")
    g.add_argument("--no-reorder", action="store_true",
                   help="keep the declaration order of variables")
    g.add_argument("--no-saturate", action="store_true",
                   help="keep the full range of growing counters (e.g. mission time)")
    sym = g.add_mutually_exclusive_group()
    sym.add_argument("--symmetry", action="store_const", const="on", dest="symmetry",
                     help="keep alike agents of a composed mission in a canonical order (one "
                     "state per set of their local states) even where an output names the "
                     "agents (--strategy, --witness: they then name slots); a note says why "
                     "not where the mission or a property tells them apart (default: applied "
                     "where exact and nothing asked for names the agents; the output says "
                     "which)")
    sym.add_argument("--no-symmetry", action="store_const", const="off", dest="symmetry",
                     help="check alike agents as they are, each state of each ordering")


def reductions(args: argparse.Namespace) -> Reductions:
    """The reductions asked for; the symmetry's "auto" is decided by the verification
    (afsmc.lower.symmetry.decide), and --no-reduce turns it off unless --symmetry."""
    given = getattr(args, "symmetry", None)
    if getattr(args, "no_reduce", False):
        return replace(Reductions.none(), symmetry=given or "off")
    return Reductions(dead_reset=not getattr(args, "no_dead_reset", False),
                      reorder=not getattr(args, "no_reorder", False),
                      saturate=not getattr(args, "no_saturate", False),
                      symmetry=given or "auto")


def overrides(args: argparse.Namespace) -> dict[str, str]:
    out: dict[str, str] = {}
    for item in args.const:
        for part in item.split(","):
            if not part.strip():
                continue
            try:
                name, value = parse_override(part)
            except ValueError as exc:
                usage_error(f"--const: {exc}")
            if name in out:
                usage_error(f"--const {name} is given twice ({name}={out[name]} and {name}={value})")
            out[name] = value
    return out


def add_baseline_options(p: argparse.ArgumentParser) -> None:
    """--baseline and --tolerance (`verify` and `report`)."""
    p.add_argument("--baseline", metavar="JSON",
                   help="compare with an earlier `afsmc verify --json` output: each "
                        "property's old and new bounds and verdict, flagged where the "
                        "verdict flips or a bound moves by more than --tolerance; exit 1 "
                        "on a flip to worse")
    p.add_argument("--tolerance", type=_tolerance, default=0.0, metavar="EPS",
                   help="with --baseline: flag a bound that moved by more than EPS "
                        "(absolute; default 0: any change)")


def _tolerance(text: str) -> float:
    try:
        v = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a number, got {text!r}") from None
    if not v >= 0 or v == float("inf"):
        raise argparse.ArgumentTypeError(f"expected a finite number >= 0, got {text!r}")
    return v


def usage_error(message: str) -> None:
    print(f"afsmc: error: {message}", file=sys.stderr)
    raise SystemExit(2)


def color_enabled() -> bool:
    return sys.stderr.isatty()


def report(diags: Iterable[Diagnostic], as_json: bool = False) -> None:
    diags = list(diags)
    if as_json:
        print(diags_to_json(diags))
    elif diags:
        print(render_all(diags, color_enabled()), file=sys.stderr)


def fail(exc: CompileError, as_json: bool = False, wrapped: bool = False) -> int:
    """Print the diagnostics (as text, as a JSON list, or -- `wrapped`, for commands whose
    --json output is an object -- as `{"diagnostics": [...]}`, followed by what the command
    had finished, `exc.partial`, if it has a JSON form: verify's answered queries) and return
    exit code 1."""
    if as_json and wrapped:
        obj: dict[str, object] = {"diagnostics": [d.to_json() for d in exc.diagnostics]}
        if isinstance(exc.partial, JsonResult):
            obj |= exc.partial.to_json()
        print(json.dumps(obj, indent=2))
        return 1
    report(exc.diagnostics, as_json)
    return 1


def print_json(obj: object) -> None:
    print(json.dumps(obj, indent=2, sort_keys=False))


def answer_json(name: str, obj: object) -> str:
    """The text `afsmc NAME --json` prints: `obj` through its published model
    (afsmc.answer.schema.published), so that it is what the command's schema says. The
    models are imported only for --json: pydantic takes half a second to load."""
    from afsmc.answer.schema import published

    return json.dumps(published(name, obj), indent=2)
