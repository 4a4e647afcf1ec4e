"""Storm's strategies and most probable paths in mission terms (`afsmc.verify.run` with
`strategy=True` / `witness=(name, K)`): the paths are replayed through the model's own
semantics (Definition 2 on the IR, not the lowering that produced them)."""

from __future__ import annotations

import math
from typing import Any

import numpy as np
import pytest

from afsmc.lower.reduce import Reductions
from afsmc.model import ir
from afsmc.model.evaluate import Env, evaluate
from afsmc.model.semantics import effective_weight, fire_condition
from afsmc.verify import run
from afsmc.verify.outcome.witness import Step, Witness
from tests.conftest import EXAMPLES

pytestmark = pytest.mark.storm

PATROL = str(EXAMPLES / "patrol.afsm")
UAV = str(EXAMPLES / "uav.afsm")


def _env(model: ir.Model, state: dict[str, Any], choice: dict[str, str]) -> Env:
    consts: dict[str, Any] = dict(model.const_values)
    for c in model.interval_constants:
        if c.name in choice:
            assert c.interval is not None
            consts[c.name] = c.interval[0] if choice[c.name] == "floor" else c.interval[1]
    box: list[Env] = []
    env = Env(vars={k: v for k, v in state.items() if k != "mode"}, mode=state["mode"],
              consts=consts, formulas={f.name: f.value for f in model.formulas},
              labels={lb.name: lb.value for lb in model.labels},
              weight=lambda a: evaluate(effective_weight(model, model.action(a)), box[0]))
    box.append(env)
    return env


def _apply(model: ir.Model, state: dict[str, Any], outcome: ir.Outcome,
           env: Env) -> dict[str, Any]:
    new = dict(state)
    for u in outcome.updates:
        v = int(evaluate(u.value, env))
        if u.var != "mode":
            var = model.variable(u.var)
            if var.clamp:
                v = min(max(v, int(var.lo)), int(var.hi))
        new[u.var] = v
    return new


def ir_step(model: ir.Model, state: dict[str, Any], step: Step) -> tuple[float, dict[str, Any]]:
    """Definition 2 on the IR: the action that fires in `state` must be the step's; the
    probability of reaching the step's next state (hazards first, then the action's
    outcomes) and that state."""
    choice = dict(step.choice)
    env = _env(model, state, choice)
    mode = state["mode"]
    firing = [a for a in model.actions if mode in a.modes
              and bool(evaluate(fire_condition(model, a, mode), env))]
    assert [a.name for a in firing] == [step.action], (state, step)
    action = firing[0]
    by_name = {m.name: m.number for m in model.modes}
    flat = {v.display: v.name for v in model.variables}
    there = dict(state)
    for k, v in step.changes.items():
        there["mode" if k == "mode" else flat[k]] = by_name[v] if k == "mode" else int(v)
    branches: list[tuple[float, ir.Outcome]] = []
    rest = 1.0
    if action.kind == "action":
        for h in model.hazards_in(mode):
            ph = float(evaluate(h.prob, env))
            branches += [(rest * ph * float(evaluate(o.prob, env)), o) for o in h.outcomes]
            rest *= 1.0 - ph
    branches += [(rest * float(evaluate(o.prob, env)), o) for o in action.outcomes]
    total = math.fsum(p for p, o in branches if _apply(model, state, o, env) == there)
    return total, there


def replay(model: ir.Model, w: Witness) -> None:
    flat = {v.display: v.name for v in model.variables}
    state: dict[str, Any] = {flat[k]: int(v) for k, v in w.start.items()}
    state["mode"] = model.initial_mode.number
    for s in w.steps:
        p, state = ir_step(model, state, s)
        assert p == pytest.approx(s.probability, rel=1e-9, abs=1e-12), s


def check_witnesses(ws: list[Witness], value: float, model: ir.Model, target: str) -> None:
    assert ws
    probs = [w.probability for w in ws]
    assert probs == sorted(probs, reverse=True)
    for w in ws:
        assert w.confirmed
        assert w.probability == pytest.approx(math.prod(s.probability for s in w.steps),
                                              rel=1e-9)
        assert w.end_mode == target
        replay(model, w)
    assert math.fsum(probs) <= value + 1e-12


def test_patrol_strategies_name_the_constant_its_ends_action_and_mode() -> None:
    res = run(PATROL, properties=["finish"], strategy=True, uniform=False)
    p = res.property("finish")
    assert p.strategy is not None and set(p.strategy) == {"min", "max"}
    for opt, entries in p.strategy.items():
        assert entries, opt
        for e in entries:
            assert (e.constant, e.action, e.mode) == ("MOVE_COST", "Move", "Patrol")
            assert (e.end, e.value) in (("floor", 1), ("ceil", 2))
            assert e.states > 0
    # the max moves cheaply wherever it matters; the min spends more battery somewhere
    assert {e.end for e in p.strategy["max"]} == {"floor"}
    assert "ceil" in {e.end for e in p.strategy["min"]}
    js = p.to_json()["strategy"]
    assert isinstance(js, dict)
    assert set(js["min"][0]) >= {"constant", "end", "action", "mode", "states"}


def test_patrol_witnesses_descend_multiply_and_replay_through_the_semantics() -> None:
    from afsmc.compiler import load

    model = load(PATROL).model
    for direction in ("min", "max"):
        res = run(PATROL, properties=["finish"], witness=("finish", 6), witness_dir=direction,
                  reductions=Reductions.none(), uniform=False)
        p = res.property("finish")
        assert p.witnesses is not None and len(p.witnesses) == 6
        assert p.witness_of == direction
        value = p.min if direction == "min" else p.max
        assert value is not None
        check_witnesses(p.witnesses, value, model, "Finished")


def test_a_hazard_path_names_the_hazard() -> None:
    from afsmc.compiler import load

    model = load(PATROL).model
    res = run(PATROL, properties=["fault"], witness=("fault", 3), reductions=Reductions.none(),
              uniform=False)
    p = res.property("fault")
    assert p.witnesses is not None and p.max is not None
    check_witnesses(p.witnesses, p.max, model, "Halted")
    assert p.witnesses[0].steps[-1].hazard == "Fault"


def test_reductions_keep_the_path_probabilities() -> None:
    """With the reductions (default) the states differ (reset dead variables), the paths'
    probabilities do not."""
    plain = run(PATROL, properties=["finish"], witness=("finish", 4),
                reductions=Reductions.none(), uniform=False).property("finish").witnesses
    reduced = run(PATROL, properties=["finish"], witness=("finish", 4),
                  uniform=False).property("finish").witnesses
    assert plain is not None and reduced is not None
    assert [w.probability for w in plain] == pytest.approx([w.probability for w in reduced])
    assert all(w.confirmed for w in reduced)


@pytest.mark.slow
def test_a_symbolic_engine_rechecks_with_the_sparse_one() -> None:
    res = run(PATROL, properties=["finish"], engine="dd", strategy=True, uniform=False)
    p = res.property("finish")
    assert res.model.engine == "dd"
    assert p.strategy is not None and p.strategy["max"]


@pytest.mark.slow
def test_uav_default_strategy_names_interval_constants_and_ends() -> None:
    res = run(UAV, properties=["success"], strategy=True, witness=("success", 3),
              uniform=False)
    p = res.property("success")
    assert p.strategy is not None
    constants = {c.name for c in __import__("afsmc.compiler", fromlist=["load"]).load(
        UAV).model.interval_constants}
    for opt in ("min", "max"):
        assert p.strategy[opt]
        assert {e.constant for e in p.strategy[opt]} <= constants
        assert len({e.constant for e in p.strategy[opt]}) >= 5
    # the worst case takes the longer durations where they matter, the best the shorter
    assert {e.end for e in p.strategy["min"]} == {"ceil"}
    assert {e.end for e in p.strategy["max"]} == {"floor"}
    assert p.witnesses is not None and p.max is not None
    probs = np.array([w.probability for w in p.witnesses])
    assert (np.diff(probs) <= 0).all() and probs.sum() <= p.max


REWARDED = """
machine m;

const int DUR = [2, 3];
var t : [0..12] init 0 clamp;

mode A = 0 initial;
mode Done = 1 final;

action Work in A when t < 12 {
    0.5: t += DUR, goto Done;
    0.5: t += DUR;
}
action Stop in A when t >= 12 { goto Done; }

label late = t > 4;
rewards work { [Work] true : 1; }
rewards time { [Work] true : t; }
property late = P=? [ F mode == Done && t > 4 ];
property works = R{"work"}=? [ F mode == Done ];
property time = R{"time"}=? [ F mode == Done ];
"""


def test_the_variant_labels_keep_every_value(tmp_path: Any) -> None:
    """With --strategy each floor/ceil command gets its own action label in the PRISM
    text, and its action rewards are repeated for it: no value changes."""
    path = tmp_path / "m.afsm"
    path.write_text(REWARDED)
    plain = run(str(path), uniform=False)
    labelled = run(str(path), strategy=True, uniform=False)
    for a, b in zip(plain.properties, labelled.properties, strict=True):
        assert (a.min, a.max) == pytest.approx((b.min, b.max), rel=1e-12), a.name
    time = labelled.property("time")
    assert time.strategy is not None and time.min is not None and time.max is not None
    assert time.max > time.min  # t grows by DUR: [2, 3]


def test_a_threshold_on_one_variable_separates_the_ends() -> None:
    from afsmc.compiler import load, lowered
    from afsmc.verify.engines.strategy_storm import Group
    from afsmc.verify.outcome.strategy import summarise

    low = lowered(load(PATROL).model, "nondet", None)
    lo = next(i for i, c in enumerate(low.commands) if c.choice == (("MOVE_COST", "lo"),))
    hi = next(i for i, c in enumerate(low.commands) if c.choice == (("MOVE_COST", "hi"),))
    variables = ("mode", "cell", "rounds", "battery")
    groups = [Group(lo, 0, 7, (0, 0, 0, 10), (0, 4, 2, 20)),
              Group(hi, 0, 3, (0, 0, 1, 4), (0, 4, 2, 9)),
              Group(hi, 0, 2, (0, 0, 0, 4), (0, 1, 0, 5), matters=False)]
    entries = {e.end: e for e in summarise(groups, variables, low)}
    assert entries["floor"].when == "battery >= 10" and entries["floor"].states == 7
    assert entries["ceil"].when == "battery <= 9" and entries["ceil"].states == 3
    assert entries["ceil"].indifferent == 2 and entries["ceil"].value == 2
    assert entries["ceil"].text() == \
        "MOVE_COST = 2 (ceil) in Move, mode Patrol when battery <= 9"


def test_a_witness_goes_into_other_target_states_following_a_named_strategy() -> None:
    """The hook for a failed requirement: the paths go into given states (a PRISM state
    formula, e.g. the violating ones) following the strategy named, not the property's."""
    from afsmc.compiler import load
    from afsmc.verify import check
    from afsmc.verify.outcome.strategy import witness_request

    model = load(PATROL).model
    props = [p for p in model.properties if p.name == "finish"]
    for target in ("mode=3", '"halted"'):
        w = witness_request(model, props, False, ("finish", 3), "min", target)
        assert w is not None and w.query == "finish_min" and w.target == target
        p = check(model, props, witness=w, uniform=False).properties[0]
        assert p.witnesses is not None and p.witness_of == "min"
        assert [x.end_mode for x in p.witnesses] == ["Halted"] * 3
        assert p.witnesses[0].steps[-1].hazard == "Fault"
        assert all(x.confirmed for x in p.witnesses)


def test_a_requirements_witnesses_show_how_it_is_violated_under_its_deciding_strategy() -> None:
    """`P>=` is decided by the min: its paths follow the min strategy into the states where
    "done" can no longer be reached; `P<=` by the max: its paths go into its target."""
    from afsmc.compiler import load

    model = load(PATROL).model
    res = run(PATROL, formulas=['P>=0.82 [ F "done" ]'], witness=(None, 5),
              reductions=Reductions.none(), uniform=False)
    p = res.properties[0]
    assert p.witnesses is not None and p.witness_of == "min" and p.witness_avoids
    assert p.min is not None
    check_witnesses(p.witnesses, 1.0 - p.min, model, "Halted")  # patrol misses only by a fault
    assert res.to_json()["properties"][0]["witness_violates"] is True

    res = run(PATROL, formulas=['P<=0.15 [ F "halted" ]'], witness=(None, 3),
              reductions=Reductions.none(), uniform=False)
    p = res.properties[0]
    assert p.witnesses is not None and p.witness_of == "max" and not p.witness_avoids
    assert p.max is not None
    check_witnesses(p.witnesses, p.max, model, "Halted")


def _entries(res: Any, name: str, digits: int | None = None) -> tuple[Any, Any]:
    """The strategy tables and paths as JSON; with `digits`, each float to that many
    significant digits (afsmc and Storm evaluate a probability in different orders)."""
    p = res.property(name)
    out = ({k: [e.to_json() for e in v] for k, v in (p.strategy or {}).items()},
           [w.to_json() for w in p.witnesses or []])
    return out if digits is None else _rounded(out, digits)


def _rounded(x: Any, digits: int) -> Any:
    if isinstance(x, float):
        return float(f"{x:.{digits}g}")
    if isinstance(x, dict):
        return {k: _rounded(v, digits) for k, v in x.items()}
    if isinstance(x, list | tuple):
        return type(x)(_rounded(v, digits) for v in x)
    return x


def test_the_explored_model_gives_storm_s_strategies_and_paths(monkeypatch: Any) -> None:
    """By default the strategies and paths come from afsmc's own exploration and its
    backward pass (explicit, strategy_arrays); Storm's own scheduler and path generator
    (the topological solver's route) must give the same tables and the same paths, ties
    included, up to the last digits of the probabilities. The tables are summed a chunk
    of states at a time (small chunks here: many)."""
    from afsmc.verify.engines import strategy_arrays

    monkeypatch.setattr(strategy_arrays, "CHUNK", 97)
    consts = {"T_LIMIT": 90, "DEADLINE": 90}
    ours = run(UAV, consts=consts, properties=["success"], strategy=True,
               witness=("success", 12), uniform=False, isolate=False)
    storms = run(UAV, consts=consts, properties=["success"], strategy=True,
                 witness=("success", 12), uniform=False, solver="topological")
    assert (ours.model.engine, ours.model.solver) == ("explicit", "acyclic")
    assert storms.model.solver == "topological"
    assert _entries(ours, "success", 12) == _entries(storms, "success", 12)
    assert ours.property("success").strategy
    assert len(ours.property("success").witnesses or []) >= 5


def test_storm_s_model_gives_storm_s_strategies_and_paths(monkeypatch: Any) -> None:
    """Where afsmc's exploration does not apply, the backward pass over Storm's exported
    model gives them (strategy_arrays on Storm's arrays), equal to Storm's own to the bit."""
    from afsmc.verify.core import model_loop as runner

    monkeypatch.setattr(runner, "applies", lambda *_a: False)
    consts = {"T_LIMIT": 90, "DEADLINE": 90}
    ours = run(UAV, consts=consts, properties=["success"], strategy=True,
               witness=("success", 12), uniform=False, isolate=False)
    storms = run(UAV, consts=consts, properties=["success"], strategy=True,
                 witness=("success", 12), uniform=False, solver="topological", isolate=False)
    assert (ours.model.engine, ours.model.solver) == ("sparse", "acyclic")
    assert _entries(ours, "success") == _entries(storms, "success")
    assert ours.property("success").strategy


def test_an_expected_reward_s_strategies_come_from_the_backward_pass_as_storm_s() -> None:
    """A strategy of an expected reward (`drops`, R [F T]) also comes from afsmc's own
    exploration and backward pass, and equals Storm's (its topological solver's
    scheduler): the same ends in the same states, the same counts where they matter."""
    consts = {"T_LIMIT": 90, "DEADLINE": 90}
    ours = run(UAV, consts=consts, properties=["drops"], strategy=True, uniform=False,
               isolate=False)
    storms = run(UAV, consts=consts, properties=["drops"], strategy=True, uniform=False,
                 solver="topological", isolate=False)
    assert (ours.model.engine, ours.model.solver) == ("explicit", "acyclic")
    assert storms.model.solver == "topological"
    assert ours.property("drops").strategy
    assert _entries(ours, "drops", 12) == _entries(storms, "drops", 12)
