"""dead_reset(): a transition into a mode where a variable is dead (not read before it is
written again) resets it to its initial value; the values of every property stay."""

from __future__ import annotations

from pathlib import Path

import pytest

from afsmc.lower.lowering import lower
from afsmc.lower.reduce import dead_reset, live_variables
from afsmc.model import expr as E
from tests.unit.lower.models import DEAD, commands, model_of


def test_the_variable_is_live_only_where_it_is_read() -> None:
    model = model_of(DEAD)
    live = live_variables(lower(model))
    assert live[model.mode("Use").number] == {"tmp"}
    assert live[model.mode("Pick").number] == set()
    assert live[model.mode("Done").number] == set()


def test_transitions_into_modes_where_it_is_dead_reset_it() -> None:
    low = lower(model_of(DEAD))
    reduced = dead_reset(low)
    for action in ("One", "Two"):
        (before,) = commands(low, action)
        (after,) = commands(reduced, action)
        assert dict(before.branches[0].updates).get("tmp") is None
        assert dict(after.branches[0].updates)["tmp"] == E.lit(0)
    # into Use it is read: Choose's updates stay as they were
    assert commands(reduced, "Choose") == commands(low, "Choose")
    assert reduced.model.variables == low.model.variables


@pytest.mark.storm
def test_dead_reset_merges_states_and_keeps_every_value(tmp_path: Path) -> None:
    from tests.storm_util import storm_prism

    low = lower(model_of(DEAD))
    plain, plain_values = storm_prism(low, tmp_path, "plain")
    reduced, values = storm_prism(dead_reset(low), tmp_path, "reduced")
    assert plain.nr_states == 5  # Pick, Use x 2, Done x 2
    assert reduced.nr_states == 4  # one Done
    assert values == pytest.approx(plain_values, abs=1e-12)
    assert values["one"] == pytest.approx(0.5)
