"""Document sync: every change is parsed and resolved at once, off the event loop, and its
syntax and name errors published (or their absence, once fixed); the semantic checks then run
in a child process, at once when they are quick and after a pause in typing (DEBOUNCE) when
they are slow, exactly as `afsmc check` runs them, and replace the diagnostics. A newer
version of a document cancels the work on the older one; each document has its own.

At most MAX_SHOWN diagnostics of a document are published (errors first), with one more,
N901, that says how many are left out: a 2 MB file of unused constants has 90,000
warnings, which no editor lists usefully and whose conversion and sending held up the
server. They are picked where the checks ran (in the job), so the server never holds the
others (letting them all go at once held up the event loop). They are converted to LSP's
lines and characters, and encoded, off the event loop, through the document's one line
index (positions.indexed)."""

from __future__ import annotations

import asyncio
import time
from typing import Any

from lsprotocol import types as T
from pygls.uris import to_fs_path
from pygls.workspace import TextDocument

from afsmc.diagnostics import Diagnostic, Severity, codes
from afsmc.lsp import index as I
from afsmc.lsp.actions import fixes
from afsmc.lsp.analysis import analyse_fast, analyse_full
from afsmc.lsp.positions import Doc, indexed, keep_index, to_range
from afsmc.lsp.state import AfsmServer, DocState, guarded
from afsmc.lsp.transfer import let_go
from afsmc.lsp.worker import Failed, Job, Send, Work, off_loop, release_memory
from afsmc.model import ir

DEBOUNCE = 0.3  # seconds of quiet before the full checks run, when they are slow
FAST_CHECK = 0.1  # a full check this quick runs at once
SMALL = 64 * 1024  # characters: a bigger document is parsed in a child process too
FAST, FULL = "fast", "full"
MAX_SHOWN = 1000  # diagnostics published per document; N901 counts the rest


def _to_lsp(d: Diagnostic, doc: TextDocument, uri: str, index: I.Index | None) -> T.Diagnostic:
    rng = to_range(doc, d.span.start, d.span.end) if d.span is not None else to_range(doc, 0, 0)
    message = d.message + (f"\nhint: {d.hint}" if d.hint else "")
    related = [T.DiagnosticRelatedInformation(
        location=T.Location(uri=uri, range=to_range(doc, r.span.start, r.span.end)),
        message=r.message)
               for r in d.related]
    severity = {Severity.ERROR: T.DiagnosticSeverity.Error,
                Severity.WARNING: T.DiagnosticSeverity.Warning,
                Severity.NOTE: T.DiagnosticSeverity.Information}[d.severity]
    quick = [f.to_data() for f in fixes(d, doc.source, index)]
    return T.Diagnostic(range=rng, message=message, severity=severity, code=d.code, source="afsmc",
                        related_information=related or None, data=quick or None)


def shown(diags: list[Diagnostic]) -> list[Diagnostic]:
    """The diagnostics published for a document: all of them up to MAX_SHOWN; beyond, the
    first MAX_SHOWN by severity (errors, then warnings, then notes; each kind in the order
    reported), in the order reported, and N901 saying how many of each kind are left out."""
    if len(diags) <= MAX_SHOWN:
        return diags
    rank = {Severity.ERROR: 0, Severity.WARNING: 1, Severity.NOTE: 2}
    order = sorted(range(len(diags)), key=lambda i: rank[diags[i].severity])
    kept = sorted(order[:MAX_SHOWN])
    left: dict[Severity, int] = {}
    for i in order[MAX_SHOWN:]:
        left[diags[i].severity] = left.get(diags[i].severity, 0) + 1
    counts = ", ".join(f"{n:,} {kind.value}{'s' if n > 1 else ''}"
                       for kind, n in sorted(left.items(), key=lambda kv: rank[kv[0]]))
    note = Diagnostic(codes.N901, Severity.NOTE,
                      f"{len(diags) - MAX_SHOWN:,} more diagnostics are not shown ({counts}): "
                      f"the editor is given the first {MAX_SHOWN:,}", None,
                      hint="`afsmc check FILE` lists them all")
    return [diags[i] for i in kept] + [note]


def _params(ls: AfsmServer, uri: str, version: int | None, text: str, diags: list[Diagnostic],
            index: I.Index | None) -> tuple[str, Doc]:
    """The notification published for `text`, encoded (off the event loop), and the line
    index it used; `diags` are those `shown`."""
    doc = indexed(ls, uri, text, keep=False)
    params = T.PublishDiagnosticsParams(
        uri=uri, diagnostics=[_to_lsp(d, doc, uri, index) for d in diags], version=version)
    return ls.protocol.encode_notification(T.TEXT_DOCUMENT_PUBLISH_DIAGNOSTICS, params), doc


async def _publish(ls: AfsmServer, uri: str, version: int | None, text: str,
                   diags: list[Diagnostic]) -> None:
    st = ls.docs.get(uri)
    index = st.index if st is not None and st.index is not None and st.index.text == text else None
    encoded, doc = await asyncio.get_running_loop().run_in_executor(
        off_loop(), _params, ls, uri, version, text, diags, index)
    keep_index(ls, uri, doc)
    if st is not None:
        st.published = text
    ls.protocol.send_encoded(encoded)


def _internal_diag(what: str) -> Diagnostic:
    return Diagnostic(codes.E999, Severity.ERROR, f"afsmc could not {what} this file (an internal "
                      "error; see the language server's log)", None)


def _fast_stage(text: str, path: str) -> tuple[list[Diagnostic], ir.Model | None, I.Index | None]:
    fast = analyse_fast(text, path)
    index = I.build(fast.module, text) if fast.module is not None else None
    return shown(fast.diagnostics), fast.model, index


def _full_stage(text: str, path: str) -> tuple[list[Diagnostic], float]:
    started = time.perf_counter()
    diags = analyse_full(text, path)
    return shown(diags), time.perf_counter() - started


def _work(text: str, path: str, stages: tuple[str, ...]) -> Work:
    """The stages, run in a job: each sends its result as soon as it has one; the checks
    do not run on a text with parse or name errors (they would stop at them too)."""

    def work(send: Send) -> None:
        for stage in stages:
            if stage == FAST:
                result = _fast_stage(text, path)
                send((FAST, result))
                if result[0]:
                    return
            else:
                send((FULL, _full_stage(text, path)))

    return work


def _changed(ls: AfsmServer, uri: str) -> None:
    doc = ls.workspace.get_text_document(uri)
    st = ls.docs.setdefault(uri, DocState())
    st.version, st.text = doc.version, doc.source
    if st.task is not None:  # a newer version: the work on the older one stops
        st.task.cancel()
    st.parsed = asyncio.Event()
    st.task = asyncio.get_running_loop().create_task(
        _analyse(ls, uri, st, st.version, st.text, st.parsed))


async def _run(ls: AfsmServer, job: Job, what: str) -> Any:
    """The next message of `job`; None (logged) if its work failed."""
    msg = await job.next()
    if isinstance(msg, Failed):
        ls.window_log_message(T.LogMessageParams(type=T.MessageType.Error, message=msg.trace))
        return (what, None)
    return msg


async def _analyse(ls: AfsmServer, uri: str, st: DocState, version: int | None,
                   text: str, parsed: asyncio.Event) -> None:
    """Parse and resolve, publish; then check, publish. A small document is parsed in a
    thread (tens of milliseconds: no process to start) and checked in a child process; a
    big one is parsed and checked in one child. Cancelling the task kills the child.
    `parsed` is set once the parse is known (or given up), for the semantic tokens."""
    path = to_fs_path(uri) or uri
    big = len(text) > SMALL
    job = Job(_work(text, path, (FAST, FULL) if big else (FAST,)), process=big)
    try:
        msg = await _run(ls, job, FAST)
        if msg is None:
            return
        if msg[1] is None:
            await _publish(ls, uri, version, text, [_internal_diag("parse")])
            return
        diags, model, index = msg[1]
        old: list[object] = [st.model]
        if index is not None:
            index.text = text  # the same text (the child's copy of it is let go)
            old.append(st.index)
            st.index = index
            st.recovered = None
            _refresh_tokens(ls)
        parsed.set()
        # The facts hover shows (values, ranges) hold for the text that resolved: another
        # text keeps none rather than show a constant's old value beside its new declaration.
        st.model = model
        off_loop().submit(let_go, old)  # the older analysis, freed off the loop
        if diags or st.shows_fast:  # new parse or name errors, or old ones now fixed
            await _publish(ls, uri, version, text, diags)
        st.shows_fast = bool(diags)
        if diags:
            return
        if not big:
            # Quick checks run while the author types; slow ones wait for a pause.
            await asyncio.sleep(0 if st.last_check < FAST_CHECK else DEBOUNCE)
            job.cancel()
            job = Job(_work(text, path, (FULL,)), process=True)
        msg = await _run(ls, job, FULL)
        if msg is None:
            return
        if msg[1] is None:
            await _publish(ls, uri, version, text, [_internal_diag("check")])
            return
        diags, st.last_check = msg[1]
        await _publish(ls, uri, version, text, diags)
    finally:
        parsed.set()  # cancelled: a newer version's own event is waited for next
        job.cancel()


def _refresh_tokens(ls: AfsmServer) -> None:
    """Ask a client that supports it to ask for the semantic tokens again: the names of a
    new parse may be coloured otherwise (a request answered before it had the last one)."""
    caps = ls.client_capabilities.workspace
    tokens = caps.semantic_tokens if caps is not None else None
    if tokens is not None and tokens.refresh_support:
        ls.workspace_semantic_tokens_refresh(None)


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
    if st is not None:  # its analysis freed off the loop, then the memory given back
        old = [st.index, st.model]
        st.index = st.model = st.recovered = None
        off_loop().submit(let_go, old)
    del st
    off_loop().submit(release_memory)

