"""A document's diagnostics published by the language server: at most MAX_SHOWN, errors
before warnings before notes, in the order reported, and N901 counting the rest; and the
line index of a document is built once, whatever the number of positions converted, and
its client units are counted as pygls counts them (in C, not per character)."""

from __future__ import annotations

import json

import pytest
from lsprotocol import types as T
from pygls.workspace.position_codec import PositionCodec

from afsmc.diagnostics import Diagnostic, Severity, Source, Span, codes
from afsmc.lsp.documents import MAX_SHOWN, shown
from afsmc.lsp.positions import Doc, to_range

SRC = Source("m.afsm", "x\n" * 10)


def _diag(i: int, severity: Severity) -> Diagnostic:
    code = {Severity.ERROR: codes.E201, Severity.WARNING: codes.W304, Severity.NOTE: codes.N901}
    return Diagnostic(code[severity], severity, f"d{i}", Span(SRC, 0, 1, 1, 1))


def test_up_to_the_cap_every_diagnostic_is_shown_as_reported() -> None:
    diags = [_diag(i, Severity.WARNING) for i in range(MAX_SHOWN)]
    assert shown(diags) == diags


def test_beyond_the_cap_errors_come_first_and_n901_counts_the_rest() -> None:
    warnings = [_diag(i, Severity.WARNING) for i in range(MAX_SHOWN + 500)]
    errors = [_diag(-i, Severity.ERROR) for i in range(3)]
    diags = warnings[:700] + errors + warnings[700:]  # the errors come late in the list
    out = shown(diags)
    assert len(out) == MAX_SHOWN + 1
    kept, note = out[:-1], out[-1]
    assert set(errors) <= set(kept)  # no error is hidden behind the warnings
    assert kept == [d for d in diags if d in set(kept)]  # in the order reported
    assert kept[-1] is warnings[MAX_SHOWN - 3 - 1]
    assert note.code == "N901" and note.severity is Severity.NOTE
    assert "503 more diagnostics" in note.message and "503 warnings" in note.message


def test_positions_go_through_one_line_index() -> None:
    text = "".join(f"line {i}\r\n" if i % 3 else f"line {i}\n" for i in range(20_000))
    doc = Doc("file:///m.afsm", text)
    lines = doc.lines
    for off in range(0, len(text), 97):
        r = to_range(doc, off, off)
        assert text.count("\n", 0, off) == r.start.line
    assert doc.lines is lines  # not rebuilt per conversion


@pytest.mark.parametrize("encoding", list(T.PositionEncodingKind))
def test_client_units_are_pygls_s_at_c_speed(encoding: T.PositionEncodingKind) -> None:
    text = "machine m; // é\n  x = \"😋 ab\"\r\nüñî😋😋 z\rplain\n"
    codec = PositionCodec(encoding)
    doc = Doc("file:///m.afsm", text, position_codec=codec)
    for off in range(len(text) + 1):
        pos = doc.server_position_at_offset(off)
        assert doc.position_to_client_units(pos) == codec.position_to_client_units(doc.lines, pos)


def test_a_big_reply_is_encoded_item_by_item_to_the_same_json() -> None:
    from pygls.protocol.json_rpc import JsonRPCResponseMessage

    from afsmc.lsp.state import BIG_REPLY, AfsmServer

    proto = AfsmServer().protocol
    r = T.Range(start=T.Position(line=1, character=2), end=T.Position(line=1, character=5))
    symbols = [T.DocumentSymbol(name=f"C{i}", kind=T.SymbolKind.Constant, range=r,
                                selection_range=r, detail="constant")
               for i in range(BIG_REPLY + 1)]
    reply = JsonRPCResponseMessage(id=7, result=symbols, jsonrpc="2.0")
    whole = json.dumps(reply, default=proto._serialize_message)
    assert json.loads(proto._encode(reply)) == json.loads(whole)
