"""The pipeline in one place: read -> parse -> resolve -> check -> lower -> reduce.

Commands call these functions; each raises CompileError with every diagnostic it
collected, so a caller renders them once. Reading and writing files is `afsmc.files`.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass

from afsmc import check
from afsmc.diagnostics import CompileError, Diagnostic, Reporter
from afsmc.files import read_source
from afsmc.heap import collector_paused
from afsmc.lower.lowering import Lowered, Resolution, lower
from afsmc.lower.reduce import Reductions, reduce
from afsmc.model import ir
from afsmc.resolve import resolve
from afsmc.stack import deep
from afsmc.syntax import ast
from afsmc.syntax.parser import parse


def parse_file(path: str) -> ast.Module:
    return parse(read_source(path), path)


@dataclass
class Checked:
    model: ir.Model
    diagnostics: list[Diagnostic]  # warnings and notes; errors raise instead
    # From afsmc.resolve.Resolved: the names the source uses where the IR keeps no
    # reference (for check.run), and, with `open_params`, the params without a value (the
    # E206 each would have been) and the constants that read them.
    used_names: frozenset[str]
    open_params: Mapping[str, Diagnostic]
    open_reads: Mapping[str, frozenset[str]]


@deep
def load(path: str, overrides: Mapping[str, str] | None = None, *, text: str | None = None,
         run_checks: bool = True, open_params: bool = False) -> Checked:
    """Parse, resolve and check one file. Raises CompileError if anything is an error.
    (`open_params`: see resolve; only without the checks, which need every value.)"""
    assert not (open_params and run_checks)
    with collector_paused():
        module = parse(read_source(path) if text is None else text, path)
        resolved = resolve(module, overrides, open_params=open_params)
        warnings = list(resolved.warnings)
        if run_checks:
            rep = Reporter(warnings)
            rep.extend(check.run(resolved.model, used_names=resolved.used_names))
            if rep.has_errors:
                raise CompileError(rep.sorted())
            warnings = rep.sorted()
    return Checked(resolved.model, warnings, resolved.used_names, resolved.open_params,
                   resolved.open_reads)


def lowered(model: ir.Model, resolution: Resolution = "nondet",
            reductions: Reductions | None = None) -> Lowered:
    """The lowered model with the exact reductions applied (all of them by default)."""
    return reduce(lower(model, resolution), Reductions() if reductions is None else reductions)


