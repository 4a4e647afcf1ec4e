"""The diagram labels a branch whose probability reads an interval probability with its
range over the interval (what the verified bounds range over), not the midpoint."""

from __future__ import annotations

from afsmc.api.mission import load
from tests.conftest import EXAMPLES


def _patrol(prob: str) -> str:
    return (EXAMPLES / "patrol.afsm").read_text(encoding="utf-8").replace(
        "const prob P_FAULT  = 0.01;", f"const prob P_FAULT  = {prob};")


def test_an_interval_probability_is_drawn_as_its_range() -> None:
    dot = load(_patrol("[0.005, 0.03]")).compile("dot")
    assert "Fault (0.005–0.03)" in dot and "Fault (0.0175)" not in dot


def test_a_fixed_probability_is_drawn_as_its_value() -> None:
    dot = load(_patrol("0.02")).compile("dot")
    assert "Fault (0.02)" in dot
