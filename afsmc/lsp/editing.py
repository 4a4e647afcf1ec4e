"""Editing: formatting (as `afsmc fmt`) and renaming; a rename the checker would reject is
refused with the reason, in words for the user."""

from __future__ import annotations

import asyncio
import functools
import logging
import traceback
from collections import Counter
from typing import Any

from lsprotocol import types as T
from pygls.exceptions import JsonRpcException
from pygls.uris import to_fs_path

from afsmc.diagnostics import CompileError
from afsmc.lsp import index as I
from afsmc.lsp.analysis import analyse_fast
from afsmc.lsp.documents import SMALL
from afsmc.lsp.navigation import lookup
from afsmc.lsp.positions import current, snapshot, to_range
from afsmc.lsp.state import AfsmServer, F, guarded
from afsmc.lsp.worker import call
from afsmc.model.expr import FUNCTIONS
from afsmc.model.names import AFSM_KEYWORDS
from afsmc.syntax.fmt import format_text, line_ending
from afsmc.text import article


@guarded
async def formatting(ls: AfsmServer, params: T.DocumentFormattingParams
                     ) -> list[T.TextEdit] | None:
    uri = params.text_document.uri
    doc = current(ls, uri)
    # As `afsmc fmt` does: line endings alone never make a text unformatted, and the
    # formatted text keeps the document's own.
    text = doc.source.replace("\r\n", "\n").replace("\r", "\n")
    try:
        out = await call(format_text, text, to_fs_path(uri) or uri, process=len(text) > SMALL)
    except CompileError:
        return None  # a syntax error: it is already shown as a diagnostic
    if out == text:
        return []
    return [T.TextEdit(range=to_range(doc, 0, len(doc.source)),
                       new_text=out.replace("\n", line_ending(doc.source)))]


RENAMEABLE = {"mode", "constant", "variable", "action", "hazard", "formula", "label", "rewards",
              "property"}


def _rename_target(ls: AfsmServer, uri: str, pos: T.Position) -> tuple[I.Index, I.Definition,
                                                                       I.Occurrence] | None:
    st = ls.docs.get(uri)
    doc = ls.workspace.get_text_document(uri)
    if st is None or st.index is None or st.index.text != doc.source:
        return None  # only on text that parses: the spans must be current
    found = lookup(ls, uri, pos)
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
    async def wrapper(ls: AfsmServer, params: Any) -> Any:
        try:
            result = fn(ls, params)
            return await result if asyncio.iscoroutine(result) else result
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
    found = lookup(ls, uri, pos)
    if found is None:
        return None
    idx, occ, _, _ = found
    d = idx.definition(occ)
    if d is None:
        return f"'{occ.name}' is not declared in this file"
    if d.kind not in RENAMEABLE:
        return "a tuple's fields cannot be renamed" if d.kind == "field" else \
            f"{article(d.kind)} {d.kind} cannot be renamed"
    return None



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
    return to_range(snapshot(ls, uri, idx.text), occ.start, occ.end)


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
        return f"'{new}' is already declared (as {article(kind)} {kind})"
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


@refusing
async def rename(ls: AfsmServer, params: T.RenameParams) -> T.WorkspaceEdit | None:
    uri = params.text_document.uri
    target = _rename_target(ls, uri, params.position)
    if target is None:
        raise RequestFailed(_why_not_renameable(ls, uri, params.position)
                            or "there is no name to rename here")
    idx, d, _ = target
    # off the event loop: the renamed text is parsed and resolved (seconds for 2 MB)
    why = await call(refusal, idx, d, params.new_name, to_fs_path(uri) or uri,
                     process=len(idx.text) > SMALL)
    if why is not None:
        raise RequestFailed(f"cannot rename {d.kind} '{d.name}' to '{params.new_name}': {why}")
    doc = snapshot(ls, uri, idx.text)
    edits = [T.TextEdit(range=to_range(doc, o.start, o.end), new_text=params.new_name)
             for o in idx.references(d.ns, d.name)]
    return T.WorkspaceEdit(changes={uri: edits})
