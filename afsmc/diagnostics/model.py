"""The data of a diagnostic: the source it quotes, its span, its severity, and the
diagnostic itself (a code, a severity, a message, a span, an optional hint and related
places), with its JSON form both ways."""

from __future__ import annotations

import bisect
import re
from collections.abc import Mapping
from dataclasses import dataclass
from enum import StrEnum
from functools import cached_property
from typing import Any


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

    def line(self, lineno: int, lo: int = 0, hi: int | None = None) -> str:
        """The text of line `lineno` (1-based), without its ending (and the byte-order mark
        on line 1); only its columns lo..hi-1 (0-based) if given, so that quoting a place
        in a long line does not copy the whole line."""
        base, end = self._line_bounds(lineno)
        return self.text[base + lo:end if hi is None else min(end, base + hi)]

    def line_length(self, lineno: int) -> int:
        """The length of `line(lineno)`."""
        base, end = self._line_bounds(lineno)
        return end - base

    def _line_bounds(self, lineno: int) -> tuple[int, int]:
        starts = self._starts
        if not 1 <= lineno <= len(starts):
            return 0, 0
        base = starts[lineno - 1]
        end = starts[lineno] - 1 if lineno < len(starts) else len(self.text)
        if end > base and self.text[end - 1] == "\r":
            end -= 1
        if lineno == 1 and end > base and self.text.startswith(BOM):
            base += 1
        return base, end

    def position(self, offset: int) -> tuple[int, int]:
        """1-based (line, column) of a 0-based character offset."""
        offset = max(0, min(offset, len(self.text)))
        line = bisect.bisect_right(self._starts, offset)
        col = offset - self._starts[line - 1] + 1
        if line == 1 and offset > 0 and self.text.startswith(BOM):
            col -= 1
        return line, col

    def offset(self, line: int, column: int) -> int:
        """The 0-based offset of a 1-based (line, column), the inverse of `position`: on
        the first line of a file with a byte-order mark, column 1 is the character after
        the mark."""
        starts = self._starts
        line = max(1, min(line, len(starts)))
        at = starts[line - 1] + column - 1
        if line == 1 and self.text.startswith(BOM):
            at += 1
        return max(0, min(at, len(self.text)))


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

    @staticmethod
    def at_position(source: Source, line: int, column: int,
                    end_line: int | None = None, end_column: int | None = None) -> Span:
        """The span between two 1-based positions (a point when no end is given), its
        offsets computed from the source's text. (1, 1)-(1, 1) is the whole file, and an
        empty span at the end of the text is the one character past it that `at_offset`
        makes there."""
        end_line = line if end_line is None else end_line
        end_column = column if end_column is None else end_column
        if (line, column, end_line, end_column) == (1, 1, 1, 1):
            return Span.whole_file(source)
        start, end = source.offset(line, column), source.offset(end_line, end_column)
        if start == end == len(source.text):
            end += 1
        return Span(source, line, column, end_line, end_column, start, end)

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

    @staticmethod
    def from_json(obj: Mapping[str, Any], sources: Mapping[str, Source] | None = None
                  ) -> Diagnostic:
        """The diagnostic `to_json` wrote. `sources` gives the text of each file named, by
        path, for the offsets of the spans (a file not given reads as empty text). The JSON
        form of a related place has no end: its span is the point where it starts."""
        sources = sources or {}

        def source(path: str) -> Source:
            return sources.get(path) or Source(path, "")

        span = None
        if "file" in obj:
            span = Span.at_position(source(obj["file"]), obj["line"], obj["column"],
                                    obj["end_line"], obj["end_column"])
        related = tuple(
            Related(r["message"], Span.at_position(source(r["file"]), r["line"], r["column"]))
            for r in obj.get("related", ()))
        return Diagnostic(obj["code"], Severity(obj["severity"]), obj["message"], span,
                          obj.get("hint"), related)
