"""A report in a real browser (Debian's Chromium, driven by Playwright): every section
is there, the diagram's SVG is drawn with a size, and the page logs no error. Skipped,
with the reason, only when the browser cannot start (scripts/setup.sh installs it)."""

from __future__ import annotations

import shutil
from pathlib import Path

import pytest

from tests.conftest import run_cli
from tests.e2e.test_report import SECTIONS
from tests.specs import patrol_with_requirements

pytestmark = [pytest.mark.storm, pytest.mark.slow]  # a report and a browser: 8 s

CHROMIUM = shutil.which("chromium") or shutil.which("chromium-browser")


def _browser(p: object) -> object:
    if CHROMIUM is None:
        pytest.skip("no Chromium on PATH (scripts/setup.sh installs Debian's chromium)")
    try:
        return p.chromium.launch(executable_path=CHROMIUM,  # type: ignore[attr-defined]
                                 args=["--no-sandbox", "--disable-gpu"])
    except Exception as exc:  # any failure to start is the reason to skip
        pytest.skip(f"Chromium at {CHROMIUM} does not start: {exc}")


def test_the_report_renders_in_chromium(tmp_path: Path) -> None:
    sync = pytest.importorskip("playwright.sync_api",
                               reason="playwright is not installed (pip install -e '.[dev]')")
    spec = patrol_with_requirements(tmp_path)
    out = tmp_path / "report.html"
    assert run_cli("report", str(spec), "-o", str(out)).code == 0
    with sync.sync_playwright() as p:
        browser = _browser(p)
        try:
            page = browser.new_page(java_script_enabled=False)  # type: ignore[attr-defined]
            problems: list[str] = []
            page.on("console", lambda m: problems.append(m.text) if m.type == "error" else None)
            page.on("pageerror", lambda e: problems.append(str(e)))
            page.on("requestfailed", lambda r: problems.append(f"request {r.url}"))
            requests: list[str] = []
            page.on("request", lambda r: requests.append(r.url))
            page.goto(out.as_uri())
            assert page.title() == "Assurance case: patrol"
            for section in SECTIONS:
                heading = page.locator(f"section#{section} h2")
                assert heading.count() == 1 and heading.is_visible(), section
            box = page.locator("#mission figure svg").bounding_box()
            assert box is not None and box["width"] > 100 and box["height"] > 100, box
            # the SVG's nodes are laid out: its modes' boxes have a size too
            node = page.locator("#mission svg g.node").first.bounding_box()
            assert node is not None and node["width"] > 0 and node["height"] > 0
            verdicts = page.locator("#requirements td.holds")
            assert verdicts.count() == 2
            assert problems == []
            assert requests == [out.as_uri()]  # nothing fetched but the page itself
        finally:
            browser.close()  # type: ignore[attr-defined]
