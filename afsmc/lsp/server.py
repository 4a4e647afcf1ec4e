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
- editing.py: formatting and rename;
- actions.py: quick fixes from the diagnostics' hints;
- tokens.py: semantic tokens;
- features.py: folding, workspace symbols, inlay hints, signature help, range formatting;
- worker.py: jobs off the event loop (a killable child process, or a thread).
"""

from __future__ import annotations

import sys
from collections.abc import Callable
from typing import Any

from lsprotocol import types as T

from afsmc.lsp import actions, completion, documents, editing, features, navigation, tokens
from afsmc.lsp.state import AfsmServer

server = AfsmServer()
SWITCH_INTERVAL = 0.001  # seconds

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
    (T.TEXT_DOCUMENT_CODE_ACTION, T.CodeActionOptions(code_action_kinds=[T.CodeActionKind.QuickFix]),
     actions.code_action),
    (T.TEXT_DOCUMENT_SEMANTIC_TOKENS_FULL, tokens.LEGEND, tokens.semantic_tokens),
    (T.TEXT_DOCUMENT_FOLDING_RANGE, None, features.folding_ranges),
    (T.WORKSPACE_SYMBOL, None, features.workspace_symbols),
    (T.TEXT_DOCUMENT_INLAY_HINT, None, features.inlay_hints),
    (T.TEXT_DOCUMENT_SIGNATURE_HELP, T.SignatureHelpOptions(trigger_characters=["(", ","]),
     features.signature_help),
    (T.TEXT_DOCUMENT_RANGE_FORMATTING, None, features.range_formatting),
]
for _name, _options, _handler in _FEATURES:
    server.feature(_name, _options)(_handler)


@server.feature(T.SHUTDOWN)
def _on_shutdown(ls: AfsmServer, params: Any) -> None:
    ls.shut_down = True


def serve() -> int:
    """Serve until `exit`: 0 after a `shutdown` request, 1 without one (as LSP asks; pygls's
    own exit code is lost in its event loop)."""
    # The threads that decode and encode run Python code for seconds on a big document;
    # the event loop's thread, wanting the interpreter back to answer a request, waits for
    # them at most this long each time (the default, 5 ms, adds up over the steps of one
    # request).
    sys.setswitchinterval(SWITCH_INTERVAL)
    server.start_io()
    return 0 if server.shut_down else 1
