"""Lowering of hazards: preemptive hazards, the hazards woven into them, and the weights of
the actions they disable. The oracle is Storm on the lowered model."""

from __future__ import annotations

from pathlib import Path

import pytest

from afsmc.compiler import load
from afsmc.lower.lowering import lower
from tests.storm_util import storm_prism

pytestmark = pytest.mark.storm


def _model(tmp: Path, text: str) -> object:
    path = tmp / "spec.afsm"
    path.write_text(text)
    return load(str(path)).model


def test_hazards_woven_into_a_preemptive_hazard_make_their_target_reachable(tmp_path: Path) -> None:
    """Only the preemptive Stop fires in A, but Crash is woven into it: D is reachable."""
    path = tmp_path / "mg.afsm"
    path.write_text("""
machine mg;
var x : [0..3] init 0;
mode A = 0 initial;
mode C = 2 final;
mode D = 3 final;
action Wait in A when x > 0 && x < 1 { x := 0; }
hazard Stop from {A} when x >= 0 { goto C; }
hazard Crash from {A} with probability 0.5 { goto D; }
label L = mode == D;
property p = P=? [ F "L" ];
""")
    checked = load(str(path))
    assert not any(d.code == "W601" for d in checked.diagnostics)
    _, values = storm_prism(lower(checked.model), tmp_path)
    assert values["p"] == pytest.approx(0.5)


def test_weight_of_an_action_disabled_by_a_preemptive_hazard_is_zero(tmp_path: Path) -> None:
    """Definition 2: w(s, a) > 0 only where a is enabled, and a preemptive hazard disables
    the ordinary actions of its modes. Halt's weight 1 - w(Run) must see w(Run) = 0."""
    model = _model(tmp_path, """
machine pre;
var x : [0..2] init 0;
mode A = 0 initial;
mode Low = 1 final;
mode High = 2 final;
action Run in A when x < 2 weight 0.9 { x := x + 1; }
hazard Halt from {A} when x >= 1 weight 1 - w(Run) { goto Low; }
hazard Stop from {A} when x >= 1 weight 0.3 { goto High; }
label low = mode == Low;
property p = P=? [ F "low" ];
""")
    # At x = 1 the hazards preempt Run, so w(Run) = 0 and Halt (1) beats Stop (0.3).
    _, values = storm_prism(lower(model), tmp_path)  # type: ignore[arg-type]
    assert values["p"] == 1.0
