"""A composed mission against a PRISM model of it written by hand (charge_pair.prism),
independently of the compiler: the same state count and the same value of every
property, min and max."""

from __future__ import annotations

import os

import pytest

from afsmc.lower.reduce import Reductions
from afsmc.verify.core.api import run

HERE = os.path.dirname(__file__)
QUERIES = {
    "done": ('P{}=? [F "done"]', "P"),
    "lost": ('P{}=? [F "lost"]', "P"),
    "soon": ('P{}=? [F<=6 "done"]', "P"),
    "charged": ('R{{"charging"}}{}=? [F "done"|"lost"]', "R"),
    "worked": ('R{{"jobs"}}{}=? [F "done"|"lost"]', "R"),
}


def _by_hand() -> tuple[int, dict[str, float]]:
    import stormpy

    prog = stormpy.parse_prism_program(os.path.join(HERE, "charge_pair.prism"))
    out: dict[str, float] = {}
    states = 0
    for name, (text, _) in QUERIES.items():
        for opt in ("min", "max"):
            props = stormpy.parse_properties(text.format(opt), prog)
            opts = stormpy.BuilderOptions([p.get_raw_formula() for p in props])
            opts.set_build_choice_labels()
            opts.set_build_all_labels()
            opts.set_build_all_reward_models()
            model = stormpy.build_model(prog, props)
            out[f"{name}_{opt}"] = stormpy.model_checking(model, props[0]).get_value(
                model.initial_states[0])
    full = stormpy.build_model(prog)
    states = full.nr_states
    return states, out


@pytest.mark.storm
@pytest.mark.parametrize("via", ["prism", "jani"])
def test_compiled_mission_agrees_with_the_hand_written_prism(via: str) -> None:
    pytest.importorskip("stormpy")
    states, expected = _by_hand()
    path = os.path.join(HERE, "charge_pair.afsm")
    plain = run(path, via=via, uniform=False, reductions=Reductions.none())
    assert plain.model.states == states
    # the exact reductions (on by default) give the same values on fewer states
    reduced = run(path, via=via, uniform=False)
    assert reduced.model.states < states
    for result in (plain, reduced):
        assert {r.name for r in result.properties} == set(QUERIES)
        for r in result.properties:
            assert r.min == pytest.approx(expected[f"{r.name}_min"], rel=1e-6, abs=1e-9), r.name
            assert r.max == pytest.approx(expected[f"{r.name}_max"], rel=1e-6, abs=1e-9), r.name


@pytest.mark.storm
def test_the_heading_says_the_agents_order_is_a_choice() -> None:
    from afsmc.commands.verify import render

    res = run(os.path.join(HERE, "charge_pair.afsm"))
    assert res.composition == "interleaving"
    assert render(res).splitlines()[0].endswith(
        ": min and max bound every property over the interval constants' floor/ceil choices "
        "and the order in which the agents move")
    assert res.uncertainty == ("interval constants", "agent order")
