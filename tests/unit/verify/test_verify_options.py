"""One frozen VerifyOptions: `run`, `check` and `sweep` take it whole or as keywords, and
refuse what it does not hold."""

from __future__ import annotations

import dataclasses

import pytest

from afsmc.verify import VerifyOptions, run, sweep
from tests.conftest import EXAMPLES

PATROL = str(EXAMPLES / "patrol.afsm")


def test_options_are_frozen() -> None:
    o = VerifyOptions(engine="sparse")
    with pytest.raises(dataclasses.FrozenInstanceError):
        o.engine = "dd"  # type: ignore[misc]


@pytest.mark.parametrize(("field", "value"), [("via", "smv"), ("engine", "fast"),
                                              ("solver", "guess")])
def test_a_misspelt_choice_is_refused_when_the_options_are_made(field: str, value: str) -> None:
    with pytest.raises(ValueError, match=f"{field} must be one of"):
        VerifyOptions(**{field: value})  # type: ignore[arg-type]


def test_an_unknown_keyword_names_the_options() -> None:
    with pytest.raises(TypeError, match=r"unknown verification option.*precison.*precision"):
        run(PATROL, precison=1e-9)


def test_options_whole_and_as_keywords_exclude_each_other() -> None:
    with pytest.raises(TypeError, match="either"):
        run(PATROL, VerifyOptions(), engine="sparse")


def test_a_sweep_refuses_what_only_verify_gives() -> None:
    with pytest.raises(ValueError, match="--strategy and --witness are verify's"):
        sweep(PATROL, "CELLS", [2], strategy=True)


@pytest.mark.storm
def test_options_whole_and_as_keywords_give_the_same_answer() -> None:
    whole = run(PATROL, VerifyOptions(engine="sparse", precision=1e-9), properties=["finish"])
    keywords = run(PATROL, engine="sparse", precision=1e-9, properties=["finish"])
    a, b = whole.property("finish"), keywords.property("finish")
    assert (a.min, a.max, a.uniform, a.error) == (b.min, b.max, b.uniform, b.error) \
        and 1e-9 <= a.error < 1.001e-9  # the precision and the rounding's bound
