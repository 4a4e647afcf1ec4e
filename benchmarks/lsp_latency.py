"""How long `afsmc lsp` takes to react to a change of examples/uav.afsm.

Drives the real server (`python -m afsmc.cli lsp`, a subprocess) with pygls's client and
measures, from sending `didChange` to receiving `publishDiagnostics`:

- a syntax error (published at once: parse only),
- a name error (published at once: parse + resolve),
- a weight tie (published after the debounce and the full semantic checks),

and from sending the fix to the first diagnostics without the error (a fixed syntax or name
error clears at once, before the checks run).

It also times the in-process stages, parse + resolve (what runs on every keystroke) and
the full checks (what runs once typing pauses), and the hover round trip, on its own and
while a 2 MB document is being analysed.

    .venv/bin/python benchmarks/lsp_latency.py [--repeat N]

With `--big RUNS`, only the hovers on a small document while a document of 90,000 unused
constants (2 MB, 90,000 warnings) is checked, in RUNS fresh servers, median and max of
each run (`--outline`: then while that document's outline is made and sent too;
`--edit`: then while it is changed and checked again); then,
for comparison, the same hovers with no big document, alone and beside two processes
that spin (what the machine itself adds).

    .venv/bin/python benchmarks/lsp_latency.py --big 3 --outline
"""

from __future__ import annotations

import argparse
import asyncio
import statistics
import subprocess
import sys
import time
from collections.abc import Callable
from pathlib import Path

from lsprotocol import types as T
from pygls.lsp.client import LanguageClient

ROOT = Path(__file__).resolve().parent.parent
UAV = ROOT / "examples" / "uav.afsm"


def stages(text: str, repeat: int) -> None:
    from afsmc.compiler import load
    from afsmc.lsp.analysis import analyse_fast

    fast, full = [], []
    for _ in range(repeat):
        t = time.perf_counter()
        analyse_fast(text, str(UAV))
        fast.append(time.perf_counter() - t)
        t = time.perf_counter()
        load(str(UAV), text=text)
        full.append(time.perf_counter() - t)
    print(f"in process: parse + resolve {_ms(fast)}, full check {_ms(full)}")


def _ms(xs: list[float]) -> str:
    return f"median {statistics.median(xs) * 1000:.0f} ms (max {max(xs) * 1000:.0f} ms)"


async def server(text: str, repeat: int) -> None:
    client = LanguageClient("afsmc-bench", "0")
    got: asyncio.Queue[T.PublishDiagnosticsParams] = asyncio.Queue()

    @client.feature(T.TEXT_DOCUMENT_PUBLISH_DIAGNOSTICS)
    def _diags(params: T.PublishDiagnosticsParams) -> None:
        got.put_nowait(params)

    await client.start_io(sys.executable, "-m", "afsmc.cli", "lsp")
    await client.initialize_async(T.InitializeParams(capabilities=T.ClientCapabilities()))
    client.initialized(T.InitializedParams())
    uri = UAV.as_uri()
    client.text_document_did_open(T.DidOpenTextDocumentParams(
        text_document=T.TextDocumentItem(uri=uri, language_id="afsm", version=0, text=text)))
    await got.get()

    head = "action HeadHome in AscendFromDeposit weight 0.5 {"
    variants = {
        "syntax error (immediate)": text.replace(head, head[:-2]),
        "name error (immediate)": text.replace("goto Land,", "goto Lnd,", 1),
        "weight tie (debounced full check)": text.replace(head, head.replace("0.5", "0.9")),
    }
    version = 0
    for name, changed in variants.items():
        times: dict[str, list[float]] = {"break": [], "fix": []}
        for _ in range(repeat):
            for what, body in (("break", changed), ("fix", text)):
                version += 1
                t = time.perf_counter()
                client.text_document_did_change(T.DidChangeTextDocumentParams(
                    text_document=T.VersionedTextDocumentIdentifier(uri=uri, version=version),
                    content_changes=[T.TextDocumentContentChangeWholeDocument(text=body)]))
                while (await got.get()).version != version:  # the first publish of it
                    pass
                times[what].append(time.perf_counter() - t)
        print(f"change -> diagnostics, {name}: {_ms(times['break'])}; "
              f"fixed -> cleared: {_ms(times['fix'])}")

    line = text[:text.index("T_MOVE,")].count("\n")
    col = len(text[:text.index("T_MOVE,")].rsplit("\n", 1)[-1])
    times = []
    for _ in range(repeat):
        t = time.perf_counter()
        await client.text_document_hover_async(T.HoverParams(
            text_document=T.TextDocumentIdentifier(uri=uri), position=T.Position(line, col)))
        times.append(time.perf_counter() - t)
    print(f"hover round trip: {_ms(times)}")

    # the same hover while a 2 MB document is being parsed and checked
    big = "machine big;\n" + "".join(f"const int C{i} = {i % 97};\n" for i in range(90_000))
    client.text_document_did_open(T.DidOpenTextDocumentParams(text_document=T.TextDocumentItem(
        uri=(ROOT / "big.afsm").as_uri(), language_id="afsm", version=0, text=big)))
    await asyncio.sleep(0.5)
    times = []
    for _ in range(repeat * 4):
        t = time.perf_counter()
        await client.text_document_hover_async(T.HoverParams(
            text_document=T.TextDocumentIdentifier(uri=uri), position=T.Position(line, col)))
        times.append(time.perf_counter() - t)
        await asyncio.sleep(0.05)
    print(f"hover round trip while a {len(big) / 1e6:.1f} MB document is checked: {_ms(times)}")
    await client.shutdown_async(None)
    client.exit(None)
    await client.stop()


SMALL = "machine m;\nconst int N = 3;\nvar x : [0..N] init 0;\nmode A initial final;\n"


async def _hovers_until(client: LanguageClient, uri: str, done: Callable[[], bool]
                        ) -> list[tuple[float, float]]:
    """Hover on `uri` every 20 ms until `done()`: when each was sent (s from the first)
    and its round trip (s)."""
    times: list[tuple[float, float]] = []
    start = time.perf_counter()
    while not done():
        t = time.perf_counter()
        await client.text_document_hover_async(T.HoverParams(
            text_document=T.TextDocumentIdentifier(uri=uri), position=T.Position(2, 12)))
        times.append((t - start, time.perf_counter() - t))
        await asyncio.sleep(0.02)
    return times


def _summary(times: list[tuple[float, float]], what: str = "hover") -> dict[str, float]:
    worst = max(times, key=lambda x: x[1])
    return {f"{what} median ms": statistics.median(x[1] for x in times) * 1000,
            f"{what} max ms": worst[1] * 1000, f"{what} max sent at s": worst[0]}


async def while_big_document(text: str, outline: bool = False, edit: bool = False
                             ) -> dict[str, float]:
    """Open `text` in a fresh server and hover on a small document until the big one's
    diagnostics arrive: the seconds to them, and the hover round trips meanwhile (ms).
    With `outline`, then ask for the big document's outline and hover until it comes: its
    seconds and symbols, and the hovers meanwhile. With `edit`, then change the big
    document (a constant added) and hover until its new diagnostics come (its older
    analysis is let go meanwhile)."""
    client = LanguageClient("afsmc-bench", "0")
    published: dict[str, float] = {}
    versions: dict[str, int | None] = {}

    @client.feature(T.TEXT_DOCUMENT_PUBLISH_DIAGNOSTICS)
    def _diags(params: T.PublishDiagnosticsParams) -> None:
        published.setdefault(params.uri, time.perf_counter())
        versions[params.uri] = params.version

    await client.start_io(sys.executable, "-m", "afsmc.cli", "lsp")
    await client.initialize_async(T.InitializeParams(capabilities=T.ClientCapabilities()))
    client.initialized(T.InitializedParams())
    small, big = "file:///tmp/bench_small.afsm", "file:///tmp/bench_big.afsm"
    for uri, body in ((small, SMALL), (big, text)):
        client.text_document_did_open(T.DidOpenTextDocumentParams(text_document=T.TextDocumentItem(
            uri=uri, language_id="afsm", version=1, text=body)))
        if uri == small:
            while small not in published:
                await asyncio.sleep(0.01)
    opened = time.perf_counter()
    times = await _hovers_until(client, small, lambda: big in published)
    out = {"to diagnostics s": published[big] - opened, **_summary(times)}
    if outline:
        t = time.perf_counter()
        request = asyncio.ensure_future(client.text_document_document_symbol_async(
            T.DocumentSymbolParams(text_document=T.TextDocumentIdentifier(uri=big))))
        times = await _hovers_until(client, small, request.done)
        out["outline s"] = time.perf_counter() - t
        out["outline symbols"] = float(len(request.result() or []))
        out.update(_summary(times, "hover during outline"))
    if edit:
        t = time.perf_counter()
        client.text_document_did_change(T.DidChangeTextDocumentParams(
            text_document=T.VersionedTextDocumentIdentifier(uri=big, version=2),
            content_changes=[T.TextDocumentContentChangeWholeDocument(
                text=text + "const int Z = 1;\n")]))
        times = await _hovers_until(client, small, lambda: versions.get(big) == 2)
        out["edit to diagnostics s"] = time.perf_counter() - t
        out.update(_summary(times, "hover after edit"))
    await client.shutdown_async(None)
    client.exit(None)
    await client.stop()
    return out


async def baseline(seconds: float, busy: int) -> dict[str, float]:
    """The hovers on a small document alone, for `seconds`, while `busy` processes of
    this machine spin (what a 2 MB document's child process and the decoding thread take
    of the CPU): what the machine itself adds to the round trips."""
    spinners = [subprocess.Popen([sys.executable, "-c", "while True: pass"])
                for _ in range(busy)]
    try:
        client = LanguageClient("afsmc-bench", "0")
        published: set[str] = set()

        @client.feature(T.TEXT_DOCUMENT_PUBLISH_DIAGNOSTICS)
        def _diags(params: T.PublishDiagnosticsParams) -> None:
            published.add(params.uri)

        await client.start_io(sys.executable, "-m", "afsmc.cli", "lsp")
        await client.initialize_async(T.InitializeParams(capabilities=T.ClientCapabilities()))
        client.initialized(T.InitializedParams())
        small = "file:///tmp/bench_small.afsm"
        client.text_document_did_open(T.DidOpenTextDocumentParams(text_document=T.TextDocumentItem(
            uri=small, language_id="afsm", version=1, text=SMALL)))
        while small not in published:
            await asyncio.sleep(0.01)
        end = time.perf_counter() + seconds
        times = await _hovers_until(client, small, lambda: time.perf_counter() > end)
        await client.shutdown_async(None)
        client.exit(None)
        await client.stop()
    finally:
        for p in spinners:
            p.kill()
            p.wait()
    return _summary(times)


def big_runs(runs: int, n: int, outline: bool, edit: bool) -> None:
    """`while_big_document` `runs` times on a document of `n` unused constants: each run's
    figures, and the worst of the hovers' maxima."""
    text = "machine big;\nmode A = 0 initial final;\n" + "".join(
        f"const int C{i} = {i % 97};\n" for i in range(n))
    worst: dict[str, float] = {}
    print(f"a document of {n:,} unused constants, {len(text):,} characters:")
    for i in range(runs):
        got = asyncio.run(while_big_document(text, outline, edit))
        print(f"run {i + 1}: " + ", ".join(f"{k} {v:,.1f}" for k, v in got.items()), flush=True)
        for k, v in got.items():
            if k.endswith("max ms"):
                worst[k] = max(worst.get(k, 0.0), v)
    print("worst over the runs: " + ", ".join(f"{k} {v:,.1f}" for k, v in worst.items()))
    for busy in (0, 2):
        got = asyncio.run(baseline(15, busy))
        print(f"no big document, {busy} busy processes, 15 s: "
              + ", ".join(f"{k} {v:,.1f}" for k, v in got.items()))


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawTextHelpFormatter)
    ap.add_argument("--repeat", type=int, default=5)
    ap.add_argument("--big", type=int, metavar="RUNS",
                    help="only hover while a 2 MB document is checked, RUNS times")
    ap.add_argument("--constants", type=int, default=90_000, help="the big document's size")
    ap.add_argument("--outline", action="store_true", help="with --big: then ask its outline")
    ap.add_argument("--edit", action="store_true", help="with --big: then change it")
    args = ap.parse_args()
    if args.big:
        big_runs(args.big, args.constants, args.outline, args.edit)
        return
    text = UAV.read_text()
    stages(text, args.repeat)
    asyncio.run(server(text, args.repeat))


if __name__ == "__main__":
    main()
