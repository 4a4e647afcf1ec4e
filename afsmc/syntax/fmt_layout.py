"""The layout half of `afsmc fmt`: comments, blank lines and columns.

afsmc.syntax.fmt prints the AST as units (a declaration, a block's header or '}', one
statement of a body). Here the comments, which the AST does not hold, are placed back
among those units by position; then blank lines are kept, columns aligned and the lines
rendered.
"""

from __future__ import annotations

import bisect
from dataclasses import dataclass, field
from functools import cached_property

import lark

from afsmc.diagnostics import line_starts

INDENT = "    "


@dataclass
class Unit:
    """Source text [start, end) printed as `lines` (indentation included)."""

    start: int
    end: int
    depth: int
    lines: list[str]
    kind: str = "item"  # "open" (a block header ending in '{'), "close" ('}'), "item"
    leading: list[tuple[lark.Token, bool]] = field(default_factory=list)  # (comment, blank before)
    trailing: list[lark.Token] = field(default_factory=list)
    blank: bool = False
    cols: list[str] | None = None  # a one-line declaration in columns, aligned with neighbours
    group: str = ""  # which declarations align together
    cont: list[lark.Token] = field(default_factory=list)  # lines continuing `trailing`


@dataclass
class Line:
    """One output line: its code, and a trailing comment to be put in a column."""

    code: str
    comment: str | None = None
    blank: bool = False  # a blank line before this one
    is_comment: bool = False
    cont: bool = False  # continues the trailing comment of the line above, in its column
    col: int = 0

    @property
    def indent(self) -> int:
        return len(self.code) - len(self.code.lstrip(" "))


def lay_out(text: str, toks: list[lark.Token], units: list[Unit]) -> str:
    """The file's text from its printed `units`, with the comments among `toks` placed
    back and the blank lines of `text` kept (at most one in a row)."""
    return _Layout(text, toks).run(units)


class _Layout:
    """Where comments and blank lines go, from their positions in the original text."""

    def __init__(self, text: str, toks: list[lark.Token]):
        self.text = text
        self.toks = toks
        self.ends = sorted(t.end_pos or 0 for t in toks)

    def _blank_before(self, offset: int) -> bool:
        i = bisect.bisect_right(self.ends, offset) - 1
        prev = self.ends[i] if i >= 0 else None
        return prev is not None and self.text.count("\n", prev, offset) >= 2

    def _continues(self, u: Unit, c: lark.Token) -> bool:
        """A `//` comment right under the trailing `//` comment of `u`, in its column, goes on
        with it (a trailing comment too long for one line)."""
        if not u.trailing or not str(c).startswith("//"):
            return False
        first, last = u.trailing[-1], (u.cont or u.trailing)[-1]
        pos, at = c.start_pos or 0, first.start_pos or 0
        return (str(first).startswith("//")
                and self._line(pos) == self._line(last.start_pos or 0) + 1
                and self._column(pos) == self._column(at))

    def _column(self, offset: int) -> int:
        return offset - (self.text.rfind("\n", 0, offset) + 1)

    def _line(self, offset: int) -> int:
        # by bisection, so that placing every comment stays O(n log n) in the file's length
        return bisect.bisect_right(self._starts, offset) - 1

    @cached_property
    def _starts(self) -> list[int]:
        return line_starts(self.text)

    def run(self, units: list[Unit]) -> str:
        for u in units:
            u.blank = self._blank_before(u.start)
        tail = self._place_comments(units)
        _align_columns(units)
        lines: list[Line] = []
        for i, u in enumerate(units):
            # no blank line just after a '{', nor just before a '}'
            allow = not (i > 0 and units[i - 1].kind == "open")
            depth = u.depth + 1 if u.kind == "close" else u.depth
            blank = u.blank
            for c, cblank in sorted(u.leading, key=lambda x: x[0].start_pos or 0):
                if (c.start_pos or 0) >= u.start:  # a hoisted comment takes the unit's blank
                    cblank, blank = blank, False
                self._comment(lines, c, depth, cblank and allow)
                allow = True
            first = len(lines)
            lines.extend(Line(text) for text in u.lines)
            lines[first].blank = blank and allow and u.kind != "close"
            if u.trailing:
                lines[-1].comment = " ".join(str(t).rstrip() for t in u.trailing)
            lines.extend(Line("", str(c).rstrip(), cont=True) for c in u.cont)
        for c, cblank in tail:
            self._comment(lines, c, 0, cblank)
        if lines:
            lines[0].blank = False
        return _render(lines)

    def _place_comments(self, units: list[Unit]) -> list[tuple[lark.Token, bool]]:
        """Attach each comment to a unit: inside a statement (moved before it), at the end
        of its last line, continuing such a comment, or before the next unit. The comments
        after the last unit are returned, each with whether a blank line precedes it."""
        tail: list[tuple[lark.Token, bool]] = []
        starts = [u.start for u in units]
        for c in (t for t in self.toks if t.type == "COMMENT"):
            pos = c.start_pos or 0
            k = bisect.bisect_right(starts, pos) - 1  # the last unit starting before c
            if k >= 0 and pos < units[k].end:
                units[k].leading.append((c, False))  # inside a statement: move it before
            elif k >= 0 and self._line(pos) == self._line(units[k].end):
                units[k].trailing.append(c)
            elif k >= 0 and self._continues(units[k], c):
                units[k].cont.append(c)
            elif k + 1 < len(units):
                units[k + 1].leading.append((c, self._blank_before(pos)))
            else:
                tail.append((c, self._blank_before(pos)))
        return tail

    def _comment(self, lines: list[Line], c: lark.Token, depth: int, blank: bool) -> None:
        text = str(c).rstrip().split("\n")
        lines.append(Line(INDENT * depth + text[0], blank=blank and bool(lines), is_comment=True))
        for rest in text[1:]:  # inside a block comment: kept as written
            lines.append(Line(rest.rstrip(), is_comment=True))


def _align_columns(units: list[Unit]) -> None:
    """Neighbouring declarations of one kind (no blank line or comment line between them)
    line up their columns: `const int T_MOVE = [5, 6]   from sim ...`."""
    i = 0
    while i < len(units):
        j = i + 1
        if units[i].cols is not None:
            while (j < len(units) and units[j].cols is not None and units[j].group == units[i].group
                   and not units[j].blank and not units[j].leading):
                j += 1
            run = [u.cols for u in units[i:j] if u.cols is not None]
            for c in range(max(len(cols) for cols in run) - 1):
                width = max((len(cols[c]) for cols in run if len(cols) > c + 1), default=0)
                for cols in run:
                    if len(cols) > c + 1:
                        cols[c] = cols[c].ljust(width)
            for u in units[i:j]:
                u.lines = [" ".join(u.cols or [])]
        i = j


def _render(lines: list[Line]) -> str:
    # Trailing comments of neighbouring lines (same indentation, no blank line or comment line
    # between) start in one column.
    main = [ln for ln in lines if not ln.cont]
    i = 0
    while i < len(main):
        j = i + 1
        while (j < len(main) and not main[j].blank and not main[j].is_comment
               and not main[i].is_comment and main[j].indent == main[i].indent):
            j += 1
        group = [ln for ln in main[i:j] if ln.comment is not None]
        col = max((len(ln.code) for ln in group), default=0) + 2
        for ln in group:
            ln.col = col
        i = j
    out = []
    col = 0
    for ln in lines:
        if ln.blank:
            out.append("")
        if ln.cont:
            out.append(" " * col + (ln.comment or ""))
        elif ln.comment is not None:
            col = ln.col
            out.append(ln.code.ljust(col) + ln.comment)
        else:
            out.append(ln.code.rstrip())
    return "\n".join(out) + "\n" if out else ""
