"""Strategies and witnesses through `--scratch` (afsmc.verify.stream.extract): from the
files of the one streamed exploration, no second exploration in memory. Oracle: the
in-memory route's extraction (afsmc.verify.engines.strategy_arrays, itself pinned to
Storm's schedulers and k-shortest-paths generator in tests/unit/verify), which must come
out equal field for field: the strategies' groups and counts, the whole policy in Storm's
order, every witness path (probabilities, states, commands, steps) and the notes."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import pytest

from afsmc.backends.prism import property_variants
from afsmc.compiler import load, lowered
from afsmc.verify import run
from afsmc.verify.engines import explicit
from afsmc.verify.engines.strategy_storm import Extracted, WitnessRequest
from afsmc.verify.outcome.strategy import extract_for
from afsmc.verify.stream import extract, scratch, sweep
from tests.conftest import run_cli
from tests.unit.verify.test_streaming import CASES, UAV, _loops

pytestmark = pytest.mark.storm

MIDDLE = {"WIDTH": "3", "HEIGHT": "3", "T_LIMIT": "120"}  # the UAV: 16,972 states


def _both(path: str, consts: dict[str, str], where: Path, witness: int | None, k: int,
          policy: int | None) -> tuple[explicit.Answer, explicit.Answer, list[str]]:
    """The in-memory and the streamed answers with every P and R strategy asked, the
    policy of query number `policy` and the witness of P query number `witness`."""
    low = lowered(load(path, consts).model, "nondet")
    names = tuple(n for p in low.model.properties for n, _ in property_variants(low, p))
    p = explicit.plan(low, names)
    asked = [q for q in p.queries if q.kind in ("P", "R") and q.opt in ("min", "max")]
    probs = [q for q in asked if q.kind == "P"]
    ex = extract_for(low, tuple(q.name for q in asked),
                     None if policy is None else asked[policy % len(asked)].name,
                     None if witness is None else
                     WitnessRequest(probs[witness % len(probs)].name, k))
    said: list[str] = []
    memory = explicit.answer(low, names, "MDP", lambda *_: None, extract=ex)
    with scratch.made(str(where)) as into:
        streamed = explicit.answer(low, names, "MDP", lambda e, d: said.append(str(d)),
                                   extract=ex, scratch=str(into))
    assert memory is not None and streamed is not None
    return memory, streamed, said


def _same(a: Extracted | None, b: Extracted | None) -> None:
    assert a is not None and b is not None
    for f in ("variables", "reached", "groups", "policy_states", "policy_commands",
              "witness_note", "witness_query"):
        assert getattr(a, f) == getattr(b, f), f
    assert [(x.probability, x.states, x.commands, x.steps) for x in a.paths] == \
        [(x.probability, x.states, x.commands, x.steps) for x in b.paths]


@pytest.mark.parametrize(("case", "witness", "k", "policy"), [
    ("uav", 0, 5, None),  # fewer paths than asked: the bound lowered to 0
    ("uav", 1, 2, 3),
    ("rover", 0, 7, 1),  # late states (a clock set back)
    ("rover", 3, 1, None),
    ("overtake", 2, 30, 0),  # sinks
    ("overtake", 5, 3, None),
    ("loops", 0, 5, 2),  # self-loops: paths that loop
    ("loops", 3, 12, None),
])
@pytest.mark.parametrize("kernels", ["numpy", "numba"])
def test_streamed_strategies_and_witnesses_equal_the_in_memory_ones(
        case: str, witness: int, k: int, policy: int | None, kernels: str, tmp_path: Path,
        monkeypatch: pytest.MonkeyPatch) -> None:
    # numba: the sweep's compiled kernel gives the optimal choices, every layer cut
    # between its threads
    monkeypatch.setenv("AFSMC_KERNELS", kernels)
    monkeypatch.setattr(sweep, "SPLIT", 1)
    monkeypatch.setattr(extract, "PROGRESS_EVERY", -1.0)  # a progress line for every file
    path, consts = CASES[case] if case != "loops" else (_loops(tmp_path), {})
    memory, streamed, said = _both(path, consts, tmp_path, witness, k, policy)
    assert streamed.scratch is not None and memory.scratch is None
    assert streamed.values == pytest.approx(memory.values, rel=1e-12, abs=1e-12)
    _same(memory.extracted, streamed.extracted)
    assert memory.extracted is not None
    assert memory.extracted.paths or memory.extracted.witness_note  # a witness was asked
    assert any("read forward from the same layers" in s for s in said)
    assert any("files forward for the strategies" in s for s in said), said
    assert not list(tmp_path.glob(scratch.PREFIX + "*"))


def test_the_witness_searches_only_the_states_its_paths_may_cross(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    # k paths into k distinct targets bound the search: the sub-model searched is a small
    # part of the states; and where the bound is lowered at once to 0 (every state that
    # reaches the target), the paths are the same
    sizes: list[int] = []
    sub = extract._sub

    def counted(*args: Any) -> Any:
        got = sub(*args)
        sizes.append(len(got.states) - 1)
        return got

    monkeypatch.setattr(extract, "_sub", counted)
    memory, streamed, _ = _both(UAV, MIDDLE, tmp_path, 2, 3, None)
    _same(memory.extracted, streamed.extracted)
    assert memory.extracted is not None and len(memory.extracted.paths) == 3
    assert len(sizes) == 1 and 0 < sizes[0] < streamed.states / 100, (sizes, streamed.states)
    monkeypatch.setattr(extract, "TRIES", 0)  # tau 0 from the start
    _, whole, _ = _both(UAV, MIDDLE, tmp_path, 2, 3, None)
    _same(memory.extracted, whole.extracted)
    assert len(sizes) == 2 and sizes[1] > sizes[0], sizes  # every state that reaches it


def test_a_strategy_with_a_scratch_is_streamed_and_leaves_nothing(tmp_path: Path) -> None:
    said: list[str] = []
    res = run(_loops(tmp_path), isolate=True, scratch=str(tmp_path), strategy=True,
              progress=said.append)
    assert any("read forward from the same layers" in s for s in said), said
    assert not any("explored in memory" in s for s in said), said
    memory = run(_loops(tmp_path), isolate=False, strategy=True)
    assert res.properties[0].strategy == memory.properties[0].strategy is not None
    assert [p.name for p in tmp_path.iterdir()] == ["loops.afsm"]


def test_verify_strategy_and_witness_say_the_same_with_a_scratch(tmp_path: Path) -> None:
    args = ["verify", UAV, "--const", "WIDTH=2,HEIGHT=2,T_LIMIT=100", "--strategy",
            "--witness", "3", "-p", "success"]
    plain = run_cli(*args)
    streamed = run_cli(*args, "--scratch", str(tmp_path))
    assert plain.code == streamed.code == 0, streamed.err

    def kept(text: str) -> list[str]:  # all but the timings and the engine's reason
        return [x for x in text.splitlines() if " s " not in x and "engine" not in x
                and "total" not in x]

    assert "strateg" in plain.out and "path" in plain.out
    assert kept(plain.out) == kept(streamed.out)
    assert "scratch disk" in streamed.out
    assert list(tmp_path.iterdir()) == []


def test_with_little_room_the_asked_queries_keep_their_choices_in_a_sweep_of_their_own(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    # every query's values not fitting one sweep: the asked one in the sweep that keeps
    # the choices, the others (the uniform DTMC's means among them) in sweeps of their own
    monkeypatch.setattr(sweep, "SWEEP_BYTES", 1)
    monkeypatch.setattr(sweep, "SWEEP_SHARE", 0.0)
    kept: list[bool] = []
    whole = sweep.run

    def counted(*args: Any, **kwargs: Any) -> Any:
        kept.append((len(args) > 5 and args[5] is not None) or "keep" in kwargs)
        return whole(*args, **kwargs)

    monkeypatch.setattr(sweep, "run", counted)
    path, consts = CASES["uav"]
    low = lowered(load(path, consts).model, "nondet")
    names = tuple(n for p in low.model.properties for n, _ in property_variants(low, p))
    means = tuple(p.name for p in low.model.properties)
    ex = extract_for(low, ("success_max",), None, WitnessRequest("success_max", 3))
    memory = explicit.answer(low, names, "MDP", lambda *_: None, extract=ex, uniform=means)
    with scratch.made(str(tmp_path)) as into:
        streamed = explicit.answer(low, names, "MDP", lambda *_: None, extract=ex,
                                   uniform=means, scratch=str(into))
    assert memory is not None and streamed is not None
    assert kept[0] and len(kept) > 1 and not any(kept[1:])
    assert streamed.values == pytest.approx(memory.values, rel=1e-12, abs=1e-12)
    assert streamed.uniform is not None and memory.uniform is not None
    assert streamed.uniform.values == pytest.approx(memory.uniform.values, rel=1e-12,
                                                    abs=1e-12)
    assert streamed.uniform.transitions == memory.uniform.transitions
    _same(memory.extracted, streamed.extracted)
