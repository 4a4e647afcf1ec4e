"""End-to-end tests that `afsmc lsp` never blocks (a real client, pytest-lsp, over stdio):
requests are answered while a 2 MB document is being analysed, a newer version cancels the
work on the older one, closing a document gives its memory back, and protocol errors get
the replies LSP specifies.

The big document is generated here. The latency bound is generous (the machine is shared);
the true figure is measured by benchmarks/lsp_latency.py and recorded in docs/editors.md.
"""

from __future__ import annotations

import asyncio
import sys
import time
from pathlib import Path

import pytest
import pytest_lsp
from lsprotocol import types as T
from pygls.exceptions import JsonRpcException
from pytest_lsp import ClientServerConfig, LanguageClient

from afsmc.syntax.fmt import format_text

pytestmark = pytest.mark.slow  # real servers with megabyte documents: seconds each

ROOT = Path(__file__).resolve().parents[2]
UAV = ROOT / "examples" / "uav.afsm"
CONFIG = ClientServerConfig(server_command=[sys.executable, "-m", "afsmc.cli", "lsp"])

SMALL = "machine m;\nconst int N = 3;\nvar x : [0..N] init 0;\nmode A initial final;\n"


def big_text(size: int = 2_000_000) -> str:
    lines = ["machine big;"]
    n, i = len(lines[0]), 0
    while n < size:
        line = f"const int C{i} = {i % 97};"
        lines.append(line)
        n += len(line) + 1
        i += 1
    return "\n".join(lines) + "\n"


def _open(client: LanguageClient, uri: str, text: str, version: int = 1) -> None:
    client.text_document_did_open(T.DidOpenTextDocumentParams(
        text_document=T.TextDocumentItem(uri=uri, language_id="afsm", version=version, text=text)))


PUBLISHED: dict[str, list[T.PublishDiagnosticsParams]] = {}


def _record(client: LanguageClient) -> None:
    """Keep every publishDiagnostics, with its version (the default handler keeps the last
    diagnostics only)."""
    default = client.protocol.fm.features[T.TEXT_DOCUMENT_PUBLISH_DIAGNOSTICS]

    def publish(params: T.PublishDiagnosticsParams) -> None:
        PUBLISHED.setdefault(params.uri, []).append(params)
        default(params)

    client.protocol.fm.features[T.TEXT_DOCUMENT_PUBLISH_DIAGNOSTICS] = publish


async def _diagnostics_of(client: LanguageClient, uri: str, version: int,
                          timeout: float = 30) -> list[T.Diagnostic]:
    """The first diagnostics published for `version` of `uri` (waits for them)."""
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        for p in PUBLISHED.get(uri, []):
            if p.version == version:
                return p.diagnostics
        await asyncio.sleep(0.01)
    raise AssertionError(f"no diagnostics for version {version} of {uri}")


def _children(pid: int) -> list[int]:
    out: list[int] = []
    for task in Path(f"/proc/{pid}/task").iterdir():
        out += [int(x) for x in (task / "children").read_text().split()]
    return out


def _rss_mb(pid: int) -> float:
    for line in Path(f"/proc/{pid}/status").read_text().splitlines():
        if line.startswith("VmRSS:"):
            return int(line.split()[1]) / 1024
    raise AssertionError("no VmRSS")


@pytest_lsp.fixture(config=CONFIG)
async def client(lsp_client: LanguageClient):  # type: ignore[no-untyped-def]
    await lsp_client.initialize_session(T.InitializeParams(
        capabilities=T.ClientCapabilities(), root_uri=ROOT.as_uri()))
    _record(lsp_client)
    yield
    if not getattr(lsp_client, "_shut", False):
        await lsp_client.shutdown_session()


async def _hover_time(client: LanguageClient, uri: str) -> float:
    t = time.perf_counter()
    hover = await client.text_document_hover_async(T.HoverParams(
        text_document=T.TextDocumentIdentifier(uri=uri), position=T.Position(line=2, character=12)))
    elapsed = time.perf_counter() - t
    assert hover is not None and "N" in str(hover.contents)
    return elapsed


@pytest.mark.asyncio
async def test_hover_on_a_small_document_while_a_2mb_document_is_checked(
        client: LanguageClient) -> None:
    small, big = "file:///tmp/small.afsm", "file:///tmp/big.afsm"
    _open(client, small, SMALL)
    await _diagnostics_of(client, small, 1)
    _open(client, big, big_text())
    await asyncio.sleep(0.3)  # the big document's analysis is under way
    pid = client._server.pid  # type: ignore[union-attr]
    assert _children(pid), "the big document is analysed in a child process"
    times = [await _hover_time(client, small) for _ in range(10)]
    assert max(times) < 0.5, times
    # symbols and completion answer too, from the small document's last good analysis
    symbols = await client.text_document_document_symbol_async(T.DocumentSymbolParams(
        text_document=T.TextDocumentIdentifier(uri=small)))
    assert {s.name for s in symbols or []} >= {"N", "x", "A"}
    # completion in the big document itself, before its first analysis is done: the
    # keywords (its names come with the analysis); the line starts of its 2 MB are found
    # first (0.1 s, more on a loaded machine)
    text = big_text()
    t = time.perf_counter()
    items = await client.text_document_completion_async(T.CompletionParams(
        text_document=T.TextDocumentIdentifier(uri=big),
        position=T.Position(line=text.count("\n"), character=0)))
    assert time.perf_counter() - t < 3
    assert isinstance(items, T.CompletionList) and "const" in {i.label for i in items.items}


@pytest.mark.asyncio
async def test_a_newer_version_cancels_the_work_on_the_older_one(client: LanguageClient) -> None:
    big = "file:///tmp/big2.afsm"
    _open(client, big, big_text())
    await asyncio.sleep(0.3)
    pid = client._server.pid  # type: ignore[union-attr]
    (first,) = _children(pid)
    client.text_document_did_change(T.DidChangeTextDocumentParams(
        text_document=T.VersionedTextDocumentIdentifier(uri=big, version=2),
        content_changes=[T.TextDocumentContentChangeWholeDocument(text=SMALL + "bad")]))
    diags = await _diagnostics_of(client, big, 2, timeout=20)
    assert diags and all(str(d.code).startswith("E1") for d in diags)
    assert first not in _children(pid)  # killed, not left to finish


@pytest.mark.asyncio
async def test_memory_returns_to_baseline_after_close(client: LanguageClient) -> None:
    pid = client._server.pid  # type: ignore[union-attr]
    small = "file:///tmp/small3.afsm"
    _open(client, small, SMALL)
    await _diagnostics_of(client, small, 1)
    baseline = _rss_mb(pid)
    for k in range(3):
        uri = f"file:///tmp/big3_{k}.afsm"
        _open(client, uri, big_text())
        await asyncio.sleep(0.5)
        client.text_document_did_close(T.DidCloseTextDocumentParams(
            text_document=T.TextDocumentIdentifier(uri=uri)))
    await _hover_time(client, small)  # the closes have been handled
    await asyncio.sleep(0.2)
    assert _rss_mb(pid) < baseline + 10, (baseline, _rss_mb(pid))
    assert _children(pid) == []


@pytest.mark.asyncio
async def test_protocol_errors_get_the_specified_replies(client: LanguageClient) -> None:
    with pytest.raises(JsonRpcException) as unknown:
        await client.protocol.send_request_async("afsmc/noSuchMethod", {})
    assert unknown.value.code == -32601  # MethodNotFound
    await client.shutdown_async(None)
    with pytest.raises(JsonRpcException) as after:
        await client.text_document_hover_async(T.HoverParams(
            text_document=T.TextDocumentIdentifier(uri="file:///tmp/x.afsm"),
            position=T.Position(line=0, character=0)))
    assert after.value.code == -32600  # InvalidRequest
    client._shut = True  # type: ignore[attr-defined]
    client.exit(None)


@pytest.mark.asyncio
async def test_formatting_a_big_document_does_not_hold_up_requests(
        client: LanguageClient) -> None:
    small, big = "file:///tmp/small4.afsm", "file:///tmp/big4.afsm"
    _open(client, small, SMALL)
    await _diagnostics_of(client, small, 1)
    text = big_text(100_000).replace(" = ", "   =   ")
    _open(client, big, text)
    formatting = asyncio.ensure_future(client.text_document_formatting_async(
        T.DocumentFormattingParams(text_document=T.TextDocumentIdentifier(uri=big),
                                   options=T.FormattingOptions(tab_size=4, insert_spaces=True))))
    await asyncio.sleep(0.2)
    times = [await _hover_time(client, small) for _ in range(5)]
    assert max(times) < 0.5, times
    edits = await asyncio.wait_for(formatting, 120)
    assert edits and edits[0].new_text == format_text(text)
