"""Document sync: every change is parsed and resolved at once and its syntax and name errors
published; the semantic checks run in a worker thread once typing pauses (DEBOUNCE), exactly
as `afsmc check` runs them, and replace the diagnostics when they finish if the text has not
changed meanwhile."""

from __future__ import annotations

import asyncio
import time
import traceback

from lsprotocol import types as T
from pygls.uris import to_fs_path
from pygls.workspace import TextDocument

from afsmc.diagnostics import Diagnostic, Severity, codes
from afsmc.lsp import index as I
from afsmc.lsp.analysis import Fast, analyse_fast, analyse_full
from afsmc.lsp.positions import snapshot, to_range
from afsmc.lsp.state import AfsmServer, DocState, guarded

DEBOUNCE = 0.3  # seconds of quiet before the full checks run, when they are slow
FAST_CHECK = 0.1  # a full check this quick runs at once (after a 20 ms yield)


def _to_lsp(d: Diagnostic, doc: TextDocument, uri: str) -> T.Diagnostic:
    rng = to_range(doc, d.span.start, d.span.end) if d.span is not None else to_range(doc, 0, 0)
    message = d.message + (f"\nhint: {d.hint}" if d.hint else "")
    related = [T.DiagnosticRelatedInformation(
        location=T.Location(uri=uri, range=to_range(doc, r.span.start, r.span.end)),
        message=r.message)
               for r in d.related]
    severity = {Severity.ERROR: T.DiagnosticSeverity.Error,
                Severity.WARNING: T.DiagnosticSeverity.Warning,
                Severity.NOTE: T.DiagnosticSeverity.Information}[d.severity]
    return T.Diagnostic(range=rng, message=message, severity=severity, code=d.code, source="afsmc",
                        related_information=related or None)


def _publish(ls: AfsmServer, uri: str, version: int | None, text: str,
             diags: list[Diagnostic]) -> None:
    doc = snapshot(ls, uri, text)
    ls.text_document_publish_diagnostics(T.PublishDiagnosticsParams(
        uri=uri, diagnostics=[_to_lsp(d, doc, uri) for d in diags], version=version))


def _internal_diag(what: str) -> Diagnostic:
    return Diagnostic(codes.E999, Severity.ERROR, f"afsmc could not {what} this file (an internal "
                      "error; see the language server's log)", None)


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


@guarded
async def did_open(ls: AfsmServer, params: T.DidOpenTextDocumentParams) -> None:
    _changed(ls, params.text_document.uri)


@guarded
async def did_change(ls: AfsmServer, params: T.DidChangeTextDocumentParams) -> None:
    _changed(ls, params.text_document.uri)


@guarded
async def did_close(ls: AfsmServer, params: T.DidCloseTextDocumentParams) -> None:
    st = ls.docs.pop(params.text_document.uri, None)
    if st is not None and st.task is not None:
        st.task.cancel()
    ls.text_document_publish_diagnostics(T.PublishDiagnosticsParams(uri=params.text_document.uri, diagnostics=[]))

