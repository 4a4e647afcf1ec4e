"""The language server's state: the server object, what it knows of each open document, and
the wrapper that keeps a failing handler from failing the request."""

from __future__ import annotations

import asyncio
import functools
import traceback
import types
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any, TypeVar

from lsprotocol import types as T
from pygls.exceptions import JsonRpcException, JsonRpcInvalidRequest
from pygls.lsp.server import LanguageServer
from pygls.protocol import LanguageServerProtocol
from pygls.protocol.json_rpc import RPCRequest

from afsmc import __version__
from afsmc.lsp import index as I
from afsmc.model import ir

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
    task: asyncio.Task[None] | None = None  # the analysis of the current version
    last_check: float = 0.0  # seconds the last full check of this document took
    published: str | None = None  # the text of the diagnostics on screen (their fixes' offsets)
    current: Any = None  # the editor's text as a positions.Doc, while it is the same
    shows_fast: bool = False  # the diagnostics on screen are parse or name errors
    # set once the current version is parsed (its index, or its parse errors, known):
    # semantic tokens asked for right after a change wait for it (tokens.py)
    parsed: asyncio.Event | None = None



class _Protocol(LanguageServerProtocol):
    """pygls only logs a request whose params do not fit its method (a negative position,
    no params at all), and a client waiting for the answer would hang: answer it with the
    error."""

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

    def handle_message(self, message: Any) -> Any:
        # pygls drops a request that comes after `shutdown`, and the client would wait
        # forever: LSP asks for an InvalidRequest error.
        if self._shutdown and isinstance(message, RPCRequest) and message.method != T.EXIT:
            self._send_response(message.id, error=JsonRpcInvalidRequest(
                f"the server is shut down: {message.method} is refused").to_response_error())
            return None
        return super().handle_message(message)


class AfsmServer(LanguageServer):
    def __init__(self) -> None:
        super().__init__("afsmc", __version__, protocol_cls=_Protocol)

        self.docs: dict[str, DocState] = {}
        self.shut_down = False  # a `shutdown` request came: `exit` is then 0



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
