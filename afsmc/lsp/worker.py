"""Work off the language server's event loop: a job runs a function that reports messages as
it goes, in a forked child process (where fork exists) or else in a thread.

A child can be killed, so a newer version of a document stops the work on the older one at
once, and whatever the work allocated goes back to the system with the child: the server's
own memory stays at its baseline however big the documents were. Messages come back pickled,
in parts (transfer.py), through a pipe that the event loop watches (`add_reader`), so the
loop never waits for them; the loop only gathers their bytes, and one decoding thread
unpickles them (the analysis of a 2 MB document is some 30 MB of pickle: seconds of
decoding that would hold up every request).
A thread cannot be killed: its messages are dropped once the job is cancelled.
"""

from __future__ import annotations

import asyncio
import contextlib
import gc
import os
import signal
import struct
import threading
import traceback
from collections.abc import Callable
from concurrent.futures import ThreadPoolExecutor
from typing import Any

from afsmc.diagnostics import CompileError
from afsmc.lifetime import die_with_parent
from afsmc.lsp.transfer import Decoder, Failed, Parts

__all__ = ["Failed", "Job", "Send", "Work", "call", "in_thread", "off_loop", "release_memory"]

Send = Callable[[Any], None]
Work = Callable[[Send], None]

# a part's length, and whether it is the last part of its message
_HEADER = struct.Struct("<QB")
FORK = hasattr(os, "fork")


_DECODER: ThreadPoolExecutor | None = None


def off_loop() -> ThreadPoolExecutor:
    """The one thread that decodes the jobs' messages and prepares what the server publishes
    from them: one, so that messages are decoded in the order they came."""
    global _DECODER
    if _DECODER is None:
        _DECODER = ThreadPoolExecutor(1, thread_name_prefix="afsmc-lsp-decode")
    return _DECODER


async def in_thread(fn: Callable[..., Any], *args: Any) -> Any:
    """`fn(*args)` in the decoding thread: work on a whole document (the outline, the
    semantic tokens, the folds of a 2 MB document take seconds) that the event loop then
    only sends. Python code there gives the loop's thread the interpreter every few
    milliseconds."""
    return await asyncio.get_running_loop().run_in_executor(off_loop(), fn, *args)


def _reap(pid: int) -> None:
    """Wait for a child that ended or was killed, in a thread of its own: the system takes
    a while to take down a child that analysed a big document (its memory), and the event
    loop, waiting for it, would answer nothing meanwhile."""
    with contextlib.suppress(ChildProcessError):
        os.waitpid(pid, 0)


class Job:
    """`work(send)` running in a child process (`process=True`, where fork exists) or a
    thread; `await job.next()` gives each message it sends, then None when it is done."""

    def __init__(self, work: Work, process: bool) -> None:
        self._loop = asyncio.get_running_loop()
        self._queue: asyncio.Queue[Any] = asyncio.Queue()
        self.cancelled = False
        self.pid = 0
        self._fd = -1
        self._buf = bytearray()
        self._decoder = Decoder()
        if process and FORK:
            self._fork(work)
        else:
            threading.Thread(target=self._thread, args=(work,), daemon=True).start()

    # ---- in a thread -------------------------------------------------------------------

    def _thread(self, work: Work) -> None:
        def send(msg: Any) -> None:
            if not self.cancelled:
                self._loop.call_soon_threadsafe(self._queue.put_nowait, msg)

        try:
            work(send)
        except BaseException:
            send(Failed(traceback.format_exc()))
        self._loop.call_soon_threadsafe(self._queue.put_nowait, None)

    # ---- in a child process ------------------------------------------------------------

    def _fork(self, work: Work) -> None:
        parent = os.getpid()
        r, w = os.pipe()
        pid = os.fork()
        if pid == 0:  # the child: never returns, never touches the server's streams
            code = 0
            try:
                os.close(r)
                signal.set_wakeup_fd(-1)
                die_with_parent(parent)

                def send(msg: Any) -> None:
                    parts = Parts().encode(msg)
                    for i, data in enumerate(parts):
                        view = memoryview(_HEADER.pack(len(data), i == len(parts) - 1) + data)
                        while view:
                            view = view[os.write(w, view):]

                try:
                    work(send)
                except BaseException:
                    send(Failed(traceback.format_exc()))
            except BaseException:
                code = 1
            os._exit(code)  # no atexit, no flush of the server's buffered output
        os.close(w)
        self.pid, self._fd = pid, r
        os.set_blocking(r, False)
        self._loop.add_reader(r, self._readable)

    def _readable(self) -> None:
        try:
            chunk = os.read(self._fd, 1 << 20)
        except BlockingIOError:
            return
        except OSError:
            chunk = b""
        if chunk:
            self._buf += chunk
            while len(self._buf) >= _HEADER.size:
                n, last = _HEADER.unpack_from(self._buf)
                if len(self._buf) < _HEADER.size + n:
                    break
                data = bytes(self._buf[_HEADER.size:_HEADER.size + n])
                del self._buf[:_HEADER.size + n]
                if self.cancelled:
                    continue
                # decoded off the loop, in order: a message once its last part is
                if last:
                    self._queue.put_nowait(self._loop.run_in_executor(
                        off_loop(), self._decoder.last, data))
                else:
                    self._loop.run_in_executor(off_loop(), self._decoder.part, data)
            return
        self._close()
        self._queue.put_nowait(None)

    def _close(self) -> None:
        if self._fd >= 0:
            self._loop.remove_reader(self._fd)
            os.close(self._fd)
            self._fd = -1
        if self.pid:
            threading.Thread(target=_reap, args=(self.pid,), name="afsmc-lsp-reap",
                             daemon=True).start()
            self.pid = 0

    # ---- for the server ----------------------------------------------------------------

    async def next(self) -> Any:
        """The next message, or None once the job is done or cancelled."""
        if self.cancelled:
            return None
        msg = await self._queue.get()
        if isinstance(msg, asyncio.Future):
            msg = await msg
        return None if self.cancelled else msg

    def cancel(self) -> None:
        """Stop the work now (a child is killed) and drop whatever it would still send."""
        if self.cancelled:
            return
        self.cancelled = True
        if self.pid:
            with contextlib.suppress(ProcessLookupError):
                os.kill(self.pid, signal.SIGKILL)
            self._close()
        self._queue.put_nowait(None)


def release_memory() -> None:
    """Give the memory of closed documents back to the system: collect their cycles and
    return the C allocator's free pages (glibc only)."""
    import ctypes

    gc.collect()
    with contextlib.suppress(OSError, AttributeError):
        ctypes.CDLL(None).malloc_trim(0)


async def call(fn: Callable[..., Any], *args: Any, process: bool = True) -> Any:
    """`fn(*args)` in a job (a child process where fork exists): its result, or its
    exception raised here again. Cancelling the awaiting task kills the child."""

    def work(send: Send) -> None:
        try:
            send(("ok", fn(*args)))
        except CompileError as exc:  # its diagnostics pickle; the exception does not
            send(("compile", list(exc.diagnostics)))

    job = Job(work, process)
    try:
        msg = await job.next()
    finally:
        job.cancel()
    if isinstance(msg, Failed) or msg is None:
        raise RuntimeError("the job failed" + (f":\n{msg.trace}" if msg else ""))
    how, value = msg
    if how == "compile":
        raise CompileError(value)
    return value
