"""What the language server learns from a text: the parse and resolution it runs on every
change (a few tens of milliseconds on examples/uav.afsm), and every diagnostic `afsmc check`
reports (about a second and a half on uav.afsm: the checks enumerate states)."""

from __future__ import annotations

from dataclasses import dataclass, field

from afsmc.compiler import load
from afsmc.diagnostics import CompileError, Diagnostic
from afsmc.model import ir
from afsmc.resolve import resolve
from afsmc.syntax import ast
from afsmc.syntax.parser import parse


@dataclass
class Fast:
    """What parsing and resolving found, before the slow checks."""

    module: ast.Module | None
    model: ir.Model | None
    diagnostics: list[Diagnostic] = field(default_factory=list)


def analyse_fast(text: str, path: str) -> Fast:
    try:
        module = parse(text, path)
    except CompileError as exc:
        return Fast(None, None, exc.diagnostics)
    try:
        model = resolve(module).model
    except CompileError as exc:
        return Fast(module, None, exc.diagnostics)
    return Fast(module, model, [])


def analyse_full(text: str, path: str) -> list[Diagnostic]:
    """Every diagnostic `afsmc check` reports for this text."""
    try:
        return load(path, text=text).diagnostics
    except CompileError as exc:
        return exc.diagnostics
