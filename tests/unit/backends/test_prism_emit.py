"""afsmc.backends.prism.emit on a lowered model: the model type, constants (interval ends
included), one module with the mode and the variables, one command per lowered command
with its guard and branches, labels and the properties file."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

from afsmc.backends.prism import emit, files
from afsmc.lower.lowering import lower
from tests.unit.lower.models import CLIMB, GEOMETRIC, model_of


def test_an_mdp_with_one_command_per_interval_end() -> None:
    out = emit(lower(model_of(CLIMB), "nondet"))
    lines = out.model.splitlines()
    assert "mdp" in lines
    assert "const int STEP_lo = 1; // STEP in [1, 2], spec.afsm:5" in lines
    assert "const int STEP_hi = 2; // STEP in [1, 2], spec.afsm:5" in lines
    assert "const double P_OK = 0.9; // spec.afsm:4" in lines
    module = out.model[out.model.index("module climb"):out.model.index("endmodule")]
    assert "  mode : [0..2] init 0;" in module
    assert re.search(r"^  x : \[0\.\.5\] init 0;", module, re.M)
    # the weights are guards: Up where its weight beats Stop's
    guard = "[Up] mode = 0 & 0.5 < (x < K ? 0.8 : 0.2) ->"
    assert module.count(guard) == 2
    assert "P_OK : (x'=min(x + STEP_lo, 5))" in module
    assert "P_OK : (x'=min(x + STEP_hi, 5))" in module
    assert "[Stop] mode = 0 & (x < K ? 0.8 : 0.2) < 0.5 ->" in module
    # final modes loop on themselves, unlabelled
    assert module.count("[] mode = 1 ->") == 1 and module.count("[] mode = 2 ->") == 1
    assert 'label "top" = mode = 1;' in out.model


def test_properties_get_a_min_and_a_max_variant_in_an_mdp() -> None:
    out = emit(lower(model_of(CLIMB), "nondet"))
    assert out.property_names == ("top_min", "top_max")
    assert out.properties.splitlines() == ['"top_min": Pmin=? [ F "top" ];',
                                           '"top_max": Pmax=? [ F "top" ];']


def test_a_dtmc_has_one_variant_and_weaves_the_hazard() -> None:
    out = emit(lower(model_of(GEOMETRIC)))
    assert "dtmc" in out.model.splitlines()
    assert "[Attempt] mode = 0 ->" in out.model
    assert "Q : (mode'=2)" in out.model  # the hazard's branch, to Lost
    assert out.property_names == ("win",)
    assert files(lower(model_of(GEOMETRIC))) == {".prism": out.model, ".props": out.properties}


@pytest.mark.storm
def test_storm_reads_the_output_and_finds_the_closed_form(tmp_path: Path) -> None:
    from tests.storm_util import storm_prism

    _, values = storm_prism(lower(model_of(GEOMETRIC)), tmp_path)
    p, q = 0.3, 0.05
    assert values["win"] == pytest.approx((1 - q) * p / (1 - (1 - q) * (1 - p)), abs=1e-9)
