"""docs/diagnostics.md is what scripts/gen_diagnostics_doc.py writes from the registry and
the explanation files."""

from __future__ import annotations

from afsmc.diagnostics.codes import REGISTRY
from afsmc.diagnostics.docs import DOC_PATH, REGENERATE, page
from tests.conftest import ROOT


def test_the_page_is_current() -> None:
    current = (ROOT / DOC_PATH).read_text(encoding="utf-8")
    assert current == page(), f"{DOC_PATH} is stale: run `{REGENERATE}`"


def test_the_page_has_every_code_with_its_title_under_its_range() -> None:
    text = page()
    for code in REGISTRY.values():
        assert f"### {code}: {code.title}\n" in text
    ranges = [line for line in text.splitlines() if line.startswith("## ")]
    assert ranges[:5] == ["## E0xx: reading and writing files, afsmc's own failures",
                          "## E1xx: syntax", "## E2xx: names and types",
                          "## E3xx: the checks of a well-formed model",
                          "## W3xx: warnings of the checks"]
    assert text.index("### E301:") < text.index("### W301:") < text.index("### E402:")
