"""Semantic tokens: every name of the last good parse coloured by what it names, so that a
theme tells modes, actions, constants (param, const and interval apart), variables, labels,
properties and reward structures apart; built-in functions, the machine's name and simulator
references get theirs too.

The token types that LSP does not define (constant, interval, label, rewards, simulation) are
declared with a standard super type in the VS Code extension, so themes colour them anyway.
"""

from __future__ import annotations

import asyncio
import contextlib
import re

from lsprotocol import types as T

from afsmc.lsp import index as I
from afsmc.lsp.positions import Doc, Shift, shift_of
from afsmc.lsp.state import AfsmServer, DocState, guarded
from afsmc.lsp.worker import in_thread
from afsmc.model.expr import FUNCTIONS
from afsmc.syntax import ast

TYPES = ["enumMember", "method", "event", "constant", "parameter", "interval", "variable",
         "property", "label", "rewards", "function", "namespace", "simulation", "field"]
MODIFIERS = ["declaration", "defaultLibrary"]
LEGEND = T.SemanticTokensLegend(token_types=TYPES, token_modifiers=MODIFIERS)

_KIND = {"mode": "enumMember", "action": "method", "hazard": "event", "variable": "variable",
         "formula": "function", "label": "label", "rewards": "rewards", "property": "property",
         "field": "field"}
_CALL = re.compile(r"\b(" + "|".join(sorted(FUNCTIONS | {"w"})) + r")\s*\(")
_COMMENT = re.compile(r"//[^\n]*|/\*[\s\S]*?(?:\*/|\Z)|\"[^\"\n]*\"")


def constant_kind(decl: object) -> str:
    if isinstance(decl, ast.ParamDecl):
        return "parameter"
    if isinstance(decl, ast.ConstDecl) and isinstance(decl.value, ast.Interval):
        return "interval"
    return "constant"


def token_kind(d: I.Definition) -> str:
    return constant_kind(d.decl) if d.kind == "constant" else _KIND[d.kind]


def spans(idx: I.Index) -> list[tuple[int, int, str, int]]:
    """(start, end, token type, modifier bits) of every name of the index's text, in order."""
    out: dict[int, tuple[int, int, str, int]] = {}
    for o in idx.occurrences:
        d = idx.defs.get((o.ns, o.name))
        if d is not None:
            out[o.start] = (o.start, o.end, token_kind(d), 1 if o.is_def else 0)
    text = idx.text
    blank = _COMMENT.sub(lambda m: " " * len(m.group()) if not m.group().startswith('"')
                         else m.group(), text)
    for m in _CALL.finditer(blank):
        out.setdefault(m.start(1), (m.start(1), m.end(1), "function", 2))
    if idx.module.machine is not None:
        n = idx.module.machine.name.span
        out[n.start] = (n.start, n.end, "namespace", 1)
    for decl in idx.module.decls:
        if isinstance(decl, ast.ConstDecl) and decl.source is not None:
            r = decl.source.ref.span
            out[r.start] = (r.start, r.end, "simulation", 0)
            for key, _ in decl.source.policy:
                out[key.span.start] = (key.span.start, key.span.end, "parameter", 0)
    return sorted(out.values())


def encode(rows: list[tuple[int, int, str, int]], shift: Shift, doc: Doc) -> list[int]:
    """LSP's relative encoding, for the names on lines unchanged since the last good parse."""
    data: list[int] = []
    line = char = 0
    for start, end, kind, mods in rows:
        at = shift.to_new(start, end)
        if at is None:
            continue
        a = doc.client_position_at_offset(at[0])
        b = doc.client_position_at_offset(at[1])
        if b.line != a.line:
            continue  # a token does not span lines
        data += [a.line - line, a.character - (char if a.line == line else 0),
                 b.character - a.character, TYPES.index(kind), mods]
        line, char = a.line, a.character
    return data


@guarded
async def semantic_tokens(ls: AfsmServer, params: T.SemanticTokensParams) -> T.SemanticTokens:
    """The tokens of the editor's text: a request that comes right after `didOpen` or
    `didChange` waits (up to WAIT seconds) for that text's parse, so that a client that
    asks once gets colours; a text that does not parse answers from the last good one."""
    uri = params.text_document.uri
    st = ls.docs.get(uri)
    if st is None:
        return T.SemanticTokens(data=[])
    await _parsed(st)
    idx = st.index
    if idx is None:
        return T.SemanticTokens(data=[])

    def tokens() -> list[int]:  # off the event loop: a 2 MB document's take a second or more
        shift, doc = shift_of(ls, uri, idx)
        return encode(spans(idx), shift, doc)

    return T.SemanticTokens(data=await in_thread(tokens))


WAIT = 5.0  # seconds a token request waits for the parse of the current text


async def _parsed(st: DocState) -> None:
    """Wait until the current version of the document is parsed (a newer version that
    comes meanwhile is waited for in turn), at most WAIT seconds in all."""
    deadline = asyncio.get_running_loop().time() + WAIT
    while (event := st.parsed) is not None and not event.is_set():
        left = deadline - asyncio.get_running_loop().time()
        if left <= 0:
            return
        with contextlib.suppress(TimeoutError):
            await asyncio.wait_for(event.wait(), left)
