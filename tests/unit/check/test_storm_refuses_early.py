"""Fail early (issue 50): what `afsmc verify` refuses only after building the model, `check`
(and so the editor) reports from the spec alone: an interval probability whose end makes a
transition disappear (W307, verify's E440), a property the parametric engine cannot check
(W308, verify's E443), a total reward that may be negative (W310: Storm's E404 on an MDP, a
wrong +inf on a DTMC). Each warning is checked against verify itself: where check warns,
verify stops with that error; where it is silent, verify answers."""

from __future__ import annotations

from pathlib import Path

import pytest

from afsmc.compiler import load, lowered
from afsmc.diagnostics import CompileError
from afsmc.verify import run

BASE = """machine m;
const prob SLIP = {slip};
const prob P_F = {fault};
var x : [0..4] init 0;
mode A = 0 initial;
mode Done = 1 final;
mode Broken = 2 final;
action Up in A when x < 4 {{
    {up}
}}
action Finish in A when x == 4 {{ goto Done; }}
hazard Fault from A with probability P_F {{ goto Broken; }}
rewards s {{ true : 1; }}
property done = P=? [ F mode == Done ];
{extra}
"""
STEP = "1 - SLIP: x += 1; SLIP: skip;"
STATEFUL = "SLIP * (x + 1): skip; 1 - SLIP * (x + 1): x += 1;"


def spec(slip: str = "[0.01, 0.15]", fault: str = "[0.001, 0.01]", up: str = STEP,
         extra: str = "") -> str:
    return BASE.format(slip=slip, fault=fault, up=up, extra=extra)


def warned(text: str) -> list[tuple[str, int, str]]:
    diags = load("m.afsm", text=text).diagnostics
    return [(d.code, d.span.line if d.span else 0, d.message) for d in diags
            if d.code in ("W307", "W308", "W310")]


def verify_error(tmp_path: Path, text: str) -> str | None:
    """The code verify stops with, or None when it answers every property."""
    path = tmp_path / "m.afsm"
    path.write_text(text)
    try:
        run(str(path))
    except CompileError as exc:
        return next(d.code for d in exc.diagnostics if d.is_error)
    return None


@pytest.mark.parametrize(("text", "line", "says"), [
    (spec(slip="[0, 0.15]"), 2, "at SLIP = 0 the probability of an outcome of action Up is 0"),
    (spec(slip="[0.85, 1]", up="SLIP: x += 1; 1 - SLIP: skip;"), 2,
     "at SLIP = 1 the probability of an outcome of action Up is 0"),
    (spec(fault="[0, 0.01]"), 3, "at P_F = 0 the probability of hazard Fault is 0"),
    (spec(fault="[0.5, 1]"), 3, "at P_F = 1 the probability of hazard Fault is 1"),
    (spec(slip="[0.1, 0.3]", up=STATEFUL), 2,
     "at SLIP = 0.3 the probability of an outcome of action Up is 1.2 in the state mode = A, "
     "x = 3"),
])
def test_an_end_that_makes_a_transition_disappear_is_w307(text: str, line: int,
                                                          says: str) -> None:
    (code, at, message), = warned(text)
    assert (code, at) == ("W307", line) and message.startswith(says), message
    assert "would stop with E440" in message


@pytest.mark.parametrize(("prop", "kind"), [
    ('property nxt = P=? [ X x == 1 ];', "X (next)"),
    ('property i3 = R{"s"}=? [ I=3 ];', "I=k (an instantaneous reward)"),
    ('property cc = R{"s"}=? [ C ];', "C (an unbounded cumulative reward)"),
])
def test_a_property_the_parametric_engine_cannot_check_is_w308(prop: str, kind: str) -> None:
    (code, at, message), = warned(spec(extra=prop))
    assert (code, at) == ("W308", 15) and f"asks {kind}" in message
    assert "would stop with E443" in message


def test_nothing_is_said_of_a_box_verify_takes_or_of_a_fixed_probability() -> None:
    assert warned(spec(extra='property c5 = R{"s"}=? [ C<=5 ];\n'
                             'property g = P=? [ G<=3 x < 2 ];')) == []
    fixed = spec(slip="0.1", fault="0.01", extra='property nxt = P=? [ X x == 1 ];')
    assert warned(fixed) == []
    assert warned(spec(slip="[0.1, 0.2]", up=STATEFUL)) == []  # at most 0.2 * 4 = 0.8


@pytest.mark.storm
@pytest.mark.parametrize(("text", "code"), [
    (spec(slip="[0, 0.15]"), "E440"),
    (spec(fault="[0.5, 1]"), "E440"),
    (spec(slip="[0.1, 0.3]", up=STATEFUL), "E440"),
    (spec(extra='property nxt = P=? [ X x == 1 ];'), "E443"),
    (spec(extra='property cc = R{"s"}=? [ C ];'), "E443"),
    (spec(extra='property c5 = R{"s"}=? [ C<=5 ];'), None),
    (spec(slip="[0.1, 0.2]", up=STATEFUL), None),
])
def test_verify_stops_exactly_where_check_warns(tmp_path: Path, text: str,
                                                code: str | None) -> None:
    assert verify_error(tmp_path, text) == code
    assert bool(warned(text)) == (code is not None)


SIGNED = """machine n;
const int K = {k};
var x : [0..4] init 0 clamp;
mode A = 0 initial;
mode Done = 1 final;
action Up in A when x < 4 {{ 0.9: x += K; 0.1: skip; }}
action Finish in A when x == 4 {{ goto Done; }}
rewards gain {{ {state} : {loss}; [Up] true : 3; }}
property total = R{{"gain"}}=? [ C ];
property soon = R{{"gain"}}=? [ C<=4 ];
property till_done = R{{"gain"}}=? [ F mode == Done ];
"""


def signed(k: str = "[1, 2]", state: str = "true", loss: str = "-1") -> str:
    return SIGNED.format(k=k, state=state, loss=loss)


def test_a_total_reward_that_may_be_negative_is_w310() -> None:
    (code, at, message), = warned(signed())
    assert (code, at) == ("W310", 9) and "the total reward of \"gain\", which may be " \
        "negative" in message
    assert warned(signed(loss="1")) == []  # never negative: a total reward exists
    # negative only where x < 0, which no state has: interval bounds show it is >= 0
    assert warned(signed(state="x < 0", loss="x")) == []


@pytest.mark.storm
def test_storm_refuses_it_on_an_mdp_and_gets_its_sign_wrong_on_a_dtmc(tmp_path: Path) -> None:
    import stormpy

    from afsmc.backends.prism import emit

    # the MDP: Storm refuses the total; verify says so (E404) before building
    assert verify_error(tmp_path, signed()) == "E404"
    # the DTMC: Done's state reward of -1 every step makes the total -inf; Storm says +inf
    # (asked directly here), so verify refuses it too rather than print that
    path = tmp_path / "m.afsm"
    path.write_text(signed(k="1"))
    out = emit(lowered(load(str(path)).model, "nondet"))
    program = stormpy.parse_prism_program(str(_written(tmp_path, out.model)))
    formula = stormpy.parse_properties('R{"gain"}=? [ C ]', program)
    model = stormpy.build_model(program, formula)
    got = stormpy.model_checking(model, formula[0]).get_value(model.initial_states[0])
    assert got == float("inf")  # the wrong sign: no run collects more than 12
    assert verify_error(tmp_path, signed(k="1")) == "E404"
    assert [c for c, _, _ in warned(signed(k="1"))] == ["W310"]


def _written(tmp_path: Path, text: str) -> Path:
    p = tmp_path / "m.prism"
    p.write_text(text)
    return p
