"""verify refuses what it cannot ask before any Storm process starts: two properties in one
--formula (E409), and the JANI route when its backend cannot be imported (E408)."""

from __future__ import annotations

import sys

import pytest

from tests.conftest import EXAMPLES, run_cli


def test_two_properties_in_one_formula_are_e409() -> None:
    r = run_cli("verify", str(EXAMPLES / "patrol.afsm"), "--formula",
                'P=? [ F "docked" ]; P=? [ F "halted" ]')
    assert r.code == 1
    assert "error[E409]" in r.err and "one property, without ';'" in r.err


@pytest.mark.storm
def test_the_jani_route_without_its_backend_is_e408(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setitem(sys.modules, "afsmc.backends.jani", None)  # import raises ImportError
    r = run_cli("verify", str(EXAMPLES / "patrol.afsm"), "--via", "jani")
    assert r.code == 1
    assert "error[E408]" in r.err and "--via prism" in r.err
