"""Semantic tokens for the editor's current text (issue 50), through a real client
(pytest-lsp over stdio): a request sent right after `didOpen` or `didChange`, with no wait
for diagnostics, gets the tokens of that text; a client that supports it is asked to
refresh them once a parse ends (`workspace/semanticTokens/refresh`)."""

from __future__ import annotations

import asyncio
import sys
from pathlib import Path

import pytest
import pytest_lsp
from lsprotocol import types as T
from pytest_lsp import ClientServerConfig, LanguageClient

ROOT = Path(__file__).resolve().parents[2]
MODULE = pytest.mark.asyncio(loop_scope="module")
LEGEND: list[str] = []
REFRESHES: list[None] = []  # workspace/semanticTokens/refresh requests the client got

TEXT = """machine m;
const int T_GO = 2;
var t : [0..9] init 0 clamp;
mode Fly = 0 initial;
mode Done = 1 final;
action Go in Fly when t < 6 { t += T_GO; }
action Land in Fly when t >= 6 { goto Done; }
property done = P=? [ F mode == Done ];
"""


@pytest_lsp.fixture(scope="module", config=ClientServerConfig(
    server_command=[sys.executable, "-m", "afsmc.cli", "lsp"]))
async def client(lsp_client: LanguageClient):  # type: ignore[no-untyped-def]
    @lsp_client.feature(T.WORKSPACE_SEMANTIC_TOKENS_REFRESH)
    def _refresh(params: None) -> None:
        REFRESHES.append(params)

    result = await lsp_client.initialize_session(T.InitializeParams(
        capabilities=T.ClientCapabilities(workspace=T.WorkspaceClientCapabilities(
            semantic_tokens=T.SemanticTokensWorkspaceClientCapabilities(
                refresh_support=True))),
        root_uri=ROOT.as_uri()))
    assert result.capabilities.semantic_tokens_provider is not None
    LEGEND[:] = result.capabilities.semantic_tokens_provider.legend.token_types
    yield
    await lsp_client.shutdown_session()


async def tokens(client: LanguageClient, uri: str, text: str) -> dict[str, str]:
    """Each coloured word of `text` -> its token type, from one request."""
    result = await client.text_document_semantic_tokens_full_async(
        T.SemanticTokensParams(text_document=T.TextDocumentIdentifier(uri=uri)))
    assert result is not None
    lines, out, line, char = text.split("\n"), {}, 0, 0
    data = list(result.data)
    for i in range(0, len(data), 5):
        dl, dc, n, kind, _ = data[i:i + 5]
        line, char = line + dl, (char + dc if dl == 0 else dc)
        out[lines[line][char:char + n]] = LEGEND[kind]
    return out


@MODULE
async def test_tokens_right_after_did_open(client: LanguageClient) -> None:
    uri = (ROOT / "examples" / "tokens_now_open.afsm").as_uri()
    client.text_document_did_open(T.DidOpenTextDocumentParams(
        text_document=T.TextDocumentItem(uri=uri, language_id="afsm", version=1, text=TEXT)))
    got = await tokens(client, uri, TEXT)  # no wait for the diagnostics
    assert {k: got.get(k) for k in ("Fly", "Go", "T_GO", "t", "done")} == {
        "Fly": "enumMember", "Go": "method", "T_GO": "constant", "t": "variable",
        "done": "property"}, got


@MODULE
async def test_tokens_right_after_did_change_are_those_of_the_new_text(
        client: LanguageClient) -> None:
    uri = (ROOT / "examples" / "tokens_now_change.afsm").as_uri()
    client.text_document_did_open(T.DidOpenTextDocumentParams(
        text_document=T.TextDocumentItem(uri=uri, language_id="afsm", version=1, text=TEXT)))
    await tokens(client, uri, TEXT)
    for version in range(2, 6):  # several quick changes, then one request
        new = TEXT.replace("T_GO", f"T_STEP{version}").replace("mode Done", "mode Done")
        new = new.replace("property done", f"label arrived{version} = mode == Done;\n"
                                           "property done")
        client.text_document_did_change(T.DidChangeTextDocumentParams(
            text_document=T.VersionedTextDocumentIdentifier(uri=uri, version=version),
            content_changes=[T.TextDocumentContentChangeWholeDocument(text=new)]))
    got = await tokens(client, uri, new)
    assert got.get("T_STEP5") == "constant" and got.get("arrived5") == "label", got
    assert "T_GO" not in got and "arrived4" not in got


@MODULE
async def test_a_client_with_refresh_support_is_asked_to_refresh(client: LanguageClient) -> None:
    uri = (ROOT / "examples" / "tokens_now_refresh.afsm").as_uri()
    before = len(REFRESHES)
    client.text_document_did_open(T.DidOpenTextDocumentParams(
        text_document=T.TextDocumentItem(uri=uri, language_id="afsm", version=1, text=TEXT)))
    for _ in range(200):  # up to 10 s for the parse and the request
        if len(REFRESHES) > before:
            break
        await asyncio.sleep(0.05)
    assert len(REFRESHES) > before
