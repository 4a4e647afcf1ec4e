"""PRISM output pinned by golden files: tests/golden/cases/prism_*/expected.prism, byte for
byte and the same on every run."""

from __future__ import annotations

import pytest

from tests.conftest import CASES, ROOT, run_cli


@pytest.mark.parametrize("stem", ["patrol", "uav"])
def test_prism_output_is_deterministic_and_golden(stem: str, update_golden: bool,
                                                  monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.chdir(ROOT)
    first = run_cli("compile", f"examples/{stem}.afsm", "-o", "-")
    second = run_cli("compile", f"examples/{stem}.afsm", "-o", "-")
    assert first.code == 0 and first.out == second.out
    golden = CASES / f"prism_{stem}" / "expected.prism"
    if update_golden or not golden.exists():
        golden.parent.mkdir(parents=True, exist_ok=True)
        golden.write_text(first.out)
    assert first.out == golden.read_text()
