"""Mode numbers: modes without a number take the lowest free one."""

from __future__ import annotations

from afsmc.compiler import load


def test_unnumbered_modes_take_the_lowest_free_number() -> None:
    """docs/language.md (Modes): unnumbered modes fill the gaps in declaration order, counting
    the numbers written further down too; not "one more than the mode before"."""
    text = """machine num;
mode Idle = 0 initial; mode Search; mode Carry = 5; mode Back; mode Done = 9 final;
mode Emerg final;
action Go in Idle { goto Search; }
action Pick in Search { goto Carry; }
action Drop in Carry { goto Back; }
action Home in Back { goto Done; }
"""
    model = load("num.afsm", text=text).model
    assert {m.name: m.number for m in model.modes} == {
        "Idle": 0, "Search": 1, "Back": 2, "Emerg": 3, "Carry": 5, "Done": 9}
