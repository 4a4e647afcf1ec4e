"""End-to-end tests of the language server's editing help (a real client, pytest-lsp, over
stdio): quick fixes, semantic tokens, folding, workspace symbols, inlay hints, signature
help and range formatting. Expected positions come from plain string searches of the text.
"""

from __future__ import annotations

import re
import sys
from pathlib import Path

import pytest
import pytest_lsp
from lsprotocol import types as T
from pytest_lsp import ClientServerConfig, LanguageClient

from afsmc.lsp.analysis import analyse_full
from afsmc.lsp.index import KEYWORDS
from afsmc.syntax.fmt import format_text

ROOT = Path(__file__).resolve().parents[2]
UAV = ROOT / "examples" / "uav.afsm"
CASES = ROOT / "tests" / "golden" / "cases"
MODULE = pytest.mark.asyncio(loop_scope="module")
LEGEND: list[str] = []  # the server's semantic token types


@pytest_lsp.fixture(scope="module", config=ClientServerConfig(
    server_command=[sys.executable, "-m", "afsmc.cli", "lsp"]))
async def client(lsp_client: LanguageClient):  # type: ignore[no-untyped-def]
    result = await lsp_client.initialize_session(T.InitializeParams(
        capabilities=T.ClientCapabilities(), root_uri=ROOT.as_uri()))
    LEGEND[:] = result.capabilities.semantic_tokens_provider.legend.token_types
    yield
    await lsp_client.shutdown_session()


def offset(text: str, pos: T.Position) -> int:  # the test texts are ASCII: UTF-16 = chars
    lines = text.split("\n")
    return sum(len(x) + 1 for x in lines[:pos.line]) + pos.character


def position(text: str, off: int) -> T.Position:
    return T.Position(line=text.count("\n", 0, off),
                      character=off - (text.rfind("\n", 0, off) + 1))


def apply(text: str, edits: list[T.TextEdit]) -> str:
    for e in sorted(edits, key=lambda e: offset(text, e.range.start), reverse=True):
        text = text[:offset(text, e.range.start)] + e.new_text + text[offset(text, e.range.end):]
    return text


def doc(uri: str) -> T.TextDocumentIdentifier:
    return T.TextDocumentIdentifier(uri=uri)


async def open_doc(client: LanguageClient, uri: str, text: str) -> list[T.Diagnostic]:
    client.diagnostics.pop(uri, None)
    client.text_document_did_open(T.DidOpenTextDocumentParams(
        text_document=T.TextDocumentItem(uri=uri, language_id="afsm", version=1, text=text)))
    while uri not in client.diagnostics:  # the first publish of this document
        await client.wait_for_notification("textDocument/publishDiagnostics")
    return client.diagnostics[uri]


# Hints that name an edit: each of these cases gets a quick fix.
_EDIT_HINT = re.compile(r"hint: (add '|.*did you mean '|write '[^']+' (once|instead)|choose "
                        r"another name|rename the action|.*put a space after it|make the last "
                        r"outcome|write 'mode|write '\{ skip|write 'F<=|write 'mod\(|"
                        r"write '\w+ := \(|write 'x := \.\.\.'|close it with|"
                        r"write P>=\.\.\. without|round it with floor|.*with 'clamp'|"
                        r"afsm's boolean operators|found '='$)")


def _has_edit_hint(case: Path) -> bool:
    """Whether a diagnostic of the case's input.afsm has a hint that names an edit."""
    if not (case / "input.afsm").exists():
        return False
    in_file = False
    for line in (case / "expected.txt").read_text().splitlines():
        if re.match(r"\S+:\d+:\d+: \w+\[", line):
            in_file = line.startswith(f"tests/golden/cases/{case.name}/input.afsm:")
        elif in_file and _EDIT_HINT.search(line):
            return True
    return False


@MODULE
@pytest.mark.slow
async def test_quick_fixes_remove_their_diagnostic(client: LanguageClient) -> None:
    cases = sorted(c for c in CASES.glob("err_*") if _has_edit_hint(c))
    assert len(cases) >= 40
    fixed = 0
    for case in cases:
        text = (case / "input.afsm").read_text()
        uri = (case / "input.afsm").as_uri()
        diags = await open_doc(client, uri, text)
        offered = [d for d in diags if d.data]
        assert offered, case.name
        for d in offered:
            actions = await client.text_document_code_action_async(T.CodeActionParams(
                text_document=doc(uri), range=d.range,
                context=T.CodeActionContext(diagnostics=[d])))
            assert actions, (case.name, d.code)
            for a in actions:
                assert isinstance(a, T.CodeAction) and a.kind == T.CodeActionKind.QuickFix
                assert a.edit is not None and a.edit.changes is not None
                new = apply(text, list(a.edit.changes[uri]))
                after = analyse_full(new, str(case / "input.afsm"))
                left = [x for x in after if x.code == d.code
                        and x.message == d.message.split("\nhint:")[0]]
                if d.code != "E301":  # 1 - w(A) is offered; it still ties where w(A) = 0.5
                    assert left == [], (case.name, a.title)
                fixed += 1
        client.text_document_did_close(T.DidCloseTextDocumentParams(text_document=doc(uri)))
    assert fixed >= 50


def _decode(data: list[int], legend: list[str]) -> list[tuple[int, int, int, str]]:
    out, line, char = [], 0, 0
    for i in range(0, len(data), 5):
        dl, dc, n, kind, _ = data[i:i + 5]
        line, char = line + dl, (char + dc if dl == 0 else dc)
        out.append((line, char, n, legend[kind]))
    return out


@pytest.mark.slow
@MODULE
async def test_semantic_tokens_cover_every_identifier_of_uav(client: LanguageClient) -> None:
    text = UAV.read_text()
    uri = (ROOT / "examples" / "tokens_uav.afsm").as_uri()
    await open_doc(client, uri, text)
    result = await client.text_document_semantic_tokens_full_async(
        T.SemanticTokensParams(text_document=doc(uri)))
    assert result is not None
    tokens = _decode(list(result.data), LEGEND)
    starts = {offset(text, T.Position(line=a, character=b)): (n, k) for a, b, n, k in tokens}
    covered = {o + i for o, (n, _) in starts.items() for i in range(n)}
    code = re.sub(r"//[^\n]*|/\*[\s\S]*?\*/", lambda m: " " * len(m.group()), text)
    words = [m for m in re.finditer(r"[A-Za-z_]\w*", code) if m.group() not in KEYWORDS
             and m.group() not in ("sim", "from", "with")]
    assert len(words) > 300
    assert [m.group() for m in words if m.start() not in covered] == []

    def kind_of(pattern: str) -> str:
        m = re.search(pattern, text, re.M)
        assert m is not None, pattern
        return starts[m.start(1)][1]

    kinds = {
        "mode": kind_of(r"^mode (\w+)"), "action": kind_of(r"^action (\w+)"),
        "param": kind_of(r"^param int (\w+)"), "const": kind_of(r"^const int (\w+)\s*=\s*\d"),
        "interval": kind_of(r"^const int (\w+)\s*=\s*\["), "var": kind_of(r"^var (\w+)"),
        "label": kind_of(r"^label (\w+)"), "property": kind_of(r"^property (\w+)"),
        "rewards": kind_of(r"^rewards (\w+)"),
    }
    assert len(set(kinds.values())) == len(kinds), kinds


@MODULE
async def test_folding_workspace_symbols_inlay_hints(client: LanguageClient) -> None:
    text = UAV.read_text()
    uri = (ROOT / "examples" / "fold_uav.afsm").as_uri()
    other = (ROOT / "examples" / "other.afsm").as_uri()
    await open_doc(client, uri, text)
    await open_doc(client, other, "machine o;\nconst int ZETA_ONLY = 2;\nmode A initial final;\n")

    folds = await client.text_document_folding_range_async(
        T.FoldingRangeParams(text_document=doc(uri)))
    assert folds is not None
    head = len(re.match(r"(//[^\n]*\n)+", text).group().splitlines())  # type: ignore[union-attr]
    assert any(f.start_line == 0 and f.end_line == head - 1
               and f.kind == T.FoldingRangeKind.Comment for f in folds)
    act = text.index("action BatteryLow in Search")
    first = text.count("\n", 0, act)
    last = text.count("\n", 0, text.index("\n}", act) + 2)
    assert any(f.start_line == first and f.end_line == last for f in folds)

    syms = await client.workspace_symbol_async(T.WorkspaceSymbolParams(query="zeta"))
    assert [(s.name, s.location.uri) for s in syms or []] == [("ZETA_ONLY", other)]  # type: ignore[union-attr]
    syms = await client.workspace_symbol_async(T.WorkspaceSymbolParams(query="BatteryLow"))
    found = [s for s in syms or [] if s.location.uri == uri]  # type: ignore[union-attr]
    assert [s.name for s in found] == ["BatteryLow"]

    whole = T.Range(start=T.Position(line=0, character=0), end=position(text, len(text)))
    hints = await client.text_document_inlay_hint_async(
        T.InlayHintParams(text_document=doc(uri), range=whole))
    assert hints
    at = {offset(text, h.position): h.label for h in hints}
    # a param's value after its use; an interval after a use of T_TAKEOFF
    use = text.index("T_LIMIT", text.index("label timeout")) + len("T_LIMIT")
    assert at[use] == " = 150"
    use = text.index("t += T_TAKEOFF") + len("t += T_TAKEOFF")
    assert at[use] == " ∈ [10, 11]"
    # after w(Carry): Carry's weight, as written
    carry = re.search(r"action Carry in [^\n]*? weight ([^{]+?) \{", text)
    assert carry is not None
    w = text.index("w(Carry)") + len("w(Carry)")
    assert at[w] == " = " + carry.group(1).removeprefix("(").removesuffix(")")


@pytest.mark.slow
@MODULE
async def test_signature_help_and_range_formatting(client: LanguageClient) -> None:
    text = "machine s;\nconst int A = 1;\nformula f = max(A, floor(2.5), "
    uri = (ROOT / "examples" / "sig.afsm").as_uri()
    await open_doc(client, uri, text)
    help_ = await client.text_document_signature_help_async(T.SignatureHelpParams(
        text_document=doc(uri), position=position(text, len(text))))
    assert help_ is not None and help_.signatures[0].label == "max(a, b, ...)"
    assert help_.active_parameter == 2
    inner = text.index("2.5")
    help_ = await client.text_document_signature_help_async(T.SignatureHelpParams(
        text_document=doc(uri), position=position(text, inner)))
    assert help_ is not None and help_.signatures[0].label == "floor(x)"

    good = format_text(UAV.read_text(), str(UAV))
    a, b = "var t ", "label success "
    assert a in good and b in good
    messy = good.replace(a, "var    t ", 1).replace(b, "label    success ", 1)
    uri = (ROOT / "examples" / "range_uav.afsm").as_uri()
    await open_doc(client, uri, messy)
    line = messy[:messy.index("var    t ")].count("\n")
    edits = await client.text_document_range_formatting_async(T.DocumentRangeFormattingParams(
        text_document=doc(uri), range=T.Range(start=T.Position(line=line, character=0),
                                              end=T.Position(line=line, character=3)),
        options=T.FormattingOptions(tab_size=4, insert_spaces=True)))
    assert edits
    out = apply(messy, list(edits))
    assert "var t " in out and "label    success " in out  # only the range's line changed
    assert out == good.replace(b, "label    success ", 1)
