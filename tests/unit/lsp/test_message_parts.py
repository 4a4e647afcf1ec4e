"""A job's message crosses from the child process in parts (afsmc/lsp/transfer.py): what the
server decodes equals what the child sent, objects shared in it stay shared, and no part's
unpickler holds more than a bounded number of objects, whatever the document's size (one
unpickler for the parse of a big document holds millions, and lets them go in one step
that holds the interpreter's lock); a replaced analysis is let go whole."""

from __future__ import annotations

import io
import pickle

from afsmc.diagnostics import Diagnostic, Severity, codes
from afsmc.lsp import transfer
from afsmc.lsp.analysis import analyse_full
from afsmc.lsp.documents import FAST, FULL, MAX_SHOWN, _fast_stage, _full_stage
from afsmc.lsp.transfer import PART_ITEMS, Decoder, Failed, Parts


def unused_constants(n: int) -> str:
    return "machine big;\nmode A = 0 initial final;\n" + "".join(
        f"const int C{i} = {i % 97};\n" for i in range(n))


def _decode(parts: list[bytes]) -> object:
    decoder = Decoder()
    for data in parts[:-1]:
        decoder.part(data)
    return decoder.last(parts[-1])


def _memo_sizes(parts: list[bytes]) -> list[int]:
    """How many objects each part's unpickler keeps until it is freed."""
    decoder, sizes = Decoder(), []
    for i, data in enumerate(parts):
        unpickler = transfer._Unpickler(io.BytesIO(data), decoder)
        loaded = unpickler.load()
        if i < len(parts) - 1:
            decoder.table.extend(loaded)
        sizes.append(len(unpickler.memo.copy()))
    return sizes


def test_a_parse_comes_back_equal_with_its_shared_objects_shared() -> None:
    n = 3 * PART_ITEMS + 17
    sent = (FAST, _fast_stage(unused_constants(n), "/tmp/big.afsm"))
    parts = Parts().encode(sent)
    got = _decode(parts)
    assert got == sent
    _, (_, model, index) = got  # type: ignore[misc]
    assert model is not None and index is not None and len(model.constants) == n
    # a declaration is the module's and the index's: one object, sent once
    decl = index.defs[("value", "C5")].decl
    assert any(decl is d for d in index.module.decls)
    # the text, which every span refers to, is one object too
    assert len({id(d.span.source) for d in index.module.decls}) == 1
    assert model.source is index.module.decls[0].span.source


def test_no_part_keeps_more_objects_as_the_document_grows() -> None:
    small = Parts().encode((FAST, _fast_stage(unused_constants(2 * PART_ITEMS), "/tmp/a.afsm")))
    big = Parts().encode((FAST, _fast_stage(unused_constants(8 * PART_ITEMS), "/tmp/a.afsm")))
    assert len(big) > len(small) > 2
    # one constant is some 15 objects between its declaration, its definition and its IR
    assert max(_memo_sizes(small)) == max(_memo_sizes(big)) <= 20 * PART_ITEMS
    # as one pickle, the big document's unpickler keeps them all
    whole = pickle.Unpickler(io.BytesIO(pickle.dumps(_decode(big), protocol=5)))
    whole.load()
    assert len(whole.memo.copy()) > 8 * 20 * PART_ITEMS


def test_the_checks_send_only_the_diagnostics_shown() -> None:
    text = unused_constants(MAX_SHOWN + 5)
    diags, _ = _full_stage(text, "/tmp/w.afsm")
    assert len(diags) == MAX_SHOWN + 1 and diags[-1].code == "N901"
    assert "5 more diagnostics are not shown" in diags[-1].message


def test_many_diagnostics_come_back_in_order() -> None:
    text = unused_constants(2 * PART_ITEMS + 1)
    diags, seconds = analyse_full(text, "/tmp/w.afsm"), 1.5
    assert len(diags) == 2 * PART_ITEMS + 1 and {d.code for d in diags} == {"W304"}
    parts = Parts().encode((FULL, (diags, seconds)))
    assert len(parts) >= 5  # the text, three parts of diagnostics, the message
    assert _decode(parts) == (FULL, (diags, seconds))


def test_a_small_message_is_one_part() -> None:
    d = Diagnostic(codes.W304, Severity.WARNING, "unused", None)
    msg = ("ok", [d] * PART_ITEMS, {"k": (1, 2.5)})
    parts = Parts().encode(msg)
    assert len(parts) == 1
    assert _decode(parts) == msg


def test_a_part_that_does_not_decode_fails_its_message_only() -> None:
    parts = Parts().encode(("ok", list(range(3 * PART_ITEMS))))
    decoder = Decoder()
    decoder.part(b"not a pickle")
    for data in parts[1:-1]:
        decoder.part(data)
    failed = decoder.last(parts[-1])
    assert isinstance(failed, Failed) and "UnpicklingError" in failed.trace
    assert decoder.table == []
    # the next message of the same job decodes
    assert _decode(Parts().encode(("ok", [1, 2]))) == ("ok", [1, 2])
    for data in parts[:-1]:
        decoder.part(data)
    assert decoder.last(parts[-1]) == ("ok", list(range(3 * PART_ITEMS)))


def test_let_go_frees_a_replaced_analysis_whole() -> None:
    import gc
    import weakref

    sent = (FAST, _fast_stage(unused_constants(3 * PART_ITEMS), "/tmp/old.afsm"))
    got = _decode(Parts().encode(sent))
    _, (_, model, index) = got  # type: ignore[misc]
    refs = [weakref.ref(x) for x in (model, index, index.module, index.module.decls[-1],
                                     index.defs[("value", "C7")], model.constants[-1])]
    held = [index, model]
    del got, model, index
    gc.collect()
    assert all(r() is not None for r in refs)  # held only by `held`
    transfer.let_go(held)
    assert held == [] and [r() for r in refs] == [None] * len(refs)
