"""`afsmc lsp`: a Language Server Protocol server (pygls 2) for .afsm files.

It reuses the compiler: the parser and the resolver run on every change (a few tens of
milliseconds on examples/uav.afsm), so syntax and name errors appear as the author types
and navigation follows the text. The semantic checks (weights, distributions, ranges, the
mode graph: about a second and a half on uav.afsm, they enumerate states) run in a worker
thread once typing pauses (DEBOUNCE), exactly as `afsmc check` runs them, and replace the
diagnostics when they finish if the text has not changed meanwhile.

A file that does not parse keeps the navigation of its last good parse, mapped to the
editor's text through the lines both share (_Shift); completion in a file that has never
parsed uses the text with its broken part left out (I.recover);
nothing a client sends makes the server exit (every handler turns a failure into a log
message).
"""

from __future__ import annotations

import asyncio
import bisect
import difflib
import functools
import logging
import re
import time
import traceback
import types
from collections import Counter
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import Any, TypeVar

from lsprotocol import types as T
from pygls.exceptions import JsonRpcException
from pygls.lsp.server import LanguageServer
from pygls.protocol import LanguageServerProtocol
from pygls.uris import to_fs_path
from pygls.workspace import ServerTextPosition, TextDocument

from afsmc import __version__
from afsmc.compiler import load
from afsmc.diagnostics import CompileError, Diagnostic, Severity, split_lines
from afsmc.lsp import index as I
from afsmc.model import ir
from afsmc.model.expr import FUNCTIONS
from afsmc.model.names import AFSM_KEYWORDS
from afsmc.resolve import resolve
from afsmc.syntax import ast
from afsmc.syntax.fmt import format_text, line_ending
from afsmc.syntax.parser import parse

DEBOUNCE = 0.3  # seconds of quiet before the full checks run, when they are slow
FAST_CHECK = 0.1  # a full check this quick runs at once (after a 20 ms yield)

F = TypeVar("F", bound=Callable[..., Any])


@dataclass
class DocState:
    version: int | None = None
    text: str = ""
    index: I.Index | None = None  # from the last text that parsed
    model: ir.Model | None = None  # when the current text resolved
    # completion before the first good parse: names from the text with its broken part
    # blanked (I.recover), for the (text, line) it was computed for
    recovered: tuple[str, int, I.Index] | None = None
    task: asyncio.Task[None] | None = None


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


class _Protocol(LanguageServerProtocol):
    """pygls only logs a request whose params do not fit its method (a negative position,
    no params at all), so a client waiting for the answer hung: answer it with the error."""

    def structure_message(self, data: dict[str, Any]) -> Any:
        try:
            return super().structure_message(data)
        except JsonRpcException as exc:
            if not (isinstance(data, dict) and "id" in data and "method" in data):
                raise
            self._send_response(data["id"], error=exc.to_response_error())
            # Answered: handle_message passes over a message of another JSON-RPC version,
            # where an exception would also pop up "Error in server" in the editor.
            return types.SimpleNamespace(jsonrpc="answered")


class AfsmServer(LanguageServer):
    def __init__(self) -> None:
        super().__init__("afsmc", __version__, protocol_cls=_Protocol)

        self.docs: dict[str, DocState] = {}
        self.check_lock = asyncio.Lock()
        self.last_check = 0.0  # seconds the last full check took
        self.shut_down = False  # a `shutdown` request came: `exit` is then 0


server = AfsmServer()


def guarded(fn: F) -> F:
    """A handler that fails logs why and answers nothing, instead of failing the request."""

    @functools.wraps(fn)
    async def wrapper(ls: AfsmServer, params: Any) -> Any:
        try:
            result = fn(ls, params)
            if asyncio.iscoroutine(result):
                result = await result
            return result
        except Exception:
            ls.window_log_message(T.LogMessageParams(
                type=T.MessageType.Error, message=f"afsmc: internal error in {fn.__name__}:\n"
                + traceback.format_exc()))
            return None

    return wrapper  # type: ignore[return-value]


# ---- positions -------------------------------------------------------------------


_EOL = re.compile(r"\r\n|\r|\n")


class _Doc(TextDocument):
    """A document whose lines end at '\r\n', '\r' or '\n', as LSP counts them: pygls
    splits at form feeds and U+2028 too (diagnostics landed lines too low), failed on an
    empty document, walked every line for each position, and put the end of a last line
    without a newline on a line that does not exist. (`afsmc check` reads '\r' as a line end
    too.)"""

    @functools.cached_property
    def _eols(self) -> list[tuple[int, int]]:
        return [(m.start(), m.end()) for m in _EOL.finditer(self.source)]

    @functools.cached_property
    def _starts(self) -> list[int]:
        return [0, *(end for _, end in self._eols)]

    @property
    def lines(self) -> Sequence[str]:
        s, starts = self.source, self._starts
        return tuple(s[a:b] for a, b in zip(starts, [*starts[1:], len(s)], strict=True))

    def server_position_at_offset(self, offset: int) -> ServerTextPosition:
        offset = min(max(offset, 0), len(self.source))
        line = bisect.bisect_right(self._starts, offset) - 1
        return ServerTextPosition(line, offset - self._starts[line])

    def offset_at_server_position(self, server_position: ServerTextPosition) -> int:
        line = min(max(server_position.line, 0), len(self._starts) - 1)
        end = self._eols[line][0] if line < len(self._eols) else len(self.source)
        return min(self._starts[line] + max(server_position.character, 0), end)


class _Shift:
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


def _shift(ls: AfsmServer, uri: str, idx: I.Index) -> tuple[_Shift, _Doc]:
    doc = _current(ls, uri)
    return _Shift(idx.text, doc.source), doc


def _snapshot(ls: AfsmServer, uri: str, text: str) -> _Doc:
    return _Doc(uri, text, position_codec=ls.workspace.position_codec)


def _current(ls: AfsmServer, uri: str) -> _Doc:
    """The editor's current text, with afsmc's positions."""
    return _snapshot(ls, uri, ls.workspace.get_text_document(uri).source)


def _range(doc: TextDocument, start: int, end: int) -> T.Range:
    return T.Range(start=doc.client_position_at_offset(start),
                   end=doc.client_position_at_offset(end))


def _to_lsp(d: Diagnostic, doc: TextDocument, uri: str) -> T.Diagnostic:
    rng = _range(doc, d.span.start, d.span.end) if d.span is not None else _range(doc, 0, 0)
    message = d.message + (f"\nhint: {d.hint}" if d.hint else "")
    related = [T.DiagnosticRelatedInformation(
        location=T.Location(uri=uri, range=_range(doc, r.span.start, r.span.end)),
        message=r.message)
               for r in d.related]
    severity = {Severity.ERROR: T.DiagnosticSeverity.Error,
                Severity.WARNING: T.DiagnosticSeverity.Warning,
                Severity.NOTE: T.DiagnosticSeverity.Information}[d.severity]
    return T.Diagnostic(range=rng, message=message, severity=severity, code=d.code, source="afsmc",
                        related_information=related or None)


def _publish(ls: AfsmServer, uri: str, version: int | None, text: str,
             diags: list[Diagnostic]) -> None:
    doc = _snapshot(ls, uri, text)
    ls.text_document_publish_diagnostics(T.PublishDiagnosticsParams(
        uri=uri, diagnostics=[_to_lsp(d, doc, uri) for d in diags], version=version))


def _internal_diag(what: str) -> Diagnostic:
    return Diagnostic("E999", Severity.ERROR, f"afsmc could not {what} this file (an internal "
                      "error; see the language server's log)", None)


# ---- document sync -----------------------------------------------------------------


def _changed(ls: AfsmServer, uri: str) -> None:
    doc = ls.workspace.get_text_document(uri)
    st = ls.docs.setdefault(uri, DocState())
    st.version, st.text = doc.version, doc.source
    path = to_fs_path(uri) or uri
    try:
        fast = analyse_fast(st.text, path)
    except Exception:
        ls.window_log_message(T.LogMessageParams(type=T.MessageType.Error, message=traceback.format_exc()))
        fast = Fast(None, None, [_internal_diag("parse")])
    if fast.module is not None:
        st.index = I.build(fast.module, st.text)
        st.recovered = None
    # The facts hover shows (values, ranges) hold for the text that resolved: another text
    # keeps none rather than show a constant's old value beside its new declaration.
    st.model = fast.model
    if st.task is not None:
        st.task.cancel()
        st.task = None
    if fast.diagnostics:  # syntax or name errors: the checks would stop at them too
        _publish(ls, uri, st.version, st.text, fast.diagnostics)
        return
    st.task = asyncio.get_running_loop().create_task(_check_later(ls, uri, st.version, st.text))


async def _check_later(ls: AfsmServer, uri: str, version: int | None, text: str) -> None:
    # Quick checks run while the author types; slow ones wait for a pause.
    await asyncio.sleep(0.02 if ls.last_check < FAST_CHECK else DEBOUNCE)
    async with ls.check_lock:  # one check at a time: the machine is shared
        st = ls.docs.get(uri)
        if st is None or st.version != version:
            return
        try:
            started = time.perf_counter()
            diags = await asyncio.to_thread(analyse_full, text, to_fs_path(uri) or uri)
            ls.last_check = time.perf_counter() - started
        except Exception:
            ls.window_log_message(T.LogMessageParams(type=T.MessageType.Error, message=traceback.format_exc()))
            diags = [_internal_diag("check")]
    st = ls.docs.get(uri)
    if st is not None and st.version == version:
        _publish(ls, uri, version, text, diags)


@server.feature(T.TEXT_DOCUMENT_DID_OPEN)
@guarded
async def did_open(ls: AfsmServer, params: T.DidOpenTextDocumentParams) -> None:
    _changed(ls, params.text_document.uri)


@server.feature(T.TEXT_DOCUMENT_DID_CHANGE)
@guarded
async def did_change(ls: AfsmServer, params: T.DidChangeTextDocumentParams) -> None:
    _changed(ls, params.text_document.uri)


@server.feature(T.TEXT_DOCUMENT_DID_CLOSE)
@guarded
async def did_close(ls: AfsmServer, params: T.DidCloseTextDocumentParams) -> None:
    st = ls.docs.pop(params.text_document.uri, None)
    if st is not None and st.task is not None:
        st.task.cancel()
    ls.text_document_publish_diagnostics(T.PublishDiagnosticsParams(uri=params.text_document.uri, diagnostics=[]))


# ---- navigation ---------------------------------------------------------------------


def _lookup(ls: AfsmServer, uri: str, pos: T.Position
            ) -> tuple[I.Index, I.Occurrence, _Shift, _Doc] | None:
    """The name at the editor's position, found in the last good parse (through the lines
    both texts share), with the mapping back to the editor's text."""
    st = ls.docs.get(uri)
    if st is None or st.index is None:
        return None
    shift, doc = _shift(ls, uri, st.index)
    offset = shift.to_old(doc.offset_at_position(pos))
    occ = st.index.at(offset) if offset is not None else None
    return (st.index, occ, shift, doc) if occ is not None else None


def _new_range(shift: _Shift, doc: _Doc, start: int, end: int) -> T.Range | None:
    at = shift.to_new(start, end)
    return None if at is None else _range(doc, *at)


@server.feature(T.TEXT_DOCUMENT_HOVER)
@guarded
def hover(ls: AfsmServer, params: T.HoverParams) -> T.Hover | None:
    found = _lookup(ls, params.text_document.uri, params.position)
    if found is None:
        return None
    idx, occ, shift, doc = found
    d = idx.definition(occ)
    if d is None:
        return None
    st = ls.docs[params.text_document.uri]
    text = I.hover(d, idx.text, st.model if shift.same else None)
    return T.Hover(contents=T.MarkupContent(kind=T.MarkupKind.Markdown, value=text),
                   range=_new_range(shift, doc, occ.start, occ.end))


@server.feature(T.TEXT_DOCUMENT_DEFINITION)
@guarded
def definition(ls: AfsmServer, params: T.DefinitionParams) -> T.Location | None:
    uri = params.text_document.uri
    found = _lookup(ls, uri, params.position)
    if found is None:
        return None
    idx, occ, shift, doc = found
    d = idx.definition(occ)
    if d is None:
        return None
    rng = _new_range(shift, doc, d.ident.start, d.ident.end)
    return None if rng is None else T.Location(uri=uri, range=rng)


@server.feature(T.TEXT_DOCUMENT_REFERENCES)
@guarded
def references(ls: AfsmServer, params: T.ReferenceParams) -> list[T.Location] | None:
    uri = params.text_document.uri
    found = _lookup(ls, uri, params.position)
    if found is None:
        return None
    idx, occ, shift, doc = found
    ranges = (_new_range(shift, doc, o.start, o.end)
              for o in idx.references(occ.ns, occ.name, params.context.include_declaration))
    return [T.Location(uri=uri, range=r) for r in ranges if r is not None]


_SYMBOL_KINDS = {
    "constant": T.SymbolKind.Constant, "variable": T.SymbolKind.Variable,
    "mode": T.SymbolKind.EnumMember, "formula": T.SymbolKind.Function,
    "action": T.SymbolKind.Method, "hazard": T.SymbolKind.Event, "label": T.SymbolKind.Boolean,
    "rewards": T.SymbolKind.Struct, "property": T.SymbolKind.Property,
    "field": T.SymbolKind.Field,
}


@server.feature(T.TEXT_DOCUMENT_DOCUMENT_SYMBOL)
@guarded
def document_symbols(ls: AfsmServer, params: T.DocumentSymbolParams) -> list[T.DocumentSymbol]:
    uri = params.text_document.uri
    st = ls.docs.get(uri)
    if st is None or st.index is None:
        return []
    idx = st.index
    shift, doc = _shift(ls, uri, idx)
    by_decl: dict[int, I.Definition] = {
        id(d.decl): d for d in idx.defs.values() if d.kind != "field"}
    out = []
    for decl in idx.module.decls:
        d = by_decl.get(id(decl))
        whole = _new_range(shift, doc, decl.span.start, decl.span.end)
        name = _new_range(shift, doc, d.ident.start, d.ident.end) if d else None
        if d is None or whole is None or name is None:
            continue  # not declared, or edited since the last good parse
        children = [
            T.DocumentSymbol(name=f.name.text, kind=T.SymbolKind.Field, range=r, selection_range=n)
            for f in (decl.type.fields if isinstance(decl, ast.VarDecl)
                      and isinstance(decl.type, ast.TupleType) else ())
            for r, n in [(_new_range(shift, doc, f.span.start, f.span.end),
                          _new_range(shift, doc, f.name.span.start, f.name.span.end))]
            if r is not None and n is not None]
        detail = d.kind
        if isinstance(decl, (ast.ActionDecl, ast.HazardDecl)):
            detail = f"{d.kind} in {idx.text[decl.modes.span.start:decl.modes.span.end]}"
        out.append(T.DocumentSymbol(
            name=d.name, kind=_SYMBOL_KINDS[d.kind], range=whole, selection_range=name,
            detail=detail, children=children or None))
    return out


# ---- completion ---------------------------------------------------------------------

_ITEM_KINDS = {
    "constant": T.CompletionItemKind.Constant, "variable": T.CompletionItemKind.Variable,
    "mode": T.CompletionItemKind.EnumMember, "formula": T.CompletionItemKind.Function,
    "action": T.CompletionItemKind.Method, "hazard": T.CompletionItemKind.Event,
    "label": T.CompletionItemKind.Value, "rewards": T.CompletionItemKind.Struct,
}


def _items(defs: list[I.Definition]) -> list[T.CompletionItem]:
    return [T.CompletionItem(d.name, kind=_ITEM_KINDS.get(d.kind), detail=d.kind) for d in defs]


def completions(idx: I.Index | None, before: str) -> list[T.CompletionItem]:
    """Names that fit where the cursor is; `before` is the line up to the cursor."""
    if idx is None:
        return [T.CompletionItem(k, kind=T.CompletionItemKind.Keyword) for k in I.KEYWORDS]
    if re.search(r'R\{"\w*$', before):
        return _items(idx.names(I.REWARD))
    if before.count('"') % 2 == 1:
        return _items(idx.names(I.LABEL))
    if re.search(r"\bw\(\s*\w*$", before) or re.search(r"^\s*\[\s*\w*$", before):
        return _items(idx.names(I.ACTION))
    if re.search(r"\bgoto\s+\w*$", before) or (re.search(
            r"\b(in|from|except)\s+\{?[\w\s,.]*$", before) and not re.search(r"\bwhen\b", before)):
        return _items(idx.names(I.VALUE, ("mode",)))
    if m := re.search(r"\b(\w+)\.\w*$", before):
        return [T.CompletionItem(d.name.split(".", 1)[1], kind=T.CompletionItemKind.Field)
                for d in idx.names(I.FIELD) if d.name.startswith(m.group(1) + ".")]
    return (_items(idx.names(I.VALUE))
            + [T.CompletionItem(f, kind=T.CompletionItemKind.Function, detail="function")
               for f in (*sorted(FUNCTIONS), "w")]
            + [T.CompletionItem(k, kind=T.CompletionItemKind.Keyword) for k in I.KEYWORDS
               if k not in FUNCTIONS])  # `min`, `max`: once, as the functions they are


@server.feature(T.TEXT_DOCUMENT_COMPLETION, T.CompletionOptions(trigger_characters=['"', "(", "."]))
@guarded
def completion(ls: AfsmServer, params: T.CompletionParams) -> T.CompletionList:
    uri = params.text_document.uri
    doc = _current(ls, uri)
    offset = doc.offset_at_position(params.position)
    line_start = doc.source.rfind("\n", 0, offset) + 1
    st = ls.docs.get(uri)
    idx = st.index if st is not None else None
    if idx is None:  # never parsed: no last good parse to take the names from
        if st is not None and st.recovered is not None \
                and st.recovered[:2] == (doc.source, line_start):
            idx = st.recovered[2]
        else:
            idx = I.recover(doc.source, offset, to_fs_path(uri) or uri)
            if st is not None:
                st.recovered = (doc.source, line_start, idx)
    items = completions(idx, doc.source[line_start:offset])
    return T.CompletionList(is_incomplete=False, items=items)


# ---- editing -------------------------------------------------------------------------


@server.feature(T.TEXT_DOCUMENT_FORMATTING)
@guarded
def formatting(ls: AfsmServer, params: T.DocumentFormattingParams) -> list[T.TextEdit] | None:
    uri = params.text_document.uri
    doc = _current(ls, uri)
    # As `afsmc fmt` does: line endings alone never make a text unformatted, and the
    # formatted text keeps the document's own.
    text = doc.source.replace("\r\n", "\n").replace("\r", "\n")
    try:
        out = format_text(text, to_fs_path(uri) or uri)
    except CompileError:
        return None  # a syntax error: it is already shown as a diagnostic
    if out == text:
        return []
    return [T.TextEdit(range=_range(doc, 0, len(doc.source)),
                       new_text=out.replace("\n", line_ending(doc.source)))]


RENAMEABLE = {"mode", "constant", "variable", "action", "hazard", "formula", "label", "rewards",
              "property"}


def _rename_target(ls: AfsmServer, uri: str, pos: T.Position) -> tuple[I.Index, I.Definition,
                                                                       I.Occurrence] | None:
    st = ls.docs.get(uri)
    doc = ls.workspace.get_text_document(uri)
    if st is None or st.index is None or st.index.text != doc.source:
        return None  # only on text that parses: the spans must be current
    found = _lookup(ls, uri, pos)
    if found is None:
        return None
    idx, occ, _, _ = found
    d = idx.definition(occ)
    if d is None or d.kind not in RENAMEABLE:
        return None
    return idx, d, occ


class RequestFailed(JsonRpcException):
    """A request refused for a reason the user should read (LSP's RequestFailed): the client
    shows the message; no traceback goes with it."""

    CODE = int(T.LSPErrorCodes.RequestFailed)  # -32803


class _QuietRefusals(logging.Filter):
    # pygls logs every error answer with its traceback; a refusal is an answer, not a fault
    def filter(self, record: logging.LogRecord) -> bool:
        return not (record.exc_info and isinstance(record.exc_info[1], RequestFailed))


logging.getLogger("pygls.protocol.json_rpc").addFilter(_QuietRefusals())


def refusing(fn: F) -> F:
    """A handler whose RequestFailed goes to the client; any other failure is logged and
    refused in general terms (never a traceback in the answer)."""

    @functools.wraps(fn)
    def wrapper(ls: AfsmServer, params: Any) -> Any:
        try:
            return fn(ls, params)
        except RequestFailed:
            raise
        except Exception:
            ls.window_log_message(T.LogMessageParams(
                type=T.MessageType.Error, message=f"afsmc: internal error in {fn.__name__}:\n"
                + traceback.format_exc()))
            raise RequestFailed("afsmc could not do this (an internal error; see the language "
                                "server's log)") from None

    return wrapper  # type: ignore[return-value]


def _why_not_renameable(ls: AfsmServer, uri: str, pos: T.Position) -> str | None:
    """Why the name at `pos` cannot be renamed, if there is a name there at all."""
    st = ls.docs.get(uri)
    doc = ls.workspace.get_text_document(uri)
    if st is None or st.index is None:
        return None
    if st.index.text != doc.source:
        return "the file does not parse: fix the syntax error first"
    found = _lookup(ls, uri, pos)
    if found is None:
        return None
    idx, occ, _, _ = found
    d = idx.definition(occ)
    if d is None:
        return f"'{occ.name}' is not declared in this file"
    if d.kind not in RENAMEABLE:
        return "a tuple's fields cannot be renamed" if d.kind == "field" else \
            f"{_article(d.kind)} {d.kind} cannot be renamed"
    return None


def _article(word: str) -> str:
    return "an" if word[0] in "aeiou" else "a"


@server.feature(T.TEXT_DOCUMENT_PREPARE_RENAME)
@refusing
def prepare_rename(ls: AfsmServer, params: T.PrepareRenameParams) -> T.Range | None:
    uri = params.text_document.uri
    target = _rename_target(ls, uri, params.position)
    if target is None:
        why = _why_not_renameable(ls, uri, params.position)
        if why is not None:
            raise RequestFailed(why)
        return None  # not on a name
    idx, _, occ = target
    return _range(_snapshot(ls, uri, idx.text), occ.start, occ.end)


def refusal(idx: I.Index, d: I.Definition, new: str, path: str) -> str | None:
    """Why `d` cannot be renamed to `new`, in words for the user; None if it can."""
    if not I.NAME_RE.match(new) or new in I.KEYWORDS or new in AFSM_KEYWORDS \
            or new in FUNCTIONS or new == "w":
        return f"'{new}' is not a name that can be declared"
    if new == d.name:
        return None
    other = idx.defs.get((d.ns, new))
    if other is not None:
        kind = "reward structure" if other.kind == "rewards" else other.kind
        return f"'{new}' is already declared (as {_article(kind)} {kind})"
    # Whatever else the checker would reject (E202: reserved in PRISM or Storm, names of
    # afsmc's own, ...): resolve the renamed text and look for errors it did not have.
    refs = sorted(idx.references(d.ns, d.name), key=lambda o: o.start)
    renamed, shift, moved = idx.text, 0, []
    for o in refs:
        start = o.start + shift
        renamed = renamed[:start] + new + renamed[o.end + shift:]
        moved.append((start, start + len(new)))
        shift += len(new) - (o.end - o.start)
    before = Counter(x.code for x in analyse_fast(idx.text, path).diagnostics if x.is_error)
    after = [x for x in analyse_fast(renamed, path).diagnostics if x.is_error]
    extra = Counter(x.code for x in after) - before
    fresh = [x for x in after if x.code in extra]
    if not fresh:
        return None
    at_new = [x for x in fresh if x.span is not None
              and any(a <= x.span.start < b for a, b in moved)]
    return (at_new or fresh)[0].message


@server.feature(T.TEXT_DOCUMENT_RENAME)
@refusing
def rename(ls: AfsmServer, params: T.RenameParams) -> T.WorkspaceEdit | None:
    uri = params.text_document.uri
    target = _rename_target(ls, uri, params.position)
    if target is None:
        raise RequestFailed(_why_not_renameable(ls, uri, params.position)
                            or "there is no name to rename here")
    idx, d, _ = target
    why = refusal(idx, d, params.new_name, to_fs_path(uri) or uri)
    if why is not None:
        raise RequestFailed(f"cannot rename {d.kind} '{d.name}' to '{params.new_name}': {why}")
    doc = _snapshot(ls, uri, idx.text)
    edits = [T.TextEdit(range=_range(doc, o.start, o.end), new_text=params.new_name)
             for o in idx.references(d.ns, d.name)]
    return T.WorkspaceEdit(changes={uri: edits})


@server.feature(T.SHUTDOWN)
def _on_shutdown(ls: AfsmServer, params: Any) -> None:
    ls.shut_down = True


def serve() -> int:
    """Serve until `exit`: 0 after a `shutdown` request, 1 without one (as LSP asks; pygls's
    own exit code is lost in its event loop)."""
    server.start_io()
    return 0 if server.shut_down else 1
