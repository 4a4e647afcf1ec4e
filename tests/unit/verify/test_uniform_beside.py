"""The uniform DTMC answered by the MDP's own exploration: each state's value the mean of
its floor/ceil choices (afsmc.verify.arrays.acyclic, opt "mean"), with no exploration of
its own. Oracles: Storm's exact engine on the uniform DTMC it builds from the PRISM text
(rationals), and Storm's topological solver on the same DTMC."""

from __future__ import annotations

from fractions import Fraction
from pathlib import Path

import pytest

from afsmc.verify import run
from afsmc.verify.core.options import VerifyOptions
from tests.conftest import EXAMPLES
from tests.unit.backends.test_prism import SMALL

pytestmark = pytest.mark.storm

# Self-loops of different probabilities under the two ends of STEP (0.9 and 0.3 when x
# stays), and a choice that only loops (PUSH = 0) beside one that leaves: the mean is
# then not the mean of the choices' own values.
LOOPS = """\
machine loops;

const prob P_STAY = 0.3;
const int STEP = [0, 2];
const int PUSH = [0, 1];

var x : [0..12] init 0;

mode Go = 0 initial;
mode Push = 1;
mode Done = 2 final;
mode Lost = 3 final;

action Walk in Go when x < 8 {
    P_STAY: x := x;
    0.6:    x := x + STEP;
    0.1:    goto Lost;
}
action Ready in Go when x >= 8 {
    goto Push;
}
action Shove in Push when x < 10 {
    x := x + PUSH;
}
action Finish in Push when x >= 10 {
    goto Done;
}

label done = mode == Done;
label over = mode == Done || mode == Lost;

rewards tries {
    [Walk] true : 1;
    [Shove] true : 2;
}
rewards time {
    true : 0.5;
}

property reach = P=? [ F "done" ];
property lost = P=? [ F mode == Lost ];
property tries = R{"tries"}=? [ F "over" ];
property time = R{"time"}=? [ F "over" ];
"""


def test_the_uniform_dtmc_with_self_loops_equals_storms_exact_values(tmp_path: Path) -> None:
    path = tmp_path / "loops.afsm"
    path.write_text(LOOPS, encoding="utf-8")
    said: list[str] = []
    fast = run(str(path), progress=said.append)
    exact = run(str(path), options=VerifyOptions(exact=True))
    assert fast.uniform_model is not None and exact.uniform_model is not None
    # no exploration or process of its own, the same size as Storm's uniform DTMC
    assert fast.uniform_model.processes == 0 and fast.uniform_model.engine == "explicit"
    assert not any(s.startswith("built the uniform DTMC") for s in said), said
    assert (fast.uniform_model.states, fast.uniform_model.transitions) == (
        exact.uniform_model.states, exact.uniform_model.transitions)
    for got, want in zip(fast.properties, exact.properties, strict=True):
        assert want.exact["uniform"] and got.uniform is not None
        assert got.uniform == pytest.approx(float(Fraction(want.exact["uniform"])),
                                            rel=1e-12, abs=1e-15), got.name
    # the mean differs from the mean of the choices' values: a real test of the loops
    assert 0 < fast.properties[0].uniform < fast.properties[0].max  # type: ignore[operator]


def test_the_uav_uniform_values_equal_those_of_its_own_dtmc() -> None:
    consts = SMALL["uav"]
    fast = run(str(EXAMPLES / "uav.afsm"), consts=consts)
    # the topological solver takes Storm's route for both models: the DTMC built itself
    storm = run(str(EXAMPLES / "uav.afsm"), consts=consts,
                options=VerifyOptions(solver="topological"))
    assert fast.uniform_model is not None and storm.uniform_model is not None
    assert fast.uniform_model.processes == 0 and storm.uniform_model.processes == 1
    assert (fast.uniform_model.states, fast.uniform_model.transitions) == (
        storm.uniform_model.states, storm.uniform_model.transitions)
    for got, want in zip(fast.properties, storm.properties, strict=True):
        assert got.uniform == pytest.approx(want.uniform, rel=1e-9, abs=1e-12), got.name
        assert (got.min, got.max) == pytest.approx((want.min, want.max), rel=1e-9, abs=1e-12)


def test_one_process_per_query_still_builds_the_uniform_dtmc(tmp_path: Path) -> None:
    # --split explores the MDP once per query: the uniform DTMC is then checked itself
    path = tmp_path / "loops.afsm"
    path.write_text(LOOPS, encoding="utf-8")
    split = run(str(path), options=VerifyOptions(split=True))
    whole = run(str(path))
    assert split.uniform_model is not None and split.uniform_model.processes == 4
    for a, b in zip(split.properties, whole.properties, strict=True):
        assert a.uniform == pytest.approx(b.uniform, rel=1e-12, abs=1e-15), a.name
