"""`afsmc lsp`: a Language Server Protocol server (pygls 2) for .afsm files.

It reuses the compiler: the parser and the resolver run on every change, so syntax and name
errors appear as the author types and navigation follows the text; the semantic checks run
once typing pauses (afsmc/lsp/documents.py).

A file that does not parse keeps the navigation of its last good parse, mapped to the
editor's text through the lines both share (positions.Shift); completion in a file that has
never parsed uses the text with its broken part left out (I.recover); nothing a client sends
makes the server exit (every handler turns a failure into a log message).

This module wires the features to the server:
- state.py: the server object and what it knows of each document;
- analysis.py: parsing, resolving and checking a text;
- positions.py: LSP positions against afsmc's offsets;
- documents.py: document sync and publishing diagnostics;
- navigation.py: hover, definition, references, document symbols;
- completion.py: completion;
- editing.py: formatting and rename.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

from lsprotocol import types as T

from afsmc.lsp import completion, documents, editing, navigation
from afsmc.lsp.state import AfsmServer

server = AfsmServer()

_FEATURES: list[tuple[str, Any, Callable[..., Any]]] = [
    (T.TEXT_DOCUMENT_DID_OPEN, None, documents.did_open),
    (T.TEXT_DOCUMENT_DID_CHANGE, None, documents.did_change),
    (T.TEXT_DOCUMENT_DID_CLOSE, None, documents.did_close),
    (T.TEXT_DOCUMENT_HOVER, None, navigation.hover),
    (T.TEXT_DOCUMENT_DEFINITION, None, navigation.definition),
    (T.TEXT_DOCUMENT_REFERENCES, None, navigation.references),
    (T.TEXT_DOCUMENT_DOCUMENT_SYMBOL, None, navigation.document_symbols),
    (T.TEXT_DOCUMENT_COMPLETION, T.CompletionOptions(trigger_characters=['"', "(", "."]),
     completion.completion),
    (T.TEXT_DOCUMENT_FORMATTING, None, editing.formatting),
    (T.TEXT_DOCUMENT_PREPARE_RENAME, None, editing.prepare_rename),
    (T.TEXT_DOCUMENT_RENAME, None, editing.rename),
]
for _name, _options, _handler in _FEATURES:
    server.feature(_name, _options)(_handler)


@server.feature(T.SHUTDOWN)
def _on_shutdown(ls: AfsmServer, params: Any) -> None:
    ls.shut_down = True


def serve() -> int:
    """Serve until `exit`: 0 after a `shutdown` request, 1 without one (as LSP asks; pygls's
    own exit code is lost in its event loop)."""
    server.start_io()
    return 0 if server.shut_down else 1
