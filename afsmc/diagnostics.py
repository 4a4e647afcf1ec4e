"""Diagnostics are data: a code, a severity, a message, a span and an optional hint.

Every stage reports problems by appending to a :class:`Reporter`; one renderer turns
them into text. No call site formats an error by hand, and nothing user-facing is ever
a Python traceback.
"""

from __future__ import annotations

import bisect
import json
import re
import unicodedata
from collections.abc import Iterable, Sequence
from dataclasses import dataclass, field
from enum import StrEnum
from functools import cached_property
from typing import TYPE_CHECKING

if TYPE_CHECKING:  # afsmc.interrupt imports this module
    from afsmc.interrupt import JsonResult


class Severity(StrEnum):
    ERROR = "error"
    WARNING = "warning"
    NOTE = "note"


BOM = "\ufeff"


def line_starts(text: str) -> list[int]:
    """Where each line of `text` starts. Lines end at '\n' only, as the lexer counts them
    (and LSP): str.splitlines also breaks at form feeds and U+2028, which put excerpts and
    editor positions on the wrong line."""
    starts, i = [0], text.find("\n")
    while i >= 0:
        starts.append(i + 1)
        i = text.find("\n", i + 1)
    return starts


def split_lines(text: str) -> list[str]:
    """The lines of `text` with their endings ('\r\n', '\r' or '\n'): str.splitlines also
    breaks at form feeds and U+2028, which are not line ends in afsm."""
    return re.findall(r"[^\r\n]*(?:\r\n|\r|\n)|[^\r\n]+$", text)


@dataclass(frozen=True)
class Source:
    """The text of one input file, kept so diagnostics can quote it.

    Offsets index `text` as read, a leading byte-order mark included (so that edits by
    offset, e.g. `sim-check --update`, keep it); lines and columns leave the mark out, as
    editors do."""

    path: str
    text: str

    @cached_property
    def _starts(self) -> list[int]:
        return line_starts(self.text)

    def line(self, lineno: int) -> str:
        starts = self._starts
        if not 1 <= lineno <= len(starts):
            return ""
        end = starts[lineno] - 1 if lineno < len(starts) else len(self.text)
        text = self.text[starts[lineno - 1]:end].removesuffix("\r")
        return text.removeprefix(BOM) if lineno == 1 else text

    def position(self, offset: int) -> tuple[int, int]:
        """1-based (line, column) of a 0-based character offset."""
        offset = max(0, min(offset, len(self.text)))
        line = bisect.bisect_right(self._starts, offset)
        col = offset - self._starts[line - 1] + 1
        if line == 1 and offset > 0 and self.text.startswith(BOM):
            col -= 1
        return line, col


@dataclass(frozen=True)
class Span:
    """A half-open region of a source file; lines and columns are 1-based."""

    source: Source
    line: int
    column: int
    end_line: int
    end_column: int
    start: int = 0
    end: int = 0

    @staticmethod
    def at_offset(source: Source, start: int, end: int | None = None) -> Span:
        end = start + 1 if end is None else end
        line, col = source.position(start)
        eline, ecol = source.position(end)
        return Span(source, line, col, eline, ecol, start, end)

    @staticmethod
    def whole_file(source: Source) -> Span:
        return Span(source, 1, 1, 1, 1, 0, 0)

    def __str__(self) -> str:
        return f"{self.source.path}:{self.line}:{self.column}"

    def __repr__(self) -> str:  # keeps dataclass reprs short in test output
        return f"Span({self})"

    def __hash__(self) -> int:
        return hash((self.source.path, self.start, self.end))

    def __eq__(self, other: object) -> bool:
        return (
            isinstance(other, Span)
            and self.source.path == other.source.path
            and (self.start, self.end) == (other.start, other.end)
        )


@dataclass(frozen=True)
class Related:
    message: str
    span: Span


@dataclass(frozen=True)
class Diagnostic:
    code: str
    severity: Severity
    message: str
    span: Span | None
    hint: str | None = None
    related: tuple[Related, ...] = ()

    @property
    def is_error(self) -> bool:
        return self.severity is Severity.ERROR

    def sort_key(self) -> tuple[str, int, int, str]:
        if self.span is None:
            return ("", 0, 0, self.code)
        return (self.span.source.path, self.span.line, self.span.column, self.code)

    def to_json(self) -> dict[str, object]:
        out: dict[str, object] = {
            "code": self.code,
            "severity": self.severity.value,
            "message": self.message,
        }
        if self.span is not None:
            out.update(
                file=self.span.source.path,
                line=self.span.line,
                column=self.span.column,
                end_line=self.span.end_line,
                end_column=self.span.end_column,
            )
        if self.hint:
            out["hint"] = self.hint
        if self.related:
            out["related"] = [
                {"message": r.message, "file": r.span.source.path, "line": r.span.line,
                 "column": r.span.column}
                for r in self.related
            ]
        return out


@dataclass
class Reporter:
    """Collects diagnostics; stages keep going after an error so that all are reported."""

    diagnostics: list[Diagnostic] = field(default_factory=list)

    def error(self, code: str, message: str, span: Span | None, hint: str | None = None,
              related: Iterable[Related] = ()) -> None:
        self.diagnostics.append(
            Diagnostic(code, Severity.ERROR, message, span, hint, tuple(related)))

    def warning(self, code: str, message: str, span: Span | None, hint: str | None = None,
                related: Iterable[Related] = ()) -> None:
        self.diagnostics.append(
            Diagnostic(code, Severity.WARNING, message, span, hint, tuple(related)))

    def note(self, code: str, message: str, span: Span | None, hint: str | None = None) -> None:
        self.diagnostics.append(Diagnostic(code, Severity.NOTE, message, span, hint))

    @property
    def has_errors(self) -> bool:
        return any(d.is_error for d in self.diagnostics)

    def extend(self, diags: Iterable[Diagnostic]) -> None:
        self.diagnostics.extend(diags)

    def sorted(self) -> list[Diagnostic]:
        # Dedupe: the same problem reached by two routes is reported once.
        seen: set[tuple[str, str, int]] = set()
        out = []
        for d in sorted(self.diagnostics, key=Diagnostic.sort_key):
            key = (d.code, d.message, d.span.start if d.span else -1)
            if key not in seen:
                seen.add(key)
                out.append(d)
        return out


class CompileError(Exception):
    """Raised by a stage that cannot go on; carries every diagnostic collected so far.

    `partial`: what the stage had finished when it failed, for the caller to keep, so that
    one failed query does not lose an hour's others; None if there is nothing to keep. A
    result with a JSON form (verify's `Partial`, a `SweepResult`), which `--json` prints,
    or the points a sweep task answered in part, which the sweep merges; readers tell them
    apart with isinstance."""

    def __init__(self, diagnostics: Sequence[Diagnostic],
                 partial: JsonResult | Sequence[object] | None = None):
        super().__init__("; ".join(d.message for d in diagnostics))
        self.diagnostics = list(diagnostics)
        self.partial = partial


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


TAB = "    "


def _shown(text: str) -> str:
    return text.replace("\t", TAB)


def _cells(text: str) -> int:
    """Terminal columns of `text` as shown: a tab is four, a wide (CJK) character two."""
    return sum(2 if unicodedata.east_asian_width(c) in "WF" else 1 for c in _shown(text))


def _excerpt(span: Span, paint: object) -> list[str]:
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


def to_json(diags: Iterable[Diagnostic]) -> str:
    return json.dumps([d.to_json() for d in diags], indent=2)
