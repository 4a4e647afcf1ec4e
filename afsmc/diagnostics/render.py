"""The one renderer of diagnostics as text: `file:line:col: error[E123]: message`, the
source line with a caret under the span, then the hint and the related places."""

from __future__ import annotations

import unicodedata
from collections.abc import Callable, Iterable

from afsmc.diagnostics.model import Diagnostic, Severity, Span

TAB = "    "


def render(diag: Diagnostic, color: bool = False) -> str:
    """`file:line:col: error[E123]: message`, the source line, a caret, then hint and notes."""

    def paint(text: str, code: str) -> str:
        return f"\x1b[{code}m{text}\x1b[0m" if color else text

    sev_color = {"error": "1;31", "warning": "1;33", "note": "1;36"}[diag.severity.value]
    head = paint(f"{diag.severity.value}[{diag.code}]", sev_color) + f": {diag.message}"
    lines = []
    if diag.span is None:
        lines.append(head)
    else:
        lines.append(f"{diag.span}: {head}")
        lines.extend(_excerpt(diag.span, paint))
    if diag.hint:
        lines.append(f"  = hint: {diag.hint}")
    for rel in diag.related:
        lines.append(f"  = note: {rel.message} at {rel.span}")
        lines.extend(_excerpt(rel.span, paint))
    return "\n".join(lines)


def _shown(text: str) -> str:
    return text.replace("\t", TAB)


def _cells(text: str) -> int:
    """Terminal columns of `text` as shown: a tab is four, a wide (CJK) character two."""
    return sum(2 if unicodedata.east_asian_width(c) in "WF" else 1 for c in _shown(text))


def _excerpt(span: Span, paint: Callable[[str, str], str]) -> list[str]:
    text = span.source.line(span.line)
    if not text and span.start == span.end == 0:
        return []
    gutter = str(span.line)
    start = min(span.column - 1, len(text))
    # a span over several lines: underlined to the end of its first line
    end = span.end_column - 1 if span.end_line == span.line else len(text.rstrip())
    end = min(max(end, start + 1), max(len(text), start + 1))
    # The caret sits under the characters as a terminal draws them (columns, not characters).
    caret = " " * _cells(text[:start]) + "^" * max(1, _cells(text[start:end]))
    pad = " " * len(gutter)
    return [f" {pad} |", f" {gutter} | {_shown(text)}", f" {pad} | {caret}"]


def render_all(diags: Iterable[Diagnostic], color: bool = False) -> str:
    diags = list(diags)
    parts = [render(d, color) for d in diags]
    errors = sum(d.is_error for d in diags)
    warnings = sum(d.severity is Severity.WARNING for d in diags)
    if errors or warnings:
        parts.append(f"{errors} error(s), {warnings} warning(s)")
    return "\n\n".join(parts[:-1]) + ("\n\n" if len(parts) > 1 else "") + parts[-1] if parts else ""
