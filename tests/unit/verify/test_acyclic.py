"""The backward pass over an acyclic model (afsmc.verify.arrays.acyclic) gives Storm's values.

The oracle is Storm itself: `--solver topological` is the path afsmc took before, on the
same built model. Every example and test machine is checked both ways; the patrol robot
(a dock loop) is cyclic and must fall back to Storm."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
import pytest

from afsmc.compiler import load
from afsmc.verify import run
from afsmc.verify.arrays import acyclic, umb
from tests.conftest import EXAMPLES
from tests.unit.backends.test_prism import SMALL
from tests.unit.verify.models import TEXT
from tests.unit.verify.test_engine_choice import FOREVER, _close, _values

pytestmark = pytest.mark.storm


@pytest.fixture(autouse=True)
def _storm_builds(monkeypatch: pytest.MonkeyPatch) -> None:
    """These tests are of the pass over Storm's own build: afsmc's exploration, which a
    job tries first (test_explicit.py), is not tried here."""
    monkeypatch.setattr("afsmc.verify.core.model_loop.applies", lambda *_a: False)

EXAMPLE_FILES = sorted(EXAMPLES.glob("*.afsm"))
CYCLIC = {"fleet", "patrol", "warehouse"}  # examples with a cycle of more than one state


def _both(path: str, consts: dict[str, str]) -> tuple[Any, Any]:
    # Requirements (P>=0.9 [...]) are checked in Storm's sound mode, not by the pass.
    asked = [p.name for p in load(path, consts).model.properties if p.threshold is None]
    new = run(path, consts=consts, engine="sparse", isolate=False, properties=asked)
    old = run(path, consts=consts, engine="sparse", isolate=False, solver="topological",
              properties=asked)
    return new, old


@pytest.mark.slow
@pytest.mark.parametrize("path", EXAMPLE_FILES, ids=[p.stem for p in EXAMPLE_FILES])
def test_every_example_has_storm_s_values(path: Path) -> None:
    new, old = _both(str(path), SMALL.get(path.stem, {}))
    _close(_values(new), _values(old), 1e-12, rel=1e-12)
    # a bounded query (F<=k) is Storm's, on the same model
    want = {"topological"} if path.stem in CYCLIC else {"acyclic", "acyclic and topological"}
    assert new.model.solver in want and old.model.solver == "topological"
    if new.uniform_model is not None:
        assert new.uniform_model.solver in want
    assert new.model.states == old.model.states
    # not a trivial agreement: some value is neither 0 nor 1
    assert any(v is not None and 0 < v < 1 for p in new.properties
               for v in (p.min, p.max, p.uniform, p.value))


@pytest.mark.parametrize("text", [TEXT, FOREVER], ids=["tiny", "forever"])
def test_test_machines_have_storm_s_values(text: str, tmp_path: Path) -> None:
    path = tmp_path / "m.afsm"
    path.write_text(text, encoding="utf-8")
    new, old = _both(str(path), {})
    _close(_values(new), _values(old), 1e-12, rel=1e-12)
    # tiny's bounded G properties are left to Storm, on the same model
    assert new.model.solver == ("acyclic and topological" if text == TEXT else "acyclic")


# A hand-written MDP with what the missions do not have: self-loops of probability < 1,
# choices that only loop, state and action rewards, a target reached only sometimes.
LOOPS = """mdp
module m
  s : [0..5] init 0;
  [a] s=0 -> 0.5:(s'=0) + 0.25:(s'=1) + 0.25:(s'=2);
  [b] s=0 -> 0.9:(s'=3) + 0.1:(s'=0);
  [c] s=1 -> 0.3:(s'=1) + 0.7:(s'=4);
  [d] s=1 -> (s'=1);
  [e] s=2 -> 0.6:(s'=4) + 0.4:(s'=5);
  [] s=3 -> 0.2:(s'=4) + 0.8:(s'=5);
  [] s>=4 -> true;
endmodule
label "goal" = s=4;
label "end" = s>=4;
rewards "r"
  s<2 : 1.5;
  [b] true : 2;
  [e] s=2 : 3;
endrewards
rewards "t"
  [a] true : 1;
  [c] true : 0.5;
endrewards
"""
QUERIES = ['Pmin=? [F "goal"]', 'Pmax=? [F "goal"]', 'Pmin=? [F s=5]', 'Pmax=? [F "end"]',
           'R{"r"}min=? [F "end"]', 'R{"r"}max=? [F "end"]', 'R{"t"}min=? [F "end"]',
           'R{"t"}max=? [F s=3|s=5]', 'Pmax=? [F<=2 "goal"]', 'R{"r"}min=? [C]']


def _storm(text: str, tmp_path: Path) -> tuple[Any, Any, list[Any]]:
    import stormpy

    path = tmp_path / "m.prism"
    path.write_text(text, encoding="utf-8")
    program = stormpy.parse_prism_program(str(path))
    props = stormpy.parse_properties(";".join(f'"q{i}": {q}' for i, q in enumerate(QUERIES)),
                                     program)
    return stormpy, stormpy.build_model(program, props), props


def test_self_loops_and_every_kind_of_reward_as_storm(tmp_path: Path) -> None:
    stormpy, model, props = _storm(LOOPS, tmp_path)
    names = [p.get_name() for p in props]
    plan = acyclic.plan(names, props, mdp=True)
    assert plan.left == ["q8", "q9"]  # bounded and cumulative: Storm's
    arrays = umb.prepare(stormpy, model, plan)
    assert arrays is not None
    expected = {p.get_name(): stormpy.model_checking(model, p).get_value(
        model.initial_states[0]) for p in props}
    got = {q.name: acyclic.solve(arrays, q) for q in plan.queries}
    assert len(got) == 8
    for name, value in got.items():
        assert value == pytest.approx(expected[name], rel=1e-12, abs=1e-15), name
    # infinite where Storm says so: the maximum may stay in 1 forever ([d])
    assert got["q5"] == np.inf == expected["q5"]
    assert 0 < got["q0"] < got["q1"] < 1


def test_a_cycle_of_two_states_is_left_to_storm(tmp_path: Path) -> None:
    cyclic = LOOPS.replace("[e] s=2 -> 0.6:(s'=4)", "[e] s=2 -> 0.6:(s'=0)")
    stormpy, model, props = _storm(cyclic, tmp_path)
    plan = acyclic.plan([p.get_name() for p in props], props, mdp=True)
    assert umb.prepare(stormpy, model, plan) is None


def test_layers_put_every_successor_first() -> None:
    # 0 -> {1, 2}, 1 -> 3, 2 -> {2, 3}, 3 -> 3: one choice per state
    states = np.arange(5, dtype=np.int64)
    choices = np.array([0, 2, 3, 5, 6], dtype=np.int64)
    target = np.array([1, 2, 3, 2, 3, 3], dtype=np.int64)
    layers = acyclic.layers_of(states, choices, target)
    assert layers is not None
    assert [x.tolist() for x in layers] == [[3], [1, 2], [0]]
    target[4] = 0  # 2 -> 0 closes a cycle
    assert acyclic.layers_of(states, choices, target) is None


def test_compact_vectors_read_as_the_dense_ones() -> None:
    rng = np.random.default_rng(7)
    dense = np.where(rng.random(1000) < 0.1, rng.random(1000), 0.0)
    at = np.flatnonzero(dense)
    sparse = acyclic.sparse_or_dense(len(dense), at, dense[at])
    assert isinstance(sparse, acyclic.Sparse)
    for lo, hi in [(0, 1000), (3, 17), (999, 1000), (500, 500)]:
        assert np.array_equal(sparse[lo:hi], dense[lo:hi])
    table = np.array([0.25, 0.5, 0.125])
    codes = rng.integers(0, 3, 200).astype(np.uint16)
    coded = acyclic.Coded(table, codes)
    assert np.array_equal(coded[10:50], table[codes][10:50])
    assert acyclic.sparse_or_dense(4, np.array([0, 1, 3]), np.ones(3)).tolist() == [1, 1, 0, 1]


def test_self_loops_are_each_choice_s_probability_of_staying() -> None:
    # 3 states; state 1 has two choices, the second looping with 0.25; state 2 only loops
    states = np.array([0, 1, 3, 4])
    choices = np.array([0, 2, 3, 5, 6])
    target = np.array([1, 2, 0, 1, 0, 2], np.int32)
    prob = np.array([0.5, 0.5, 1.0, 0.25, 0.75, 1.0])
    stay = acyclic.self_loops(states, choices, target, prob)
    assert stay is not None
    assert np.array_equal(stay[0:4], [0.0, 0.0, 0.25, 1.0])
