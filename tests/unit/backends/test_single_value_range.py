"""A variable of one value (`[0..0]`: declared so, or a counter the reductions saturate at
0) that an update writes: Storm's PRISM state generator gives it no bits and its update
overwrites the variable stored after it, so the PRISM route wrote it `[0..1]` (a value
never reached). The PRISM route's values against the JANI route's and the unreduced
model's."""

from __future__ import annotations

import pytest

from afsmc.backends.prism import prange
from afsmc.lower.reduce import Reductions
from afsmc.verify.core.api import run
from tests.unit.compose.test_templates import PAIR

# a and b walk to 2 and meet (both to 3); without the label's read of `moves_a` their move
# counters are never read, so the reductions saturate them at 0: a one-value shared
# variable each that every step writes.
WALKERS = PAIR.replace(" && moves_a >= 2", "")
# a single machine: `g` has one value and every step writes it; `y` never changes
SINGLE = """machine one;
mode A = 0 initial;
mode B = 1 final;
var g : [0..0] init 0;
var x : [0..3] init 0;
var y : [0..3] init 1;
action Step in A when x < 3 { g := 0, x += 1; }
action End in A when x == 3 { goto B; }
property y_kept = P=? [ F mode == B && y == 1 ];
"""


def test_a_single_value_is_written_as_a_range_of_two() -> None:
    assert prange(0, 0) == "[0..1]" and prange(2, 5) == "[2..5]"


@pytest.mark.storm
@pytest.mark.parametrize("text, name, want", [(WALKERS, "met", 1.0), (SINGLE, "y_kept", 1.0)])
def test_the_prism_route_agrees_with_jani_and_the_source(text: str, name: str,
                                                         want: float) -> None:
    pytest.importorskip("stormpy")
    for options in ({"via": "prism"}, {"via": "jani"},
                    {"via": "prism", "reductions": Reductions.none()}):
        r = run("m.afsm", text=text, **options).property(name)
        assert (r.max if r.max is not None else r.value) == pytest.approx(want), options
