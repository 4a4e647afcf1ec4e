"""`compose timed ties weight;`: at equal clocks the agent whose current action has the
larger weight moves first. Two agents whose weights may tie at equal clocks are E314,
naming both agents, with a witness state; a mission without such a tie is checked on
both routes, and its values lie within the `ties nondet` composition's min and max."""

from __future__ import annotations

import os
from pathlib import Path

import pytest

from afsmc.compiler import load
from afsmc.diagnostics import CompileError, Diagnostic
from afsmc.verify.core.api import run

PAIR = """machine pair;
compose timed ties weight;

const int T_STEP = [1, 2];
const prob P_SLIP = 0.2;

agent a clock t {
    var t : [0..6] init 0 clamp;
    mode Work = 0 initial;
    mode Done = 1 final;
    action Step in Work when t < 4 weight 0.6 {
        1 - P_SLIP: t += T_STEP;
        P_SLIP:     t += 1;
    }
    action Finish in Work when t >= 4 weight 0.6 { goto Done; }
}

agent b clock t {
    var t : [0..6] init 0 clamp;
    mode Work = 0 initial;
    mode Done = 1 final;
    action Step in Work when t < 4 weight WB { t += 1; }
    action Finish in Work when t >= 4 weight WB { goto Done; }
}

label done = a.mode == Done && b.mode == Done;
label a_first = a.mode == Done && b.mode == Work;
property done = P=? [ F "done" ];
property a_first = P=? [ F "a_first" ];
"""


def _text(wb: str, ties: str = "weight") -> str:
    return PAIR.replace("WB", wb).replace("ties weight", f"ties {ties}")


def _errors(text: str) -> list[Diagnostic]:
    try:
        return [d for d in load("pair.afsm", {}, text=text).diagnostics if d.is_error]
    except CompileError as exc:
        return [d for d in exc.diagnostics if d.is_error]


def test_equal_weights_at_equal_clocks_name_both_agents_and_a_state() -> None:
    text = _text("0.6")
    (d,) = _errors(text)
    assert d.code == "E314"
    assert "agents a and b" in d.message
    assert "a.mode = Work" in d.message and "b.mode = Work" in d.message
    assert "a.t = " in d.message and "b.t = " in d.message  # the witness: equal clocks
    assert d.span is not None and text[d.span.start:d.span.end] == "compose timed ties weight;"
    assert [r.message for r in d.related] == ["agent a", "agent b"]


def test_distinct_weights_check_clean() -> None:
    assert _errors(_text("0.8")) == []
    assert _errors(_text("0.6", "order")) == []  # the tie only matters to 'ties weight'


@pytest.mark.storm
def test_the_heavier_agent_moves_first_on_both_routes(tmp_path: Path) -> None:
    pytest.importorskip("stormpy")
    path = os.fspath(tmp_path / "pair.afsm")
    heavy = _text("0.8")
    values = {}
    for via in ("prism", "jani"):
        r = run(path, text=heavy, via=via, uniform=False)
        values[via] = {p.name: (p.min, p.max) for p in r.properties}
    for name, (lo, hi) in values["prism"].items():
        assert values["jani"][name] == pytest.approx((lo, hi), rel=1e-9, abs=1e-12), name
    # b (0.8) always moves before a at equal clocks, so a never finishes first
    assert values["prism"]["a_first"] == pytest.approx((0.0, 0.0))
    light = run(path, text=_text("0.4"), uniform=False)  # a (0.6) first at equal clocks
    assert light.property("a_first").max == pytest.approx(1.0)
    loose = run(path, text=_text("0.8", "nondet"), uniform=False)
    for p in loose.properties:
        assert p.min is not None and p.max is not None
        for got in (values["prism"][p.name], (light.property(p.name).min,
                                              light.property(p.name).max)):
            assert p.min - 1e-9 <= got[0] <= got[1] <= p.max + 1e-9, p.name
