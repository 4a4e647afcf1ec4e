"""The language server's index without a parse: when no text parses, the declarations are
found by a lexical scan, which on uav.afsm finds what the parser finds."""

from __future__ import annotations

from tests.conftest import EXAMPLES

UAV = EXAMPLES / "uav.afsm"


def test_never_parsed_completion_falls_back_to_a_lexical_scan() -> None:
    """When no text parses even with broken declarations left out, the declarations are
    found by their look; on uav.afsm the scan finds exactly what the parser finds."""
    from afsmc.lsp import index as I
    from afsmc.syntax.parser import parse

    text = UAV.read_text()
    scanned = I.scan(text)
    parsed = I.build(parse(text, "uav.afsm"), text)
    assert {(k, d.kind) for k, d in scanned.defs.items()} == \
        {(k, d.kind) for k, d in parsed.defs.items()}
    garbage = "machine m; mode A = 0 initial; mode B; var t : (x: [0..2], y: bool);\n" \
              "// mode Commented;\n" + "{" * 20 + "\naction Go in "
    idx = I.recover(garbage, len(garbage), "g.afsm")
    assert [d.name for d in idx.names(I.VALUE, ("mode",))] == ["A", "B"]
    assert [d.name for d in idx.names(I.FIELD)] == ["t.x", "t.y"]


def test_completion_offers_the_aggregates_over_agent_families() -> None:
    """`count`, `all` and `any` (expanded over a family's members when names are resolved)
    are offered where an expression is typed, as functions, like `min` and `max`."""
    from lsprotocol import types as T

    from afsmc.lsp import index as I
    from afsmc.lsp.completion import completions
    from afsmc.syntax.parser import parse

    fleet = (EXAMPLES / "fleet.afsm").read_text()
    items = completions(I.build(parse(fleet, "fleet.afsm"), fleet), "label done = ")
    kinds = {i.label: i.kind for i in items}
    assert {kinds[f] for f in ("count", "all", "any", "min")} == {T.CompletionItemKind.Function}
    assert [i.label for i in items].count("count") == 1
