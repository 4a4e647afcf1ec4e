"""Positions: LSP's lines and characters against afsmc's offsets, and the offsets of the last
text that parsed against the editor's text."""

from __future__ import annotations

import bisect
import difflib
import functools
import re
from collections.abc import Sequence

from lsprotocol import types as T
from pygls.workspace import ServerTextPosition, TextDocument
from pygls.workspace.position_codec import UnitCounter, Utf8, Utf16, Utf32

from afsmc.diagnostics import split_lines
from afsmc.lsp import index as I
from afsmc.lsp.state import AfsmServer

_EOL = re.compile(r"\r\n|\r|\n")


class Doc(TextDocument):
    """A document whose lines end at '\r\n', '\r' or '\n', as LSP counts them. pygls's own
    splits at form feeds and U+2028 too (which puts diagnostics lines too low), fails on an
    empty document, walks every line for each position, and puts the end of a last line
    without a newline on a line that does not exist. (`afsmc check` reads '\r' as a line end
    too.) The line index is built once per document: pygls converts every position to the
    client's units through `lines`, and 100,000 diagnostics of a 2 MB document each rebuilt
    the list of its lines."""

    @functools.cached_property
    def _eols(self) -> list[tuple[int, int]]:
        return [(m.start(), m.end()) for m in _EOL.finditer(self.source)]

    @functools.cached_property
    def _starts(self) -> list[int]:
        return [0, *(end for _, end in self._eols)]

    @functools.cached_property
    def lines(self) -> Sequence[str]:
        s, starts = self.source, self._starts
        return tuple(s[a:b] for a, b in zip(starts, [*starts[1:], len(s)], strict=True))

    def server_position_at_offset(self, offset: int) -> ServerTextPosition:
        offset = min(max(offset, 0), len(self.source))
        line = bisect.bisect_right(self._starts, offset) - 1
        return ServerTextPosition(line, offset - self._starts[line])

    def position_to_client_units(self, position: ServerTextPosition | T.Position) -> T.Position:
        """As pygls's, counting the client's code units of the line's prefix at C speed:
        pygls adds them up one character at a time in Python (10 s for the 720,000
        positions of a 2 MB document's outline)."""
        lines = self.lines
        if position.line >= len(lines):
            return T.Position(line=len(lines), character=0)  # as pygls answers
        prefix = lines[position.line][:position.character]
        return T.Position(line=position.line, character=_units(prefix, self.position_codec.impl))

    def offset_at_server_position(self, server_position: ServerTextPosition) -> int:
        line = min(max(server_position.line, 0), len(self._starts) - 1)
        end = self._eols[line][0] if line < len(self._eols) else len(self.source)
        return min(self._starts[line] + max(server_position.character, 0), end)


def _units(text: str, counter: UnitCounter) -> int:
    """The code units of `text` in the client's encoding (LSP's UTF-16 by default)."""
    if text.isascii() or isinstance(counter, Utf32):
        return len(text)
    if isinstance(counter, Utf16):
        return len(text.encode("utf-16-le", "surrogatepass")) // 2
    if isinstance(counter, Utf8):
        return len(text.encode("utf-8", "surrogatepass"))
    return int(counter.num_units(text))


class Shift:
    """Offsets between the last text that parsed (`old`) and the editor's text (`new`), by
    the runs of lines the two share: navigation from the last good parse answers about the
    text the editor shows, and nothing about lines changed since (a position there maps to
    None)."""

    def __init__(self, old: str, new: str) -> None:
        self.same = old == new
        self.runs: list[tuple[int, int, int]] = []  # (old start, new start, length)
        if self.same:
            return
        a, b = split_lines(old), split_lines(new)
        oa, ob = [0], [0]
        for line in a:
            oa.append(oa[-1] + len(line))
        for line in b:
            ob.append(ob[-1] + len(line))
        matcher = difflib.SequenceMatcher(None, a, b, autojunk=False)
        for i, j, n in matcher.get_matching_blocks():
            if n:
                self.runs.append((oa[i], ob[j], oa[i + n] - oa[i]))

    def _map(self, off: int, end: bool, src: int, dst: int) -> int | None:
        if self.same:
            return off
        for run in self.runs:
            start, length = run[src], run[2]
            if start <= off < start + length or (end and start < off <= start + length):
                return run[dst] + off - start
        return None

    def to_old(self, off: int) -> int | None:
        return self._map(off, False, 1, 0)

    def to_new(self, start: int, end: int) -> tuple[int, int] | None:
        a, b = self._map(start, False, 0, 1), self._map(end, True, 0, 1)
        if a is None or b is None or b - a != end - start:
            return None  # the span runs into lines changed since
        return a, b


def shift_of(ls: AfsmServer, uri: str, idx: I.Index) -> tuple[Shift, Doc]:
    """The mapping from the index's text to the editor's, and the editor's text."""
    doc = current(ls, uri)
    return Shift(idx.text, doc.source), doc


def snapshot(ls: AfsmServer, uri: str, text: str) -> Doc:
    """`text` as a document of `uri`, with afsmc's positions."""
    return Doc(uri, text, position_codec=ls.workspace.position_codec)


def current(ls: AfsmServer, uri: str) -> Doc:
    """The editor's current text, with afsmc's positions."""
    return indexed(ls, uri, ls.workspace.get_text_document(uri).source)


def indexed(ls: AfsmServer, uri: str, text: str, keep: bool = True) -> Doc:
    """`text` of `uri` with afsmc's positions, one line index per version of the document:
    the one kept for it if `text` is that version's text (the line starts of a 2 MB text
    take a tenth of a second to find), else a new one, kept if `keep` (off the event loop,
    the index is made with `keep=False` and kept by the loop with `keep_index`)."""
    st = ls.docs.get(uri)
    if st is not None and isinstance(st.current, Doc) and st.current.source is text:
        return st.current
    doc = snapshot(ls, uri, text)
    if keep:
        keep_index(ls, uri, doc)
    return doc


def keep_index(ls: AfsmServer, uri: str, doc: Doc) -> None:
    """Keep `doc`'s line index for its text while that text is the document's."""
    st = ls.docs.get(uri)
    if st is not None and doc.source is st.text:
        st.current = doc


def to_range(doc: TextDocument, start: int, end: int) -> T.Range:
    """The LSP range of the offsets [start, end) of `doc`."""
    return T.Range(start=doc.client_position_at_offset(start),
                   end=doc.client_position_at_offset(end))


def new_range(shift: Shift, doc: Doc, start: int, end: int) -> T.Range | None:
    """The editor's range of offsets [start, end) of the last good parse; None if the span
    runs into lines changed since that parse."""
    at = shift.to_new(start, end)
    return None if at is None else to_range(doc, *at)
