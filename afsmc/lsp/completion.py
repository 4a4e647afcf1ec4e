"""Completion: the names that fit where the cursor is, from the last text that parsed, or,
in a file that has never parsed, from the text with its broken part left out (I.recover)."""

from __future__ import annotations

import re

from lsprotocol import types as T
from pygls.uris import to_fs_path

from afsmc.lsp import index as I
from afsmc.lsp.documents import SMALL
from afsmc.lsp.positions import current
from afsmc.lsp.state import AfsmServer, guarded
from afsmc.model.expr import FUNCTIONS
from afsmc.resolve.templates import AGGREGATES

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
            + [T.CompletionItem(f, kind=T.CompletionItemKind.Function,
                                detail="over an agent family (agent r[1..N] : T)")
               for f in sorted(AGGREGATES)]
            + [T.CompletionItem(k, kind=T.CompletionItemKind.Keyword) for k in I.KEYWORDS
               if k not in FUNCTIONS])  # `min`, `max`: once, as the functions they are


@guarded
def completion(ls: AfsmServer, params: T.CompletionParams) -> T.CompletionList:
    uri = params.text_document.uri
    doc = current(ls, uri)
    offset = doc.offset_at_position(params.position)
    line_start = doc.source.rfind("\n", 0, offset) + 1
    st = ls.docs.get(uri)
    idx = st.index if st is not None else None
    if idx is None:  # never parsed: no last good parse to take the names from
        if st is not None and st.recovered is not None \
                and st.recovered[:2] == (doc.source, line_start):
            idx = st.recovered[2]
        elif len(doc.source) > SMALL:
            # Parsing or scanning it here would hold up every request for seconds: the
            # names come with its first analysis (in a child process), the keywords now.
            idx = I.scan("", to_fs_path(uri) or uri)
        else:
            idx = I.recover(doc.source, offset, to_fs_path(uri) or uri)
            if st is not None:
                st.recovered = (doc.source, line_start, idx)
    items = completions(idx, doc.source[line_start:offset])
    return T.CompletionList(is_incomplete=False, items=items)
