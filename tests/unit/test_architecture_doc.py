"""docs/architecture.md matches the tree: every path it names exists, and every module under
afsmc/ is named on the page (by its file name, in the paragraph of its folder)."""

from __future__ import annotations

import re
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
PAGE = ROOT / "docs" / "architecture.md"


def _page() -> str:
    return PAGE.read_text(encoding="utf-8")


def test_every_path_the_page_names_exists() -> None:
    named = set(re.findall(r"(?<![\w/.])((?:afsmc|tests|grammar|scripts)/[\w/<>.-]*\w)", _page()))
    missing = sorted(p for p in named if "<" not in p and not (ROOT / p).exists())
    assert not missing, f"docs/architecture.md names paths that do not exist: {missing}"


def _bullet(page: str, folder: str) -> str:
    """The text of the top-level bullet that starts with the folder (its nested bullets
    included), or nothing."""
    found = re.search(rf"^- `{re.escape(folder)}`.*?(?=^- |^## |\Z)", page, re.M | re.S)
    return found.group(0) if found else ""


def test_every_module_is_described_on_the_page() -> None:
    page = _page()
    absent = []
    for path in sorted((ROOT / "afsmc").rglob("*.py")):
        if path.name in ("__init__.py", "__main__.py"):
            continue
        rel = path.relative_to(ROOT)
        # named by its full path, or by its file name in the bullet of its folder, or of the
        # folder above for a subpackage (afsmc/verify/'s bullet describes its subpackages)
        if rel.as_posix() in page:
            continue
        folders = [rel.parent] + ([rel.parent.parent] if len(rel.parts) > 3 else [])
        if not any(f"`{path.name}`" in _bullet(page, f"{f.as_posix()}/") for f in folders):
            absent.append(rel.as_posix())
    assert not absent, f"modules that docs/architecture.md does not describe: {absent}"
