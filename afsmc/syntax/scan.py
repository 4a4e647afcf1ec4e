"""A tolerant token scanner: positions of tokens and brackets in text that may not parse.

Not the grammar's lexer (the formatter uses that one): this scanner goes on through text
that does not lex, so the syntax-error diagnosis can look at what precedes an error, and
the resolver can quote a formula as written (flat_text).
"""

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import dataclass, field

from afsmc.diagnostics import BOM

# Each opening bracket: its closer, and the closer's terminal in the grammar.
CLOSERS = {"{": ("}", "RBRACE"), "(": (")", "RPAR"), "[": ("]", "RSQB")}


def tokens(text: str, start: int = 0, end: int | None = None) -> Iterator[tuple[int, int]]:
    """(start, end) of each token of text[start:end], skipping whitespace and comments.
    Only positions and brackets matter to its users: `<=` may come out as two tokens."""
    end = len(text) if end is None else end
    i = start
    while i < end:
        c = text[i]
        if c.isspace() or c == BOM:
            i += 1
            continue
        if text.startswith("//", i):
            j = text.find("\n", i)
            i = end if j < 0 else j
            continue
        if text.startswith("/*", i):
            j = text.find("*/", i + 2)
            i = end if j < 0 else j + 2
            continue
        j = i + 1
        if c == '"':
            j = string_end(text, i, end) + 1
        elif c.isalnum() or c == "_":
            while j < end and (text[j].isalnum() or text[j] == "_"):
                j += 1
        j = min(j, end)
        yield i, j
        i = j


def string_end(text: str, start: int, end: int | None = None) -> int:
    """Where the label name opened by the '"' at `start` closes: the offset of its closing
    '"', or of the newline or end that comes first (a quoted name does not span lines)."""
    end = len(text) if end is None else end
    j = start + 1
    while j < end and text[j] not in '"\n':
        j += 2 if text[j] == "\\" else 1
    return j


def flat_text(text: str, start: int, end: int,
              site: tuple[int, int] | None = None) -> tuple[str, tuple[int, int] | None]:
    """text[start:end] on one line as written, comments dropped and each gap between tokens
    one space; and where the region `site` (source offsets) ends up in it."""
    out = ""
    prev = None
    at: list[int] = []
    for i, j in tokens(text, start, end):
        if site is not None and not at and i >= site[0]:
            at.append(len(out))
        if site is not None and len(at) == 1 and i >= site[1]:
            at.append(len(out))
        if prev is not None and prev < i:
            out += " "
        out += text[i:j]
        prev = j
    if site is not None:
        at += [len(out)] * (2 - len(at))
        return out, (at[0], at[1])
    return out, None


@dataclass
class Scan:
    """What precedes an offset: the end of the last token, the brackets still open
    (innermost last) and the first token of every line."""

    last_end: int = 0
    open: list[tuple[str, int]] = field(default_factory=list)
    line_heads: dict[int, tuple[int, str]] = field(default_factory=dict)  # line -> (offset, text)


def scan(text: str, upto: int) -> Scan:
    """The Scan of text[:upto]. (lark's lexer state at a syntax error holds only the token
    that failed, not the ones before it.)"""
    out = Scan()
    line, counted = 1, 0
    for i, j in tokens(text, 0, upto):
        newlines = text.count("\n", counted, i)
        line, counted = line + newlines, i
        if newlines or not out.line_heads:
            out.line_heads.setdefault(line, (i, text[i:j]))
        c = text[i]
        if c in CLOSERS:
            out.open.append((c, i))
        elif out.open and c == CLOSERS[out.open[-1][0]][0]:
            out.open.pop()
        out.last_end = j
    return out
