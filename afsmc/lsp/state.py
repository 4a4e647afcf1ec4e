"""The language server's state: the server object, what it knows of each open document, and
the wrapper that keeps a failing handler from failing the request."""

from __future__ import annotations

import asyncio
import functools
import json
import os
import stat
import sys
import threading
import traceback
import types
from collections.abc import Callable
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass
from typing import Any, BinaryIO, TypeVar

from lsprotocol import types as T
from pygls.exceptions import JsonRpcException, JsonRpcInternalError, JsonRpcInvalidRequest
from pygls.io_ import StdoutWriter, run_async
from pygls.lsp.server import LanguageServer
from pygls.protocol import LanguageServerProtocol
from pygls.protocol.json_rpc import JsonRPCNotification, JsonRPCProtocol, RPCRequest

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



BIG_REPLY = 1000  # items in a reply's result: encoded to JSON off the event loop
_ENCODER: ThreadPoolExecutor | None = None


class _Protocol(LanguageServerProtocol):
    """pygls only logs a request whose params do not fit its method (a negative position,
    no params at all), and a client waiting for the answer would hang: answer it with the
    error. A reply of more than BIG_REPLY items (the folds or the references of a big
    document) is encoded in a thread of its own, not on the event loop, where it would hold
    every other request; replies may come in any order (JSON-RPC matches them by id).
    Notifications keep theirs: a big one (a document's diagnostics) is encoded off the loop
    by its sender (`encode_notification`) and sent by the loop (`send_encoded`)."""

    def _send_data(self, data: Any) -> None:
        result = getattr(data, "result", None)
        if not (isinstance(result, (list, tuple)) and len(result) > BIG_REPLY):
            super()._send_data(data)
            return
        global _ENCODER
        if _ENCODER is None:
            _ENCODER = ThreadPoolExecutor(1, thread_name_prefix="afsmc-lsp-encode")
        asyncio.get_running_loop().run_in_executor(_ENCODER, self._encode, data
                                                   ).add_done_callback(self._write)

    def _encode(self, data: Any) -> str:
        """The reply's JSON, its result's items encoded one by one: one `json.dumps` of
        the whole holds the interpreter's lock throughout (in C), and the event loop's
        thread with it."""
        msg = self._serialize_message(data)
        items = msg.pop("result")
        head = json.dumps(msg)
        return head[:-1] + ', "result": [' + ", ".join(json.dumps(x) for x in items) + "]}"

    def _write(self, encoded: asyncio.Future[str]) -> None:
        """Send a reply encoded off the loop."""
        try:
            self.send_encoded(encoded.result())
        except Exception as error:
            self._server._report_server_error(error, JsonRpcInternalError)

    def encode_notification(self, method: str, params: Any) -> str:
        """The JSON of a notification, made where this is called: off the event loop (a
        document's diagnostics, up to a thousand, are slow to encode); the loop then sends
        it with `send_encoded`, in the order it sends the others."""
        kind = self.get_message_type(method) or JsonRPCNotification
        return json.dumps(kind(method=method, params=params, jsonrpc=JsonRPCProtocol.VERSION),
                          default=self._serialize_message)

    def send_encoded(self, body: str) -> None:
        """Send a message encoded off the loop, framed as pygls frames its own."""
        header = (f"Content-Length: {len(body)}\r\n"
                  f"Content-Type: {self.CONTENT_TYPE}; charset={self.CHARSET}\r\n\r\n")
        if self.writer is not None:
            self.writer.write((header + body).encode(self.CHARSET))

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


class _PipeReader:
    """Standard input read by the event loop itself, where it is a pipe (as editors start
    the server). pygls reads it in a thread, a line at a time, and hands each line from
    that thread to the event loop: several hand-overs a request, each waiting for the
    interpreter while the decoding thread runs."""

    def __init__(self, stdin: BinaryIO) -> None:
        self._stdin = stdin
        self._stream: asyncio.StreamReader | None = None

    async def _reader(self) -> asyncio.StreamReader:
        if self._stream is None:
            loop = asyncio.get_running_loop()
            stream = asyncio.StreamReader(limit=1 << 20)
            await loop.connect_read_pipe(lambda: asyncio.StreamReaderProtocol(stream),
                                         self._stdin)
            self._stream = stream
        return self._stream

    async def readline(self) -> bytes:
        return await (await self._reader()).readline()

    async def readexactly(self, n: int) -> bytes:
        try:
            return await (await self._reader()).readexactly(n)
        except asyncio.IncompleteReadError as exc:  # the end: what a file's read gives
            return exc.partial


def _is_pipe(stream: BinaryIO) -> bool:
    try:
        return stat.S_ISFIFO(os.fstat(stream.fileno()).st_mode)
    except (OSError, ValueError):
        return False


class AfsmServer(LanguageServer):
    protocol: _Protocol

    def __init__(self) -> None:
        super().__init__("afsmc", __version__, protocol_cls=_Protocol)

        self.docs: dict[str, DocState] = {}
        self.shut_down = False  # a `shutdown` request came: `exit` is then 0

    def _start_io_async(self, stdin: BinaryIO | None = None,
                        stdout: BinaryIO | None = None) -> None:
        """pygls's own, with a pipe on standard input read by the event loop (_PipeReader)."""
        stdin = stdin or sys.stdin.buffer
        if not _is_pipe(stdin):
            super()._start_io_async(stdin, stdout)
            return
        self._stop_event = threading.Event()
        self.protocol.set_writer(StdoutWriter(stdout or sys.stdout.buffer))
        try:
            asyncio.run(run_async(stop_event=self._stop_event, reader=_PipeReader(stdin),
                                  protocol=self.protocol, error_handler=self.report_server_error))
        except BrokenPipeError:
            pass  # the client is gone
        except (KeyboardInterrupt, SystemExit):
            pass
        finally:
            self.shutdown()  # type: ignore[no-untyped-call]  # (pygls)



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
