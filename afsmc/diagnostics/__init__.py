"""Diagnostics are data: a code, a severity, a message, a span and an optional hint.

Every stage reports problems by appending to a :class:`Reporter`; one renderer turns
them into text, and formats.py into JSON or SARIF. No call site formats an error by hand,
and nothing user-facing is ever a Python traceback. Every code is declared once, in
codes.py (the registry), and explained in explanations/<CODE>.md.

- model.py: the data (Source, Span, Related, Diagnostic, Severity);
- codes.py: the registry (Code, REGISTRY, lookup);
- reporter.py: Reporter and CompileError;
- render.py: the text of a diagnostic;
- formats.py: JSON and SARIF;
- explain.py: the explanation files; docs.py: docs/diagnostics.md.
"""

from afsmc.diagnostics.codes import REGISTRY, Code, lookup
from afsmc.diagnostics.formats import to_json, to_sarif
from afsmc.diagnostics.model import (
    BOM,
    Diagnostic,
    Related,
    Severity,
    Source,
    Span,
    line_starts,
    split_lines,
)
from afsmc.diagnostics.render import TAB, render, render_all
from afsmc.diagnostics.reporter import CompileError, Reporter

__all__ = [
    "BOM",
    "REGISTRY",
    "TAB",
    "Code",
    "CompileError",
    "Diagnostic",
    "Related",
    "Reporter",
    "Severity",
    "Source",
    "Span",
    "line_starts",
    "lookup",
    "render",
    "render_all",
    "split_lines",
    "to_json",
    "to_sarif",
]
