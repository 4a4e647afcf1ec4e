"""reorder(): the variables are declared in the order Storm's decision diagrams like
(small control variables first, tuple fields interleaved, wide counters last); the updates
follow; the state space and the values stay."""

from __future__ import annotations

from pathlib import Path

import pytest

from afsmc.lower.lowering import lower
from afsmc.lower.reduce import reorder
from tests.unit.lower.models import COUNTER, ORDER, commands, model_of


def test_control_first_fields_interleaved_counters_last() -> None:
    low = lower(model_of(ORDER))
    reduced = reorder(low)
    assert [v.display for v in low.model.variables] == [
        "time", "pos.x", "pos.y", "ret.x", "ret.y", "busy"]
    assert [v.display for v in reduced.model.variables] == [
        "busy", "pos.x", "ret.x", "pos.y", "ret.y", "time"]
    (step,) = commands(reduced, "Step")
    assert [var for var, _ in step.branches[0].updates] == ["busy", "pos_x", "ret_y", "time"]


def test_an_order_that_is_already_right_is_kept() -> None:
    low = lower(model_of(COUNTER))
    assert reorder(low) is low


@pytest.mark.storm
def test_reordering_keeps_the_state_space_and_every_value(tmp_path: Path) -> None:
    from tests.storm_util import storm_prism

    low = lower(model_of(ORDER))
    plain, plain_values = storm_prism(low, tmp_path, "plain")
    reduced, values = storm_prism(reorder(low), tmp_path, "reduced")
    assert reduced.nr_states == plain.nr_states
    assert values == pytest.approx(plain_values, abs=1e-12)
