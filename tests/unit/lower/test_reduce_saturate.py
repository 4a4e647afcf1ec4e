"""saturate(): a counter that only grows and is only compared with constants stops just
above the largest of them; its range shrinks and the values of every property stay."""

from __future__ import annotations

from pathlib import Path

import pytest

from afsmc.lower.lowering import lower
from afsmc.lower.reduce import saturate
from tests.unit.lower.models import COUNTER, DEAD, commands, model_of, value


def test_a_growing_counter_compared_with_three_saturates_at_three() -> None:
    low = lower(model_of(COUNTER))
    reduced, done = saturate(low)
    assert done == ["t at 3"]
    (t,) = reduced.model.variables
    assert (t.lo, t.hi) == (0, 3)
    (tick,) = commands(reduced, "Tick")
    step = dict(tick.branches[0].updates)["t"]
    assert [value(reduced, step, "Run", t=x) for x in range(4)] == [1, 2, 3, 3]


def test_a_variable_that_is_set_not_counted_is_left_alone() -> None:
    low = lower(model_of(DEAD))
    reduced, done = saturate(low)
    assert done == []
    assert reduced is low


@pytest.mark.storm
def test_saturation_shrinks_the_state_space_and_keeps_every_value(tmp_path: Path) -> None:
    from tests.storm_util import storm_prism

    low = lower(model_of(COUNTER))
    plain, plain_values = storm_prism(low, tmp_path, "plain")
    reduced, values = storm_prism(saturate(low)[0], tmp_path, "reduced")
    assert reduced.nr_states < plain.nr_states
    assert values == pytest.approx(plain_values, abs=1e-12)
    assert values["late"] == pytest.approx(0.8**3)
