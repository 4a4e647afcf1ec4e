"""docs/report/uav.html and .md, the report docs/report.md walks a reviewer through, are
what scripts/gen_report.py writes now: the quick test checks they are of examples/uav.afsm
as it is (its hash), the slow one makes them again and compares every byte."""

from __future__ import annotations

import hashlib

import pytest

from tests.conftest import ROOT, script_module

gen = script_module("gen_report")


def test_the_report_in_docs_is_of_the_spec_as_it_is() -> None:
    digest = hashlib.sha256((ROOT / gen.SPEC).read_bytes()).hexdigest()
    for suffix in (".html", ".md"):
        text = (ROOT / f"{gen.OUT}{suffix}").read_text(encoding="utf-8")
        assert digest in text, f"{gen.OUT}{suffix} is stale: run `{gen.REGENERATE}`"
        assert gen.GENERATED in text


def test_the_page_links_the_report() -> None:
    page = (ROOT / "docs" / "report.md").read_text(encoding="utf-8")
    assert "(report/uav.html)" in page and "(report/uav.md)" in page
    assert "verification.md#what-a-result-means" in page


@pytest.mark.slow
@pytest.mark.storm
def test_the_report_in_docs_is_current() -> None:
    assert gen.stale(gen.texts()) == [], f"run `{gen.REGENERATE}`"
