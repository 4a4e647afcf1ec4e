"""afsmc.check.storm_depth: an expression that nests deeper than Storm evaluates
(STORM_DEPTH levels), once its formulas are inlined, is E310."""

from __future__ import annotations

from afsmc.check.storm_depth import STORM_DEPTH, check_storm_depth
from tests.unit.check.rules import codes, line_of, run_rule


def _model(formula_terms: int, label_terms: int) -> str:
    # each `+` of a left-associated chain is one level
    chain = " + ".join(["x"] * formula_terms)
    uses = " + ".join(["f"] * label_terms)
    return f"""machine deep;
var x : [0..1] init 0;
mode S = 0 initial;
mode D = 1 final;
formula f = {chain};
action Go in S {{ goto D; }}
label big = {uses} > 100;
"""


def test_a_label_deeper_than_storm_once_its_formula_is_inlined_is_e310() -> None:
    text = _model(3000, 2000)
    (d,) = run_rule(check_storm_depth, text)
    assert d.code == "E310"
    assert "once its formulas are inlined" in d.message
    assert d.message.endswith(f"Storm evaluates at most {STORM_DEPTH:,}")
    assert line_of(d, text) == 7


def test_the_same_shape_below_the_limit_is_fine() -> None:
    assert codes(check_storm_depth, _model(2000, 2000)) == []
