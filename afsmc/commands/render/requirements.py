"""`afsmc verify`'s requirement options (--precision, --exact, --junit) and the verdicts in
its table: a column, then one line per requirement that does not hold, saying why."""

from __future__ import annotations

import argparse
import math
from collections.abc import Sequence

from afsmc.commands.common import fail, usage_error
from afsmc.diagnostics import CompileError
from afsmc.files import check_writable
from afsmc.text import num
from afsmc.verify.outcome.results import PropertyResult
from afsmc.verify.plan.precision import DEFAULT_PRECISION, EXACT_ENGINES, PARAMETER_PRECISION


def precision(text: str) -> float:
    """--precision EPS: a number strictly between 0 and 1."""
    try:
        eps = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a number such as 1e-9, got {text!r}") from None
    if not math.isfinite(eps) or not 0 < eps < 1:
        raise argparse.ArgumentTypeError(f"expected a number strictly between 0 and 1 (the "
                                         f"largest error allowed), got {text!r}")
    return eps


def add_requirement_options(p: argparse.ArgumentParser) -> None:
    p.add_argument("--precision", type=precision, metavar="EPS",
                   help="check with Storm's sound value iteration: every value within EPS "
                        f"of the true one (default with a requirement: {DEFAULT_PRECISION:g}; "
                        "without: Storm's faster, unguaranteed stopping rule)")
    p.add_argument("--exact", action="store_true",
                   help="build the model over rationals and solve it exactly (sparse engine; "
                        "small models): no error at all")
    p.add_argument("--junit", metavar="FILE",
                   help="write the requirements' verdicts as a JUnit XML report (one "
                        "testcase per property with a threshold)")


def refuse_requirement_options(args: argparse.Namespace) -> None:
    """Exit 2 for combinations that cannot work, before any Storm run."""
    if args.exact and args.precision is not None:
        usage_error("--exact and --precision exclude each other: exact values have no error")
    if args.exact and args.engine not in EXACT_ENGINES:
        usage_error(f"--exact needs the sparse engine (Storm builds exact models as sparse "
                    f"matrices only), not --engine {args.engine}")
    if args.precision is not None and args.engine == "dd":
        usage_error("the dd engine has no sound method, so --precision cannot hold: use "
                    "--engine sparse, hybrid or auto")
    try:  # said before the checks, not after them
        for out in (args.junit, args.traces_out):
            if out is not None:
                check_writable(out, protect=(args.file,))
    except CompileError as exc:
        raise SystemExit(fail(exc, args.json, wrapped=True)) from None


def with_verdicts(rows: list[list[str]], results: Sequence[PropertyResult]) -> list[list[str]]:
    """The table's rows with a verdict column, if any property is a requirement."""
    if not any(p.threshold is not None for p in results):
        return rows
    return [rows[0] + ["verdict"]] + [
        [*row, p.verdict.kind if p.verdict is not None else "-" if p.threshold is None else "no value"]
        for row, p in zip(rows[1:], results, strict=True)]


def verdict_lines(results: Sequence[PropertyResult]) -> list[str]:
    """Under the table: how sure the values are, and why each requirement has its verdict."""
    if not results:
        return []
    lines = []
    errors = {p.error for p in results}
    over_box = any(p.reference is not None for p in results)
    for error in sorted(errors, key=lambda e: -1.0 if e is None else e):
        who = "" if len(errors) == 1 else " (" + ", ".join(
            p.name for p in results if p.error == error) + ")"
        if error == 0:
            lines.append(f"values exact (rational arithmetic){who}")
        elif error is not None and over_box:
            lines.append(f"min and max within {num(error)} of the true extremes{who} (refined "
                         f"to {PARAMETER_PRECISION:g} over the interval probabilities, by the "
                         "engine named below)")
        elif error is not None:
            lines.append(f"every value within {num(error)} of the true one{who} (sound value "
                         "iteration)")
    for p in results:
        if p.verdict is not None:
            lines.append(f"{p.name}: {p.verdict.kind}: {p.verdict.reason}")
    return ["", *lines] if lines else []


def attained_lines(results: Sequence[PropertyResult]) -> list[str]:
    """Where in the interval probabilities' box each property's min and max were found."""
    out = []
    for p in results:
        if p.attained_at is None:
            continue
        at = {k: ", ".join(f"{n}={v:.6g}" for n, v in sorted(where.items()))
              for k, where in p.attained_at.items()}
        out.append(f"{p.name}: min at {at['min']}, max at {at['max']}")
    return ["", *out] if out else []
