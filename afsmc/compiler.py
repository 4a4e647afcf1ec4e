"""The pipeline in one place: read -> parse -> resolve -> check -> lower -> reduce.

Commands call these functions; each raises CompileError with every diagnostic it
collected, so a caller renders them once. Reading and writing files is `afsmc.files`.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field

from afsmc import check
from afsmc.diagnostics import CompileError, Diagnostic, Reporter, codes
from afsmc.files import read_source
from afsmc.heap import collector_paused
from afsmc.lower.lowering import Lowered, Resolution, lower
from afsmc.lower.reduce import Reductions, reduce
from afsmc.model import ir
from afsmc.resolve import resolve
from afsmc.resolve.resolver import PropertyScope
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
    # What further properties may read (with_properties); None for a Checked made by hand.
    scope: PropertyScope | None = field(default=None, compare=False, repr=False)


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
                   resolved.open_reads, resolved.scope)


def with_properties(checked: Checked, queries: Sequence[tuple[str, ast.PQuery | ast.RQuery]],
                    *, run_checks: bool = True) -> Checked:
    """The checked model with further properties (name, parsed query), resolved and checked
    against the model as its own properties are, appended to its properties: the ad-hoc
    properties of `verify --formula`. Their diagnostics point into their own text. The
    file's warnings that a declaration is never used (W303, W304) are dropped for what
    the new properties read. Raises CompileError if any of them is an error."""
    if not queries:
        return checked
    assert checked.scope is not None, "a model loaded by compiler.load"
    adhoc = checked.scope.resolve(queries)
    found = list(adhoc.diagnostics)
    model = dataclasses.replace(checked.model,
                                properties=checked.model.properties + adhoc.properties)
    if run_checks and not any(d.is_error for d in found):
        said = set(checked.diagnostics)  # what the model's labels say, said again
        for p in adhoc.properties:  # one by one: the diagnostics in the formulas' order
            found += [d for d in check.run_properties(model, [p]) if d not in said]
    declared: list[ir.Variable | ir.Constant | ir.Formula] = [
        *model.variables, *model.constants, *model.formulas]
    read = {d.span for d in declared if d.name in adhoc.reads}
    kept = [d for d in checked.diagnostics
            if not (d.code in (codes.W303, codes.W304) and d.span in read)]
    if any(d.is_error for d in found):  # with the file's warnings, as `load` gives them
        raise CompileError(kept + found)
    return dataclasses.replace(checked, model=model, diagnostics=kept + found,
                               used_names=checked.used_names | adhoc.reads)


def lowered(model: ir.Model, resolution: Resolution = "nondet",
            reductions: Reductions | None = None) -> Lowered:
    """The lowered model with the exact reductions applied (all of them by default)."""
    return reduce(lower(model, resolution), Reductions() if reductions is None else reductions)


