"""lower(): weights become guards, interval constants become one command per end (or one
uniform command), probabilistic hazards are woven into the branches, and final and stuck
modes get self-loops."""

from __future__ import annotations

import pytest

from afsmc.lower.lowering import lower
from afsmc.model.evaluate import scalar
from tests.unit.lower.models import CLIMB, GEOMETRIC, STUCK, commands, consts, model_of, value


def test_an_interval_constant_gives_one_command_per_end_under_nondet() -> None:
    low = lower(model_of(CLIMB), "nondet")
    ups = commands(low, "Up")
    assert [c.choice for c in ups] == [(("STEP", "lo"),), (("STEP", "hi"),)]
    assert low.bounds == {"STEP_lo": ("STEP", 1), "STEP_hi": ("STEP", 2)}
    assert low.kind == "mdp"
    # each command's first branch steps x by its own end, clamped at K
    steps = [value(low, c.branches[0].updates[0][1], "Climb", x=0) for c in ups]
    assert steps == [1, 2]
    assert [value(low, c.branches[0].updates[0][1], "Climb", x=4) for c in ups] == [5, 5]


@pytest.mark.parametrize(("resolution", "step"), [("lo", 1), ("hi", 2)])
def test_a_fixed_end_gives_one_command_and_one_bound(resolution: str, step: int) -> None:
    low = lower(model_of(CLIMB), resolution)  # type: ignore[arg-type]
    (up,) = commands(low, "Up")
    end = "lo" if resolution == "lo" else "hi"
    assert up.choice == (("STEP", end),)
    assert low.bounds == {f"STEP_{end}": ("STEP", step)}
    assert low.kind == "dtmc"
    assert value(low, up.branches[0].updates[0][1], "Climb", x=0) == step


def test_uniform_picks_each_end_with_equal_probability_in_one_command() -> None:
    low = lower(model_of(CLIMB), "uniform")
    (up,) = commands(low, "Up")
    assert up.choice == ()
    assert low.kind == "dtmc"
    c = consts(low)
    probs = [scalar(b.prob, c) for b in up.branches]
    assert sum(probs) == pytest.approx(1.0)
    moves = {value(low, b.updates[0][1], "Climb", x=0): p for b, p in zip(up.branches, probs,
                                                                          strict=True)
             if b.updates[0][0] == "x"}
    assert moves == {1: pytest.approx(0.45), 2: pytest.approx(0.45)}


def test_weights_become_guards_where_the_heaviest_enabled_action_fires() -> None:
    low = lower(model_of(CLIMB), "lo")
    (up,) = commands(low, "Up")
    (stop,) = commands(low, "Stop")
    assert value(low, up.guard, "Climb", x=0) and not value(low, stop.guard, "Climb", x=0)
    assert value(low, stop.guard, "Climb", x=5) and not value(low, up.guard, "Climb", x=5)
    # the guard also names the mode: nothing fires from Top
    assert not value(low, up.guard, "Top", x=0) and not value(low, stop.guard, "Top", x=5)


def test_a_final_mode_gets_a_silent_self_loop_of_kind_final() -> None:
    low = lower(model_of(CLIMB))
    finals = [c for c in low.commands if c.kind == "final"]
    assert [c.action for c in finals] == ["Top", "Fell"]
    for c in finals:
        assert c.silent
        (branch,) = c.branches
        assert branch.updates == ()
        assert scalar(branch.prob, {}) == 1
    top = finals[0]
    assert value(low, top.guard, "Top", x=3) and not value(low, top.guard, "Climb", x=3)


def test_a_hazard_is_woven_into_the_branches_of_the_actions_it_covers() -> None:
    low = lower(model_of(GEOMETRIC))
    (attempt,) = commands(low, "Attempt")
    c = consts(low)
    probs = {b.hazard: 0.0 for b in attempt.branches}
    for b in attempt.branches:
        probs[b.hazard] += scalar(b.prob, c)
    assert probs == {"Fail": pytest.approx(0.05), None: pytest.approx(0.95)}
    (fail,) = [b for b in attempt.branches if b.hazard == "Fail"]
    assert fail.updates[0][0] == "mode"
    assert value(low, fail.updates[0][1], "Try") == low.model.mode("Lost").number
    assert low.kind == "dtmc"


def test_a_mode_whose_actions_can_all_be_disabled_gets_a_deadlock_self_loop() -> None:
    low = lower(model_of(STUCK))
    (stuck,) = [c for c in low.commands if c.kind == "deadlock"]
    assert stuck.action == "Count" and stuck.silent
    assert value(low, stuck.guard, "Count", n=2)
    assert not value(low, stuck.guard, "Count", n=1)
    (inc,) = commands(low, "Inc")
    assert value(low, inc.guard, "Count", n=1) and not value(low, inc.guard, "Count", n=2)
