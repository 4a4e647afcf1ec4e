"""End-to-end tests of `afsmc lsp`: a real LSP client (pytest-lsp) drives the server in a
subprocess (`python -m afsmc.cli lsp`, i.e. what `afsmc lsp` runs) over stdio.

One server serves the whole module (starting it costs about a second). Expected positions
are found in the text with plain string searches, not taken from the compiler.
"""

from __future__ import annotations

import re
import shutil
import subprocess
import sys
from pathlib import Path
from typing import Any

import pytest
import pytest_lsp
from lsprotocol import types as T
from pygls.exceptions import JsonRpcException
from pytest_lsp import ClientServerConfig, LanguageClient

from afsmc.compiler import load
from afsmc.syntax.fmt import format_text

ROOT = Path(__file__).resolve().parents[2]
UAV = ROOT / "examples" / "uav.afsm"
VSCODE = ROOT / "editors" / "vscode"

pytestmark = pytest.mark.skipif(not UAV.exists(), reason="examples/uav.afsm is not there yet")

MODULE = pytest.mark.asyncio(loop_scope="module")


@pytest_lsp.fixture(scope="module", config=ClientServerConfig(
    server_command=[sys.executable, "-m", "afsmc.cli", "lsp"]))
async def client(lsp_client: LanguageClient):  # type: ignore[no-untyped-def]
    await lsp_client.initialize_session(T.InitializeParams(
        capabilities=T.ClientCapabilities(), root_uri=ROOT.as_uri()))
    _record(lsp_client)
    yield
    await lsp_client.shutdown_session()


# ---- helpers ------------------------------------------------------------------------


def offset(text: str, pos: T.Position) -> int:  # the test texts are ASCII: UTF-16 = chars
    lines = text.split("\n")
    return sum(len(x) + 1 for x in lines[:pos.line]) + pos.character


def position(text: str, off: int) -> T.Position:
    line = text.count("\n", 0, off)
    return T.Position(line=line, character=off - (text.rfind("\n", 0, off) + 1))


def apply(text: str, edits: list[T.TextEdit]) -> str:
    for e in sorted(edits, key=lambda e: offset(text, e.range.start), reverse=True):
        text = text[:offset(text, e.range.start)] + e.new_text + text[offset(text, e.range.end):]
    return text


def slice_of(text: str, rng: T.Range) -> str:
    return text[offset(text, rng.start):offset(text, rng.end)]


def code_only(text: str) -> str:
    """The text with comments blanked out (offsets kept)."""
    return re.sub(r"//[^\n]*|/\*[\s\S]*?\*/", lambda m: " " * len(m.group()), text)


_version = 1


_published: dict[tuple[str, int | None], list[T.Diagnostic]] = {}


def _record(client: LanguageClient) -> None:
    """Keep the first diagnostics published for each version of each document (a document
    gets one publish per stage that has something to say; another document's late publish
    must not be taken for this one's)."""
    default = client.protocol.fm.features[T.TEXT_DOCUMENT_PUBLISH_DIAGNOSTICS]

    def publish(params: T.PublishDiagnosticsParams) -> None:
        _published.setdefault((params.uri, params.version), list(params.diagnostics))
        default(params)

    client.protocol.fm.features[T.TEXT_DOCUMENT_PUBLISH_DIAGNOSTICS] = publish


async def _first_publish(client: LanguageClient, uri: str) -> list[T.Diagnostic]:
    while (uri, _version) not in _published:
        await client.wait_for_notification("textDocument/publishDiagnostics")
    return _published[(uri, _version)]


async def open_doc(client: LanguageClient, uri: str, text: str) -> list[T.Diagnostic]:
    global _version
    _version += 1
    _published.pop((uri, _version), None)
    client.text_document_did_open(T.DidOpenTextDocumentParams(
        text_document=T.TextDocumentItem(uri=uri, language_id="afsm", version=_version, text=text)))
    return await _first_publish(client, uri)


async def change(client: LanguageClient, uri: str, text: str) -> list[T.Diagnostic]:
    global _version
    _version += 1
    _published.pop((uri, _version), None)
    client.text_document_did_change(T.DidChangeTextDocumentParams(
        text_document=T.VersionedTextDocumentIdentifier(uri=uri, version=_version),
        content_changes=[T.TextDocumentContentChangeWholeDocument(text=text)]))
    return await _first_publish(client, uri)


async def hover_at(client: LanguageClient, doc: T.TextDocumentIdentifier,
                   pos: T.Position) -> T.Hover | None:
    return await client.text_document_hover_async(T.HoverParams(text_document=doc, position=pos))


# ---- the tests ----------------------------------------------------------------------


@pytest.mark.slow
@MODULE
async def test_weight_tie_diagnostic_with_witness(client: LanguageClient) -> None:
    text = UAV.read_text()
    uri = (ROOT / "examples" / "tie_uav.afsm").as_uri()
    assert [d for d in await open_doc(client, uri, text)
            if d.severity == T.DiagnosticSeverity.Error] == []

    # HeadHome's weight 0.5 becomes 0.9: it ties with Resume's (battery_ok ? 0.9 : 0.1)
    # whenever the battery is fine and an object is left.
    head = "action HeadHome in AscendFromDeposit weight 0.5 {"
    assert head in text
    tied = text.replace(head, head.replace("0.5", "0.9"))
    diags = await change(client, uri, tied)
    ties = [d for d in diags if d.code == "E301"]
    assert len(ties) == 1, diags
    tie = ties[0]
    assert tie.severity == T.DiagnosticSeverity.Error
    assert slice_of(tied, tie.range).strip("()") == "battery_ok ? 0.9 : 0.1"
    assert "Resume" in tie.message and "HeadHome" in tie.message
    # the witness is a state where both weights are 0.9: an object left, battery above B_LOW
    wit = dict(re.findall(r"(\w+) = (\w+)", tie.message.split("in the state", 1)[1]))
    b_low = int(re.search(r"param int B_LOW\s*=\s*(\d+)", text).group(1))  # type: ignore[union-attr]
    assert wit["mode"] == "AscendFromDeposit"
    assert int(wit["obj"]) > 0 and int(wit["b"]) > b_low
    assert tie.related_information is not None
    (rel,) = tie.related_information
    assert rel.location.uri == uri
    assert slice_of(tied, rel.location.range) == "0.9"
    assert rel.location.range.start.line == text[:text.index(head)].count("\n")

    # fixing it clears the error
    assert [d for d in await change(client, uri, text) if d.code == "E301"] == []


@MODULE
async def test_half_typed_file_gives_a_syntax_diagnostic_and_keeps_navigation(
        client: LanguageClient) -> None:
    text = UAV.read_text()
    uri = (ROOT / "examples" / "half_uav.afsm").as_uri()
    await open_doc(client, uri, text)
    cut = text.index("action Descend in DescendToGrab")
    half = text[:cut] + "action Descend in Desc"  # typing stopped mid-declaration
    diags = await change(client, uri, half)
    assert diags and all(d.code.startswith("E1") for d in diags)  # type: ignore[union-attr]
    # still alive, and hover works from the last good parse
    use = code_only(text).index("T_MOVE", text.index("action Search in Search"))
    hover = await client.text_document_hover_async(T.HoverParams(
        text_document=T.TextDocumentIdentifier(uri=uri), position=position(text, use + 1)))
    assert hover is not None and "uav.search.duration" in str(hover.contents)


@pytest.mark.slow
@MODULE
async def test_completion_in_a_file_that_has_never_parsed(client: LanguageClient) -> None:
    """No last good parse to take the names from: they come from the text with the line
    being typed left out (it once offered only keywords and functions, whatever the place)."""
    text = UAV.read_text()
    modes = set(re.findall(r"^mode (\w+)", text, re.M))
    actions = set(re.findall(r"^(?:action|hazard) (\w+)", text, re.M))
    labels = set(re.findall(r"^label (\w+)", text, re.M))
    assert modes and actions and labels

    async def complete(uri: str, typed: str, at: int | None = None) -> set[str]:
        broken = text + "\n" + typed if at is None else text[:at] + typed + "\n" + text[at:]
        diags = await open_doc(client, uri, broken)
        assert diags and all(d.code.startswith("E1") for d in diags)  # type: ignore[union-attr]
        cursor = len(broken) if at is None else at + len(typed)
        items = await client.text_document_completion_async(T.CompletionParams(
            text_document=T.TextDocumentIdentifier(uri=uri), position=position(broken, cursor)))
        assert isinstance(items, T.CompletionList)
        return {i.label for i in items.items}

    # at the end of the file, and in the middle (the syntax error is then on the next line)
    base = (ROOT / "examples" / "never_uav").as_posix()
    assert await complete(f"file://{base}1.afsm", "action Zz in Search { goto ") == modes
    middle = text.index("action Carry in")
    assert await complete(f"file://{base}2.afsm", "action Zz in Search { goto ", middle) == modes
    assert await complete(f"file://{base}3.afsm", "action Zz in ") == modes
    assert await complete(f"file://{base}4.afsm", "action Zz in Search weight w(") == actions
    assert await complete(f"file://{base}5.afsm", 'property q = P=? [ F "') == labels
    # a block left open over several lines: the whole declaration is left out
    assert await complete(f"file://{base}6.afsm", "action Zz in Search {\n    goto ") == modes
    # anywhere else: every name in scope too, not only keywords and functions
    names = await complete(f"file://{base}7.afsm", "formula f = b + ")
    assert modes <= names and {"b", "T_MOVE", "B_LOW", "min"} <= names
    # a second error elsewhere: that declaration is left out as well
    damaged = text.replace("mode Search", "mode Search = ;", 1)
    assert damaged != text
    uri = f"file://{base}8.afsm"
    broken = damaged + "\naction Zz in Search { goto "
    await open_doc(client, uri, broken)
    items = await client.text_document_completion_async(T.CompletionParams(
        text_document=T.TextDocumentIdentifier(uri=uri), position=position(broken, len(broken))))
    assert isinstance(items, T.CompletionList)
    assert {i.label for i in items.items} == modes  # Search from a scan of the broken line


@MODULE
async def test_hover_definition_references(client: LanguageClient) -> None:
    text = UAV.read_text()
    code = code_only(text)
    uri = (ROOT / "examples" / "nav_uav.afsm").as_uri()
    await open_doc(client, uri, text)
    doc = T.TextDocumentIdentifier(uri=uri)

    # a constant: its interval and its simulation source
    decl = re.search(r"const int T_MOVE\s*=\s*\[(\d+), (\d+)\]\s*from sim ([\w.]+)", text)
    assert decl is not None
    use = code.index("T_MOVE", text.index("action Search in Search"))
    hover = await hover_at(client, doc, position(text, use))
    assert hover is not None
    shown = hover.contents.value  # type: ignore[union-attr]
    assert f"{decl.group(1)} to {decl.group(2)}" in shown and decl.group(3) in shown

    # a mode: its number
    num = re.search(r"mode Transport\s*=\s*(\d+)", text)
    assert num is not None
    goto = code.index("goto Transport") + len("goto ")
    hover = await hover_at(client, doc, position(text, goto))
    assert hover is not None and f"mode number {num.group(1)}" in hover.contents.value  # type: ignore[union-attr]

    # an action: its modes, guard and weight
    at = code.index("action Carry in") + len("action ")
    hover = await hover_at(client, doc, position(text, at))
    assert hover is not None
    shown = hover.contents.value  # type: ignore[union-attr]
    assert "modes: Transport" in shown and "guard: `to_base > 0`" in shown and "battery_ok" in shown

    # a variable: range and initial value
    at = code.index("b -= B_MOVE")
    hover = await hover_at(client, doc, position(text, at))
    assert hover is not None and "initially" in hover.contents.value  # type: ignore[union-attr]

    # go to definition: from `goto Transport` to `mode Transport`
    loc = await client.text_document_definition_async(T.DefinitionParams(
        text_document=doc, position=position(text, goto)))
    assert isinstance(loc, T.Location)
    assert loc.range.start == position(text, num.start() + len("mode "))

    # references of the mode Transport: every use outside comments
    refs = await client.text_document_references_async(T.ReferenceParams(
        text_document=doc, position=position(text, goto),
        context=T.ReferenceContext(include_declaration=True)))
    assert refs is not None
    expected = [m.start() for m in re.finditer(r"\bTransport\b", code)]
    assert sorted(offset(text, r.range.start) for r in refs) == expected

    # document outline: modes, actions and properties are there
    symbols = await client.text_document_document_symbol_async(T.DocumentSymbolParams(
        text_document=doc))
    names = {s.name for s in symbols or []}
    assert {"Transport", "Carry", "Emergency", "success", "T_MOVE", "pos"} <= names

    # completion after `goto `: the modes
    line_end = code.index("goto Transport")
    items = await client.text_document_completion_async(T.CompletionParams(
        text_document=doc, position=position(text, line_end + len("goto "))))
    assert isinstance(items, T.CompletionList)
    modes = set(re.findall(r"^mode (\w+)", text, re.M))
    assert {i.label for i in items.items} == modes


@pytest.mark.slow
@MODULE
async def test_formatting_and_rename_round_trip(client: LanguageClient) -> None:
    text = UAV.read_text()
    uri = (ROOT / "examples" / "edit_uav.afsm").as_uri()
    doc = T.TextDocumentIdentifier(uri=uri)
    messy = text.replace("action Fly in Return {", "action   Fly in Return{").replace(
        "goto Idle, t += T_LAND", "goto Idle,t+=T_LAND")
    assert messy != text
    await open_doc(client, uri, messy)
    edits = await client.text_document_formatting_async(T.DocumentFormattingParams(
        text_document=doc, options=T.FormattingOptions(tab_size=4, insert_spaces=True)))
    assert edits
    formatted = apply(messy, edits)
    assert formatted == format_text(text)

    # rename the mode Transport everywhere; the machine is the same, with the new name
    await change(client, uri, formatted)
    at = code_only(formatted).index("goto Transport") + len("goto ")
    edit = await client.text_document_rename_async(T.RenameParams(
        text_document=doc, position=position(formatted, at), new_name="Carrying"))
    assert edit is not None and edit.changes is not None
    renamed = apply(formatted, edit.changes[uri])
    assert not re.search(r"\bTransport\b", code_only(renamed))
    before = load("x.afsm", text=formatted, run_checks=False).model
    after = load("x.afsm", text=renamed, run_checks=False).model
    assert after.mode("Carrying").number == before.mode("Transport").number
    assert len(after.actions) == len(before.actions)


SMALL = """machine small;
var b : [0..3] init 3;
var pos : (x: [0..1], y: [0..1]) init (0, 0);
mode A = 0 initial;
mode B = 1 final;
action Step in A when b > 0 weight 0.5 {
    b -= 1, pos.x := 1;
}
action Done in A when b == 0 {
    goto B;
}
label done = mode == B && pos.y == 0;
property p = P=? [ F "done" ];
"""


async def refused(request: Any) -> JsonRpcException:
    """The error a request was answered with: LSP's RequestFailed, a message for people."""
    with pytest.raises(JsonRpcException) as info:
        await request
    err = info.value
    assert err.code == T.LSPErrorCodes.RequestFailed, (err.code, err.message, err.data)
    assert err.data is None and "Traceback" not in err.message
    return err


@MODULE
async def test_rename_refusals_are_request_failures_with_reasons(client: LanguageClient) -> None:
    uri = (ROOT / "examples" / "rename_small.afsm").as_uri()
    doc = T.TextDocumentIdentifier(uri=uri)
    await open_doc(client, uri, SMALL)
    step = position(SMALL, SMALL.index("Step"))

    rng = await client.text_document_prepare_rename_async(T.PrepareRenameParams(
        text_document=doc, position=step))
    assert isinstance(rng, T.Range) and slice_of(SMALL, rng) == "Step"

    def rename_to(name: str) -> Any:
        return client.text_document_rename_async(T.RenameParams(
            text_document=doc, position=step, new_name=name))

    err = await refused(rename_to("Done"))
    assert err.message == ("cannot rename action 'Step' to 'Done': 'Done' is already declared "
                           "(as an action)")
    # names the checker rejects (E202), in its words
    err = await refused(rename_to("S"))
    assert "'S' cannot name an action: it is reserved in PRISM or Storm" in err.message
    err = await refused(rename_to("__afsmc_step"))
    assert "reserved for Storm and afsmc" in err.message
    err = await refused(rename_to("goto"))
    assert "'goto' is not a name that can be declared" in err.message
    at_label = position(SMALL, SMALL.index("done ="))
    err = await refused(client.text_document_rename_async(T.RenameParams(
        text_document=doc, position=at_label, new_name="S")))
    assert "'S' cannot name a label" in err.message
    # a mode may be called S (modes become numbers): only what the checker rejects is refused
    at_mode = position(SMALL, SMALL.index("mode B") + len("mode "))
    edit = await client.text_document_rename_async(T.RenameParams(
        text_document=doc, position=at_mode, new_name="S"))
    assert edit is not None and edit.changes is not None
    assert "goto S;" in apply(SMALL, edit.changes[uri])

    # prepareRename refuses, with the reason, what it can tell at once
    field = position(SMALL, SMALL.index("pos.x") + len("pos."))
    err = await refused(client.text_document_prepare_rename_async(T.PrepareRenameParams(
        text_document=doc, position=field)))
    assert "fields cannot be renamed" in err.message
    assert await client.text_document_prepare_rename_async(T.PrepareRenameParams(
        text_document=doc, position=position(SMALL, SMALL.index("weight") + 2))) is None

    # and the server goes on: a good rename still works
    edit = await rename_to("Walk")
    assert edit is not None and edit.changes is not None
    renamed = apply(SMALL, edit.changes[uri])
    assert "action Walk in A" in renamed and "Step" not in renamed

    # while the file does not parse, renaming is refused with the reason
    await change(client, uri, SMALL.replace("action Done in A", "action Done in"))
    err = await refused(client.text_document_prepare_rename_async(T.PrepareRenameParams(
        text_document=doc, position=step)))
    assert "does not parse" in err.message
    await refused(rename_to("Walk"))


@pytest.mark.slow
def test_vscode_grammar() -> None:
    """The TextMate grammar's tests (editors/vscode: `npm test`), when node and npm are here."""
    npm = shutil.which("npm")
    if npm is None or shutil.which("node") is None:
        pytest.skip("node/npm are not installed")
    if not (VSCODE / "node_modules").exists():
        ci = subprocess.run([npm, "ci", "--no-audit", "--no-fund"], cwd=VSCODE,
                            capture_output=True, text=True, timeout=300)
        if ci.returncode != 0:
            pytest.skip(f"npm ci failed (offline?): {ci.stderr[-300:]}")
    run = subprocess.run([npm, "test"], cwd=VSCODE, capture_output=True, text=True, timeout=300)
    assert run.returncode == 0, run.stdout[-3000:] + run.stderr[-3000:]


@pytest.mark.slow
@MODULE
async def test_a_2000_term_expression_gets_diagnostics_not_a_crash(client: LanguageClient) -> None:
    # afsmc lsp runs in afsmc.stack's deep thread, as every command does
    chain = " +\n    ".join(["x * 0.00005"] * 2000)
    text = (f"machine long;\nvar x : [0..3] init 0;\nmode S = 0 initial;\nmode D = 1 final;\n"
            f"action Go in S weight ({chain}) {{ 0.5: goto D; 0.5: x := min(x + 1, 3); }}\n"
            f"action Stay in S weight ({chain}) {{ skip; }}\n")
    diags = await open_doc(client, "file:///tmp/long2000.afsm", text)
    assert [d.code for d in diags] == ["E301"], diags  # the two weights tie; no E999


@MODULE
async def test_positions_count_lines_at_newlines_only(client: LanguageClient) -> None:
    """Positions: an empty document gets its diagnostics replaced (the handler must not
    crash on pygls's position of an offset); a form feed or U+2028 in a comment moves no
    diagnostic a line down; the end of a last line without a newline stays on a line the
    document has."""
    uri = "file:///tmp/positions.afsm"
    broken = "machine t;\nvar x : [0..2] init 0\n"
    assert [d.code for d in await open_doc(client, uri, broken)] == ["E102"]
    empty = await change(client, uri, "")
    assert [d.code for d in empty] == ["E213"], empty  # replaced, as `afsmc check` says
    assert empty[0].range.start == T.Position(line=0, character=0)

    text = ("machine t;\n// a\x0cb\u2028c\nvar x : [0..1] init 0;\nmode A initial;\n"
            "mode B final;\naction Go in A when y == 0 {\n    goto B;\n}\n")
    (undefined,) = [d for d in await change(client, uri, text) if d.code == "E203"]
    assert undefined.range.start == position(text, text.index("y == 0"))
    assert slice_of(text, undefined.range) == "y"

    cut = "machine t;\nmode A initial;\naction Go in A {"  # no newline at the end
    lines = cut.split("\n")
    for d in await change(client, uri, cut):
        for p in (d.range.start, d.range.end):
            assert p.line < len(lines) and p.character <= len(lines[p.line]), d


def _session(*messages: dict[str, Any]) -> tuple[int, list[dict[str, Any]]]:
    """Run `afsmc lsp` on these messages (after initialize); its exit code and replies."""
    import json

    def frame(obj: dict[str, Any]) -> bytes:
        body = json.dumps(obj).encode()
        return b"Content-Length: %d\r\n\r\n" % len(body) + body

    start = [{"jsonrpc": "2.0", "id": 1, "method": "initialize", "params": {"capabilities": {}}},
             {"jsonrpc": "2.0", "method": "initialized", "params": {}}]
    p = subprocess.run([sys.executable, "-m", "afsmc.cli", "lsp"],
                       input=b"".join(frame(m) for m in (*start, *messages)),
                       capture_output=True, timeout=60)
    replies = [json.loads(part[part.index(b"{"):])
               for part in p.stdout.split(b"Content-Length")[1:]]
    return p.returncode, replies


@pytest.mark.slow
def test_exit_code_follows_shutdown() -> None:
    """LSP: `exit` after `shutdown` is 0, without it 1. It was always 0."""
    shutdown = {"jsonrpc": "2.0", "id": 2, "method": "shutdown"}
    exit_ = {"jsonrpc": "2.0", "method": "exit"}
    assert _session(exit_)[0] == 1
    assert _session(shutdown, exit_)[0] == 0


@pytest.mark.slow
def test_a_request_with_bad_params_gets_an_error_reply() -> None:
    """pygls only logged it, so a client waiting for the reply hung."""
    code, replies = _session(
        {"jsonrpc": "2.0", "id": 7, "method": "textDocument/hover",
         "params": {"textDocument": {"uri": "file:///x.afsm"},
                    "position": {"line": -1, "character": 0}}},
        {"jsonrpc": "2.0", "id": 8, "method": "textDocument/hover"},
        {"jsonrpc": "2.0", "id": 2, "method": "shutdown"}, {"jsonrpc": "2.0", "method": "exit"})
    errors = {r["id"]: r["error"]["code"] for r in replies if "error" in r}
    assert errors == {7: -32602, 8: -32602} and code == 0
    assert not [r for r in replies if r.get("method") == "window/showMessage"]  # no pop-up too


@MODULE
async def test_navigation_after_a_syntax_error_follows_the_editor_s_text(
        client: LanguageClient) -> None:
    """After an edit that does not parse, hover, definition, references and the outline
    come from the last good parse mapped through the lines both texts share (a line inserted
    on top must not make hover on `Dock` answer `Finished`), and say nothing about lines
    changed since; hover shows values only for the text that resolved (no old value of a
    constant beside its new declaration)."""
    text = (ROOT / "examples" / "patrol.afsm").read_text()
    uri = (ROOT / "examples" / "shifted_patrol.afsm").as_uri()
    doc = T.TextDocumentIdentifier(uri=uri)
    await open_doc(client, uri, text)
    edited = "var oops : ;\n" + text
    assert [d.code[:2] for d in await change(client, uri, edited)] == ["E1"]  # type: ignore[index]
    decl = edited.index("mode Dock") + len("mode ")
    hover = await hover_at(client, doc, position(edited, decl + 1))
    assert hover is not None and "Dock" in str(hover.contents), hover
    assert "Finished" not in str(hover.contents)
    assert hover.range is not None and slice_of(edited, hover.range) == "Dock"
    use = code_only(edited).index("goto Dock") + len("goto ")
    where = await client.text_document_definition_async(T.DefinitionParams(
        text_document=doc, position=position(edited, use)))
    assert isinstance(where, T.Location) and where.range.start == position(edited, decl)
    refs = await client.text_document_references_async(T.ReferenceParams(
        text_document=doc, position=position(edited, use),
        context=T.ReferenceContext(include_declaration=True)))
    assert refs and all(slice_of(edited, r.range) == "Dock" for r in refs)
    assert {offset(edited, r.range.start) for r in refs} == {
        m.start() for m in re.finditer(r"\bDock\b", code_only(edited))}
    symbols = await client.text_document_document_symbol_async(
        T.DocumentSymbolParams(text_document=doc))
    dock = [s for s in symbols if s.name == "Dock"]  # type: ignore[union-attr]
    assert dock and dock[0].selection_range.start == position(edited, decl)  # type: ignore[union-attr]
    assert not any(s.name == "oops" for s in symbols)  # type: ignore[union-attr]
    # the inserted line itself is not in the last good parse: nothing to say there
    assert await hover_at(client, doc, T.Position(line=0, character=5)) is None

    # a new value of CELLS with a name error elsewhere: hover gives no stale value
    text6 = text.replace("param int CELLS  = 4;", "param int CELLS  = 6;")
    broken = text6.replace("cell := at_end ? 0 : cell + 1", "cell := at_end ? 0 : cel + 1", 1)
    assert broken != text6
    assert "E203" in [d.code for d in await change(client, uri, broken)]
    at = broken.index("param int CELLS") + len("param int ")
    hover = await hover_at(client, doc, position(broken, at + 1))
    assert hover is not None and "CELLS" in str(hover.contents)
    assert "`4`" not in str(hover.contents), hover.contents
    await change(client, uri, text6)
    hover = await hover_at(client, doc, position(text6, at + 1))
    assert hover is not None and "`6`" in str(hover.contents), hover.contents


@MODULE
async def test_formatting_and_positions_keep_the_document_s_line_endings(
        client: LanguageClient) -> None:
    """Formatting keeps a CRLF document CRLF, as `afsmc fmt` does, formatted or not; a file
    with bare CR line endings has its diagnostics on their own lines (LSP counts '\\r' as a
    line end, as `afsmc check` does)."""
    text = format_text((ROOT / "examples" / "patrol.afsm").read_text())
    uri = "file:///tmp/crlf_patrol.afsm"
    doc = T.TextDocumentIdentifier(uri=uri)
    options = T.FormattingOptions(tab_size=4, insert_spaces=True)
    await open_doc(client, uri, text.replace("\n", "\r\n"))
    edits = await client.text_document_formatting_async(T.DocumentFormattingParams(
        text_document=doc, options=options))
    assert not edits and edits is not None
    messy = text.replace("mode Dock     = 1;", "mode   Dock=1;")
    assert messy != text
    await change(client, uri, messy.replace("\n", "\r\n"))
    edits = await client.text_document_formatting_async(T.DocumentFormattingParams(
        text_document=doc, options=options))
    assert edits and len(edits) == 1
    assert edits[0].new_text == text.replace("\n", "\r\n")

    cr = "machine m;\rvar x : [0..1] init 0;\rmode A initial;\rmode B final;\r" \
         "action Go in A when x == 0 { goto C; }\r"
    (bad,) = [d for d in await change(client, uri, cr) if d.code == "E215"]
    assert bad.range.start == T.Position(line=4, character=cr.split("\r")[4].index("C;"))
