"""verify's heading names how the agents take turns where it changes what the values are:
a fair interleaving's min and max are over fair schedulers only, a uniform interleaving
is a DTMC whose next mover is uniform (docs/language.md, "Composition")."""

from __future__ import annotations

import os
from pathlib import Path

import pytest

from tests.conftest import run_cli

HERE = Path(os.path.dirname(__file__))


@pytest.mark.storm
def test_a_fair_interleaving_says_fair_schedulers_only() -> None:
    r = run_cli("verify", str(HERE / "starve.afsm"))
    assert r.code == 0, r.err
    assert ("over the order in which the agents move (fair schedulers only: every agent "
            "that stays able to move eventually moves)") in r.out


@pytest.mark.storm
def test_a_uniform_interleaving_says_who_moves_next(tmp_path: Path) -> None:
    path = tmp_path / "u.afsm"
    path.write_text((HERE / "fleet4.afsm").read_text(encoding="utf-8").replace(
        "compose interleaving;", "compose interleaving uniform;"), encoding="utf-8")
    r = run_cli("verify", str(path))
    assert r.code == 0, r.err
    assert ("a DTMC (who moves next is uniform among the agents that can move): one value "
            "per property") in r.out
