"""The smaller features: folding ranges (declarations and comment runs), workspace symbols
across the open documents (at most MAX_SYMBOLS), inlay hints (a constant's value or interval after each use, a
weight's expression after `w(A)`), signature help for the built-in functions, and range
formatting (the lines of `afsmc fmt`'s changes that meet the range; a big document is
formatted in a child process)."""

from __future__ import annotations

import difflib
import re

from lsprotocol import types as T
from pygls.uris import to_fs_path

from afsmc.diagnostics import CompileError
from afsmc.lsp import index as I
from afsmc.lsp.documents import SMALL
from afsmc.lsp.navigation import _SYMBOL_KINDS, MAX_SYMBOLS
from afsmc.lsp.positions import current, new_range, shift_of, to_range
from afsmc.lsp.state import AfsmServer, guarded
from afsmc.lsp.worker import call, in_thread
from afsmc.model.pretty import number
from afsmc.syntax.fmt import format_text, line_ending

_COMMENT_LINE = re.compile(r"[ \t]*//")
_BLOCK_COMMENT = re.compile(r"/\*[\s\S]*?\*/")


@guarded
async def folding_ranges(ls: AfsmServer, params: T.FoldingRangeParams) -> list[T.FoldingRange]:
    """The folds, found off the event loop (a 2 MB document's: about a second)."""
    return list(await in_thread(_folding_ranges, ls, params))


def _folding_ranges(ls: AfsmServer, params: T.FoldingRangeParams) -> list[T.FoldingRange]:
    uri = params.text_document.uri
    doc = current(ls, uri)
    out: list[T.FoldingRange] = []
    lines = doc.source.splitlines()
    run = -1
    for i, line in enumerate([*lines, ""]):
        if _COMMENT_LINE.match(line):
            run = i if run < 0 else run
            continue
        if run >= 0 and i - 1 > run:
            out.append(T.FoldingRange(start_line=run, end_line=i - 1,
                                      kind=T.FoldingRangeKind.Comment))
        run = -1
    for m in _BLOCK_COMMENT.finditer(doc.source):
        a, b = doc.source.count("\n", 0, m.start()), doc.source.count("\n", 0, m.end())
        if b > a:
            out.append(T.FoldingRange(start_line=a, end_line=b, kind=T.FoldingRangeKind.Comment))
    st = ls.docs.get(uri)
    if st is not None and st.index is not None:
        shift, doc = shift_of(ls, uri, st.index)
        for decl in st.index.module.decls:
            r = new_range(shift, doc, decl.span.start, decl.span.end)
            if r is not None and r.end.line > r.start.line:
                out.append(T.FoldingRange(start_line=r.start.line, end_line=r.end.line,
                                          kind=T.FoldingRangeKind.Region))
    return sorted(out, key=lambda f: (f.start_line, f.end_line))


@guarded
async def workspace_symbols(ls: AfsmServer, params: T.WorkspaceSymbolParams
                            ) -> list[T.WorkspaceSymbol]:
    """The declarations whose names hold the query, in the open documents, found off the
    event loop: at most MAX_SYMBOLS (an editor asks again as the query grows; an empty
    query in a big document would be every name, a reply of megabytes)."""
    return list(await in_thread(_workspace_symbols, ls, params))


def _workspace_symbols(ls: AfsmServer, params: T.WorkspaceSymbolParams
                       ) -> list[T.WorkspaceSymbol]:
    query = params.query.lower()
    out: list[T.WorkspaceSymbol] = []
    for uri, st in sorted(ls.docs.items()):
        if st.index is None:
            continue
        shift, doc = shift_of(ls, uri, st.index)
        for d in st.index.defs.values():
            if query and query not in d.name.lower():
                continue
            if len(out) == MAX_SYMBOLS:
                return out
            r = new_range(shift, doc, d.ident.start, d.ident.end)
            if r is not None:
                out.append(T.WorkspaceSymbol(
                    name=d.name, kind=_SYMBOL_KINDS[d.kind], container_name=d.kind,
                    location=T.Location(uri=uri, range=r)))
    return out


_W_BEFORE = re.compile(r"\bw\s*\(\s*\Z")
_W_AFTER = re.compile(r"\s*\)")


def _hint_text(idx: I.Index, occ: I.Occurrence, model_ok: bool, st_model: object
               ) -> tuple[int, str] | None:
    """Where the hint goes (an offset of the index's text) and what it says."""
    d = idx.definition(occ)
    if d is None or occ.is_def:
        return None
    if d.kind == "constant" and model_ok:
        try:
            c = st_model.constant(d.name)  # type: ignore[attr-defined]
        except StopIteration:
            return None
        if c.interval is not None and c.interval[0] != c.interval[1]:
            return occ.end, f" ∈ [{number(c.interval[0])}, {number(c.interval[1])}]"
        return occ.end, f" = {number(c.value)}"
    if d.kind in ("action", "hazard") and _W_BEFORE.search(idx.text, 0, occ.start) \
            and (m := _W_AFTER.match(idx.text, occ.end)):
        weight = getattr(d.decl, "weight", None) or getattr(d.decl, "trigger", None)
        if weight is None:
            return None
        return m.end(), " = " + idx.text[weight.span.start:weight.span.end]
    return None


@guarded
def inlay_hints(ls: AfsmServer, params: T.InlayHintParams) -> list[T.InlayHint]:
    uri = params.text_document.uri
    st = ls.docs.get(uri)
    if st is None or st.index is None:
        return []
    idx = st.index
    shift, doc = shift_of(ls, uri, idx)
    lo = doc.offset_at_position(params.range.start)
    hi = doc.offset_at_position(params.range.end)
    out = []
    for occ in idx.occurrences:
        found = _hint_text(idx, occ, shift.same and st.model is not None, st.model)
        if found is None:
            continue
        at = shift.to_new(found[0], found[0])
        if at is None or not lo <= at[0] <= hi:
            continue
        out.append(T.InlayHint(position=doc.client_position_at_offset(at[0]), label=found[1],
                               kind=T.InlayHintKind.Type, padding_left=False))
    return out


SIGNATURES = {
    "min": ("min(a, b, ...)", ["a", "b", "..."], "the smallest of its arguments"),
    "max": ("max(a, b, ...)", ["a", "b", "..."], "the largest of its arguments"),
    "floor": ("floor(x)", ["x"], "the largest integer not above x"),
    "ceil": ("ceil(x)", ["x"], "the smallest integer not below x"),
    "pow": ("pow(base, exponent)", ["base", "exponent"], "base raised to exponent"),
    "mod": ("mod(a, b)", ["a", "b"], "the remainder of a divided by b (integers)"),
    "w": ("w(action)", ["action"], "the weight of an action (or a hazard's probability) "
          "of the same mode"),
}


def call_at(text: str, offset: int) -> tuple[str, int] | None:
    """The built-in whose argument list holds `offset`, and the argument's number."""
    depth, commas = 0, 0
    i = offset - 1
    while i >= 0:
        c = text[i]
        if c in ")]":
            depth += 1
        elif c in "([":
            if depth == 0:
                if c == "[":
                    return None
                m = re.search(r"([A-Za-z_]\w*)\s*\Z", text[max(0, i - 40):i])
                if m is None or m[1] not in SIGNATURES:
                    return None
                return m[1], commas
            depth -= 1
        elif c == "," and depth == 0:
            commas += 1
        elif c in ";{}":
            return None
        i -= 1
    return None


@guarded
def signature_help(ls: AfsmServer, params: T.SignatureHelpParams) -> T.SignatureHelp | None:
    doc = current(ls, params.text_document.uri)
    found = call_at(doc.source, doc.offset_at_position(params.position))
    if found is None:
        return None
    name, arg = found
    label, args, what = SIGNATURES[name]
    sig = T.SignatureInformation(label=label, documentation=what,
                                 parameters=[T.ParameterInformation(label=a) for a in args])
    return T.SignatureHelp(signatures=[sig], active_signature=0,
                           active_parameter=min(arg, len(args) - 1))


@guarded
async def range_formatting(ls: AfsmServer, params: T.DocumentRangeFormattingParams
                           ) -> list[T.TextEdit] | None:
    """`afsmc fmt`'s changes to the lines that meet the range, and none elsewhere."""
    uri = params.text_document.uri
    doc = current(ls, uri)
    text = doc.source.replace("\r\n", "\n").replace("\r", "\n")
    try:
        out = await call(format_text, text, to_fs_path(uri) or uri, process=len(text) > SMALL)
    except CompileError:
        return None
    old, new = text.splitlines(keepends=True), out.splitlines(keepends=True)
    starts = [0]
    for line in old:
        starts.append(starts[-1] + len(line))
    first, last = params.range.start.line, params.range.end.line
    if params.range.end.character == 0 and last > first:
        last -= 1
    eol = line_ending(doc.source)
    edits = []
    src = doc.source
    for tag, i1, i2, j1, j2 in difflib.SequenceMatcher(None, old, new, autojunk=False).get_opcodes():
        touches = first <= i1 <= last + 1 if i1 == i2 else i1 <= last and i2 - 1 >= first
        if tag == "equal" or not touches:
            continue
        a, b = _offset(src, starts[i1], text), _offset(src, starts[i2], text)
        edits.append(T.TextEdit(range=to_range(doc, a, b),
                                new_text="".join(new[j1:j2]).replace("\n", eol)))
    return edits


def _offset(src: str, off: int, text: str) -> int:
    """`off` of the text with '\n' line ends, as an offset of the document's own text."""
    if src == text:
        return off
    return off + text.count("\n", 0, off) * (len(src) - len(text)) // max(1, text.count("\n"))

