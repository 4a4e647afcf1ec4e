"""afsmc's own exploration and backward pass (afsmc.verify.explorer.explore, explicit) give
Storm's model and Storm's values.

The oracle is Storm: `--solver topological` builds the model with Storm and solves it with
Storm's own solver. On every example and test machine, the explicit path must report the
same numbers of states, choices and transitions as Storm's build, and the same values to
1e-9; a model with a real cycle, and a query of another shape, are left to Storm."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
import pytest

from afsmc.backends.prism import property_variants
from afsmc.compiler import load, lowered
from afsmc.verify import run
from afsmc.verify.engines import explicit
from afsmc.verify.explorer import explore, explore_graph, keysets
from tests.conftest import EXAMPLES
from tests.unit.backends.test_prism import SMALL
from tests.unit.verify.models import TEXT
from tests.unit.verify.test_engine_choice import FOREVER, _close, _values

pytestmark = pytest.mark.storm

EXAMPLE_FILES = sorted(EXAMPLES.glob("*.afsm"))
CYCLIC = {"fleet", "patrol", "warehouse"}  # examples with a cycle of more than one state


def _both(path: str, consts: dict[str, str]) -> tuple[Any, Any]:
    # Requirements (P>=0.9 [...]) are checked in Storm's sound mode, not by this path.
    asked = [p.name for p in load(path, consts).model.properties if p.threshold is None]
    new = run(path, consts=consts, engine="sparse", isolate=False, properties=asked)
    old = run(path, consts=consts, engine="sparse", isolate=False, solver="topological",
              properties=asked)
    return new, old


def _same_model(new: Any, old: Any) -> None:
    assert (new.states, new.choices, new.transitions) == (old.states, old.choices,
                                                          old.transitions)


@pytest.mark.slow
@pytest.mark.parametrize("path", EXAMPLE_FILES, ids=[p.stem for p in EXAMPLE_FILES])
def test_every_example_has_storm_s_model_and_values(path: Path) -> None:
    new, old = _both(str(path), SMALL.get(path.stem, {}))
    _close(_values(new), _values(old), 1e-9)
    _same_model(new.model, old.model)
    if new.uniform_model is not None:
        _same_model(new.uniform_model, old.uniform_model)
    if path.stem in CYCLIC:
        assert new.model.engine == "sparse" and new.model.solver == "topological"
    else:
        assert new.model.engine in ("explicit", "sparse")  # sparse: a bounded query left
        assert "acyclic" in new.model.solver
        if new.uniform_model is not None:
            assert "acyclic" in new.uniform_model.solver
    assert any(v is not None and 0 < v < 1 for p in new.properties
               for v in (p.min, p.max, p.uniform, p.value))


@pytest.mark.parametrize("text", [TEXT, FOREVER], ids=["tiny", "forever"])
def test_test_machines_have_storm_s_model_and_values(text: str, tmp_path: Path) -> None:
    path = tmp_path / "m.afsm"
    path.write_text(text, encoding="utf-8")
    new, old = _both(str(path), {})
    _close(_values(new), _values(old), 1e-9)
    _same_model(new.model, old.model)
    # tiny's bounded G properties are left to Storm, on a model Storm builds
    assert new.model.solver == ("acyclic (explicit) and topological" if text == TEXT
                                else "acyclic")


def test_the_uav_has_storm_s_model_and_values() -> None:
    path, consts = str(EXAMPLES / "uav.afsm"), SMALL["uav"]
    new, old = _both(path, consts)
    _close(_values(new), _values(old), 1e-9)
    _same_model(new.model, old.model)
    assert new.uniform_model is not None
    _same_model(new.uniform_model, old.uniform_model)
    assert new.model.engine == new.uniform_model.engine == "explicit"
    assert new.model.solver == "acyclic"


def _answer(path: str, consts: dict[str, str]) -> explicit.Answer | None:
    low = lowered(load(path, consts).model, "nondet")
    names = tuple(n for p in low.model.properties for n, _ in property_variants(low, p))
    return explicit.answer(low, names, "MDP", lambda _e, _d: None)


def test_a_real_cycle_is_left_to_storm() -> None:
    assert _answer(str(EXAMPLES / "patrol.afsm"), {}) is None


def test_every_successor_comes_first_and_every_choice_sums_to_one() -> None:
    low = lowered(load(str(EXAMPLES / "uav.afsm"), SMALL["uav"]).model, "nondet")
    c = explore.compile_model(low, [], [])
    a = explore_graph.explore(c).arrays
    layer = np.repeat(np.arange(len(a.layers) - 1), np.diff(a.layers))
    owner = np.repeat(np.repeat(np.arange(len(a.states) - 1), np.diff(a.states)),
                      np.diff(a.choices))
    moving = a.target != owner
    assert (layer[a.target[moving]] < layer[owner[moving]]).all()
    sums = np.add.reduceat(a.prob, a.choices[:-1])
    assert np.allclose(sums, 1.0, atol=1e-12)


def test_only_a_strategy_keeps_the_states_keys_and_choices_commands_in_storm_s_order(
) -> None:
    low = lowered(load(str(EXAMPLES / "uav.afsm"), SMALL["uav"]).model, "nondet")
    plain = explore_graph.explore(explore.compile_model(low, [], [])).arrays
    assert plain.order is None and plain.commands is None
    c = explore.compile_model(low, [], [], keep=True)
    a = explore_graph.explore(c).arrays
    assert a.order is not None and a.commands is not None
    n = len(a.states) - 1
    assert len(np.unique(a.order)) == n and a.order[a.initial] == c.initial
    assert len(a.commands) == len(a.choices) - 1 == plain.choices.size - 1
    mode = c.layout.decode(a.order)["mode"]
    owner = np.repeat(np.arange(n), np.diff(a.states))
    assert all(int(mode[s]) in low.commands[k].modes for s, k in zip(owner, a.commands, strict=True))
    # within a state: unlabelled commands first, then by label, as Storm orders choices
    assert (np.diff(a.states) > 1).any()
    rank = explore.storm_order(low)
    keys = [rank[int(k)] for k in a.commands]
    assert all(keys[i] < keys[i + 1] for i in range(len(keys) - 1) if owner[i] == owner[i + 1])


def test_the_state_limit_stops_the_exploration_as_it_stops_storm() -> None:
    from afsmc.diagnostics import CompileError

    path, consts = str(EXAMPLES / "uav.afsm"), SMALL["uav"]
    with pytest.raises(CompileError) as got:
        run(path, consts=consts, engine="sparse", isolate=False, max_states=100,
            uniform=False)
    with pytest.raises(CompileError) as want:
        run(path, consts=consts, engine="sparse", isolate=False, max_states=100,
            uniform=False, solver="topological")
    assert [d.code for d in got.value.diagnostics] == [d.code for d in want.value.diagnostics]
    assert "--max-states 100" in got.value.diagnostics[0].message


def test_a_model_past_the_memory_budget_is_left_to_storm() -> None:
    low = lowered(load(str(EXAMPLES / "uav.afsm"), SMALL["uav"]).model, "nondet")
    names = tuple(n for p in low.model.properties for n, _ in property_variants(low, p))
    said: list[str] = []
    assert explicit.answer(low, names, "MDP", lambda _e, d: said.append(str(d)),
                           max_bytes=1000) is None
    assert any("GB available" in s for s in said)
    assert explicit.answer(low, names, "MDP", lambda _e, _d: None) is not None


def test_a_long_chain_of_single_states_is_left_to_storm(tmp_path: Path) -> None:
    spec = tmp_path / "chain.afsm"
    spec.write_text("machine chain;\nvar x : [0..100000] init 0;\nmode A = 0 initial;\n"
                    "mode B = 1 final;\naction Inc in A when x < 100000 { x := x + 1; }\n"
                    "action Stop in A when x == 100000 { goto B; }\n"
                    "label done = mode == B;\nproperty reach = P=? [ F \"done\" ];\n",
                    encoding="utf-8")
    low = lowered(load(str(spec), {}).model, "nondet")
    said: list[str] = []
    assert explicit.answer(low, ("reach",), "DTMC", lambda _e, d: said.append(str(d))) is None
    assert any("a few at a time" in s for s in said), said
    r = run(str(spec), engine="sparse", isolate=False, uniform=False)
    assert r.model.engine == "sparse" and r.properties[0].value == 1.0


@pytest.mark.timeout(120)
def test_the_state_limit_stops_a_deep_bucket_within_its_rounds() -> None:
    """Patrol's corridor of 10^9 cells is one bucket explored round after round: the limit
    is checked each round, so the exploration stops just past it, not at the bucket's end."""
    low = lowered(load(str(EXAMPLES / "patrol.afsm"), {"CELLS": "1000000000"}).model, "nondet")
    names = tuple(n for p in low.model.properties for n, _ in property_variants(low, p))
    with pytest.raises(explicit.TooMany) as exc:
        explicit.answer(low, names, "MDP", lambda _e, _d: None, max_states=1000)
    # a round adds the successors of the last one: a few dozen states in patrol
    assert 1000 < exc.value.states < 2000


def test_a_buckets_keys_grow_in_sorted_runs_that_agree_with_a_set() -> None:
    """The explorer's key set (sorted runs merged like a binary counter) answers as a
    Python set does, round after round, and gives every key sorted at the end."""
    rng = np.random.default_rng(7)
    pool = rng.permutation(200_000).astype(np.int64)
    first, at = np.sort(pool[:3]), 3
    keys, oracle = keysets.Keys(first), set(first.tolist())
    for size in rng.integers(0, 300, 400).tolist():
        new = np.sort(pool[at:at + size])
        at += size
        probe = rng.integers(0, 200_000, 50).astype(np.int64)
        assert keys.found(probe).tolist() == [int(k) in oracle for k in probe]
        keys.add(new)
        oracle |= set(new.tolist())
        assert keys.size == len(oracle) and len(keys.runs) <= 2 + keys.size.bit_length()
    assert keys.sorted().tolist() == sorted(oracle)
