"""The one renderer of diagnostics as text: `file:line:col: error[E123]: message`, the
source line with a caret under the span, then the hint and the related places."""

from __future__ import annotations

import unicodedata
from collections.abc import Callable, Iterable

from afsmc.diagnostics.model import Diagnostic, Severity, Span

TAB = "    "
# A source line longer than this is shown in part, around the place (LONG_LINE characters).
LONG_LINE = 400


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
    length = span.source.line_length(span.line)
    if length > LONG_LINE:
        return _long_excerpt(span, length)
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


def _long_excerpt(span: Span, length: int) -> list[str]:
    """The part of a line longer than LONG_LINE around the span's start, '...' where the
    line goes on: each diagnostic's cost is then bounded, however long the line (a file
    of 50,000 declarations on one line would otherwise print that line 50,000 times)."""
    start = min(span.column - 1, length)
    lo = max(0, start - LONG_LINE // 4)
    hi = min(length, lo + LONG_LINE)
    text = span.source.line(span.line, lo, hi)
    end = span.end_column - 1 if span.end_line == span.line else hi
    end = min(max(end, start + 1), max(hi, start + 1))
    before, after = ("..." if lo > 0 else ""), ("..." if hi < length else "")
    caret = " " * (len(before) + _cells(text[:start - lo])) + "^" * max(
        1, _cells(text[start - lo:end - lo]))
    pad = " " * len(str(span.line))
    return [f" {pad} |", f" {span.line} | {before}{_shown(text)}{after}", f" {pad} | {caret}"]


def render_all(diags: Iterable[Diagnostic], color: bool = False) -> str:
    diags = list(diags)
    parts = [render(d, color) for d in diags]
    errors = sum(d.is_error for d in diags)
    warnings = sum(d.severity is Severity.WARNING for d in diags)
    if errors or warnings:
        parts.append(f"{errors} error(s), {warnings} warning(s)")
    return "\n\n".join(parts[:-1]) + ("\n\n" if len(parts) > 1 else "") + parts[-1] if parts else ""
