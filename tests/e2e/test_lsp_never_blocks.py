"""`afsmc lsp` answers while the analysis of a 2 MB document comes back (issue 51), through
a real client (pytest-lsp over stdio): the document is valid and has 90,000 warnings (every
constant unused, W304), the case where no request on any document was answered for minutes
(the analysis was unpickled on the event loop, each of the 90,000 diagnostics' positions
rebuilt the list of lines). The test asserts the order of events, not times: hovers on a
small document are answered after the big one's parse has come back to the server (it asks
the client to refresh the semantic tokens then) and before its diagnostics are published,
and those are capped, with N901 counting the rest. Then its outline and the workspace
symbols are asked, each with a hover sent behind it on the same pipe, which is answered
promptly: both are capped (a reply of all its names is megabytes, and the client reads it
before the hover's reply). The latency is measured by benchmarks/lsp_latency.py and
recorded in docs/benchmarks.md ("Input size scaling").
"""

from __future__ import annotations

import asyncio
import sys
import time
from pathlib import Path

import pytest
import pytest_lsp
from lsprotocol import types as T
from pytest_lsp import ClientServerConfig, LanguageClient

from afsmc.lsp.documents import MAX_SHOWN
from afsmc.lsp.navigation import MAX_SYMBOLS

pytestmark = pytest.mark.slow  # a real server with a 2 MB document: about 20 s

ROOT = Path(__file__).resolve().parents[2]
SMALL = "machine m;\nconst int N = 3;\nvar x : [0..N] init 0;\nmode A initial final;\n"
EVENTS: list[tuple[str, float]] = []  # (what, when), as the client saw them
PUBLISHED: dict[str, list[T.PublishDiagnosticsParams]] = {}


def unused_constants(size: int = 2_000_000) -> str:
    """A valid mission of `size` characters whose constants nothing uses (one W304 each)."""
    lines = ["machine big;", "mode A = 0 initial final;"]
    n, i = 40, 0
    while n < size:
        lines.append(f"const int C{i} = {i % 97};")
        n += len(lines[-1]) + 1
        i += 1
    return "\n".join(lines) + "\n"


@pytest_lsp.fixture(config=ClientServerConfig(
    server_command=[sys.executable, "-m", "afsmc.cli", "lsp"]))
async def client(lsp_client: LanguageClient):  # type: ignore[no-untyped-def]
    @lsp_client.feature(T.WORKSPACE_SEMANTIC_TOKENS_REFRESH)
    def _refresh(params: None) -> None:
        EVENTS.append(("refresh", time.monotonic()))

    default = lsp_client.protocol.fm.features[T.TEXT_DOCUMENT_PUBLISH_DIAGNOSTICS]

    def _publish(params: T.PublishDiagnosticsParams) -> None:  # each one, in order
        PUBLISHED.setdefault(params.uri, []).append(params)
        EVENTS.append((f"diagnostics {params.uri}", time.monotonic()))
        default(params)

    lsp_client.protocol.fm.features[T.TEXT_DOCUMENT_PUBLISH_DIAGNOSTICS] = _publish

    await lsp_client.initialize_session(T.InitializeParams(
        capabilities=T.ClientCapabilities(workspace=T.WorkspaceClientCapabilities(
            semantic_tokens=T.SemanticTokensWorkspaceClientCapabilities(refresh_support=True))),
        root_uri=ROOT.as_uri()))
    yield
    await lsp_client.shutdown_session()


def _open(client: LanguageClient, uri: str, text: str) -> None:
    client.text_document_did_open(T.DidOpenTextDocumentParams(
        text_document=T.TextDocumentItem(uri=uri, language_id="afsm", version=1, text=text)))


async def _hover(client: LanguageClient, uri: str) -> float:
    """A hover's round trip (s)."""
    t = time.monotonic()
    hover = await client.text_document_hover_async(T.HoverParams(
        text_document=T.TextDocumentIdentifier(uri=uri), position=T.Position(line=2, character=12)))
    assert hover is not None and "N" in str(hover.contents)
    EVENTS.append(("hover", time.monotonic()))
    return time.monotonic() - t


@pytest.mark.asyncio
async def test_hover_is_answered_while_90000_warnings_come_back(client: LanguageClient) -> None:
    small, big = "file:///tmp/small_nb.afsm", "file:///tmp/big_nb.afsm"
    _open(client, small, SMALL)
    while small not in PUBLISHED:
        await asyncio.sleep(0.01)
    EVENTS.clear()
    _open(client, big, unused_constants())
    deadline = time.monotonic() + 600
    while big not in PUBLISHED:
        assert time.monotonic() < deadline, "no diagnostics for the big document"
        await _hover(client, small)
        await asyncio.sleep(0.02)
    await _hover(client, small)

    what = [w for w, _ in EVENTS]
    done = what.index(f"diagnostics {big}")
    assert "refresh" in what[:done], "the big document's parse came back before its checks"
    after_parse = what[what.index("refresh"):done]
    assert after_parse.count("hover") >= 3, what  # answered while the checks ran and returned
    assert what[-1] == "hover"

    (params,) = PUBLISHED[big]
    assert len(params.diagnostics) == MAX_SHOWN + 1
    assert {str(d.code) for d in params.diagnostics[:-1]} == {"W304"}
    note = params.diagnostics[-1]
    assert note.code == "N901" and note.severity == T.DiagnosticSeverity.Information
    count = unused_constants().count("const int")
    assert f"{count - MAX_SHOWN:,} more diagnostics are not shown" in note.message

    # the outline, and a hover sent behind it on the same pipe
    outline = asyncio.ensure_future(client.text_document_document_symbol_async(
        T.DocumentSymbolParams(text_document=T.TextDocumentIdentifier(uri=big))))
    await asyncio.sleep(0)  # sent first
    waited = await _hover(client, small)
    symbols = await outline
    assert waited < 1.5, waited  # an uncapped outline ahead of it held it for seconds
    assert symbols is not None and len(symbols) == MAX_SYMBOLS + 1
    assert [s.name for s in symbols[:3]] == ["A", "C0", "C1"]
    last = symbols[-1]
    assert isinstance(last, T.DocumentSymbol)
    assert last.name == f"{count + 1 - MAX_SYMBOLS:,} more declarations are not shown"
    # it stands at the first declaration left out, the constant C999
    assert last.selection_range.start.line == 2 + MAX_SYMBOLS - 1

    # workspace symbols: every name holds "C", the first MAX_SYMBOLS are given
    found = asyncio.ensure_future(client.workspace_symbol_async(T.WorkspaceSymbolParams(query="c")))
    await asyncio.sleep(0)
    waited = await _hover(client, small)
    symbols = await found
    assert waited < 1.5, waited
    assert symbols is not None and len(symbols) == MAX_SYMBOLS
    assert all("C" in s.name for s in symbols)
