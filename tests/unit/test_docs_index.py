"""docs/README.md, the index of the documentation, links every page of docs/ and only pages
that exist, so that a newcomer finds each page from it."""

from __future__ import annotations

import re
from pathlib import Path

DOCS = Path(__file__).resolve().parents[2] / "docs"
INDEX = DOCS / "README.md"


def _links() -> set[str]:
    text = INDEX.read_text(encoding="utf-8")
    return {m.split("#", 1)[0] for m in re.findall(r"\]\(([^)\s]+)\)", text)
            if "://" not in m}


def test_every_page_of_docs_is_in_the_index() -> None:
    pages = {p.name for p in DOCS.glob("*.md")} - {"README.md"}
    missing = sorted(pages - _links())
    assert not missing, f"docs/README.md does not link {missing}"


def test_every_link_of_the_index_exists() -> None:
    broken = sorted(link for link in _links() if link and not (DOCS / link).exists())
    assert not broken, f"docs/README.md links files that do not exist: {broken}"
