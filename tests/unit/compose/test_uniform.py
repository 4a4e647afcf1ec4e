"""`compose interleaving uniform;`: who moves next is uniform among the agents that can
move (a synchronised action is taken when any of its partners is picked), a DTMC; its
values against an independent computation: the mission's semantics written by hand in
Python, its values exact rationals by recursion (the mission is acyclic up to its end),
and against `simulate`, whose scheduler it is."""

from __future__ import annotations

import os
from fractions import Fraction
from functools import cache

import pytest

from afsmc.api.simulate import simulate_file
from afsmc.compiler import load
from afsmc.diagnostics import CompileError
from afsmc.verify.core.api import run

# A robot does a job (or is lost), asks for the charger and is charged together with the
# station (a synchronised action of two partners); a third agent, a ticker, closes the
# station after three moves. Who wins the race depends on how often each agent moves.
RACE = """machine race;
compose interleaving uniform;
const prob P_JOB = 0.9;
agent robot {
    var b : [0..1] init 1;
    mode Work = 0 initial;
    mode Plug = 1;
    mode Done = 2 final;
    mode Lost = 3 final;
    action Job in Work when b > 0 {
        P_JOB:     b -= 1;
        1 - P_JOB: goto Lost;
    }
    action Ask in Work when b == 0 { goto Plug; }
    sync action Charge in Plug { goto Done; }
}
agent station {
    mode Idle = 0 initial;
    mode Served = 1 final;
    sync action Charge in Idle when ticker.mode == Open { goto Served; }
}
agent ticker {
    var n : [0..2] init 0;
    mode Open = 0 initial;
    mode Closed = 1 final;
    action Tick in Open when n < 2 { n += 1; }
    action Close in Open when n == 2 { goto Closed; }
}
label charged = robot.mode == Done;
rewards moves { [robot.Job] true : 1; [Charge] true : 1; [ticker.Tick] true : 1; }
property charged = P=? [ F "charged" ];
property soon    = P=? [ F<=3 "charged" ];
property moves   = R{"moves"}=? [ F robot.mode == Done || robot.mode == Lost || ticker.mode == Closed ];
"""
P_JOB = Fraction(9, 10)
WORK, PLUG, DONE, LOST = range(4)

# A state: (robot's mode, robot's b, station served?, ticker's n, ticker closed?)
State = tuple[int, int, bool, int, bool]


def _moves(s: State) -> list[tuple[Fraction, list[tuple[Fraction, State]], int]]:
    """Each move possible in `s`: (its probability, its outcomes, its reward `moves`), by
    the rule: each agent that can move is picked with equal probability; the charge moves
    robot and station, so it is taken when either is picked."""
    mode, b, served, n, closed = s
    robot: tuple[list[tuple[Fraction, State]], int] | None = None
    ticker: tuple[list[tuple[Fraction, State]], int] | None = None
    charge = mode == PLUG and not served and not closed
    if mode == WORK and b > 0:
        robot = ([(P_JOB, (WORK, 0, served, n, closed)), (1 - P_JOB, (LOST, b, served, n, closed))], 1)
    elif mode == WORK:
        robot = ([(Fraction(1), (PLUG, b, served, n, closed))], 0)
    elif charge:
        robot = ([(Fraction(1), (DONE, b, True, n, closed))], 1)
    if not closed:
        ticker = ([(Fraction(1), (mode, b, served, n + 1, closed))], 1) if n < 2 else \
            ([(Fraction(1), (mode, b, served, n, True))], 0)
    pickers = [robot, robot if charge else None, ticker]  # the station moves only to charge
    able = [p for p in pickers if p is not None]
    return [(Fraction(1, len(able)), outs, reward) for outs, reward in able]


def _end(s: State) -> bool:
    return s[0] in (DONE, LOST) or s[4]


@cache
def _reach(s: State, steps: int | None) -> Fraction:
    if s[0] == DONE:
        return Fraction(1)
    moves = _moves(s)
    if not moves or steps == 0:
        return Fraction(0)
    after = None if steps is None else steps - 1
    return sum((p * q * _reach(t, after) for p, outs, _ in moves for q, t in outs), Fraction(0))


@cache
def _reward(s: State) -> Fraction:
    if _end(s):
        return Fraction(0)
    return sum((p * (r + sum((q * _reward(t) for q, t in outs), Fraction(0)))
                for p, outs, r in _moves(s)), Fraction(0))


START: State = (WORK, 1, False, 0, False)


@pytest.mark.storm
@pytest.mark.parametrize("via", ["prism", "jani"])
def test_uniform_interleaving_is_the_dtmc_of_the_uniform_pick(via: str) -> None:
    pytest.importorskip("stormpy")
    res = run("race.afsm", text=RACE, via=via)
    assert res.model.type == "dtmc" and res.uncertainty == ()
    expected = {"charged": _reach(START, None), "soon": _reach(START, 3),
                "moves": _reward(START)}
    # the weight of the charge (two partners of three agents) matters: 1/2 each is not it
    assert 0 < expected["charged"] < 1
    for r in res.properties:
        assert r.value == pytest.approx(float(expected[r.name]), abs=1e-9), r.name


@pytest.mark.storm
def test_uniform_interleaving_is_exactly_the_rational_of_the_uniform_pick() -> None:
    pytest.importorskip("stormpy")
    res = run("race.afsm", text=RACE, exact=True, properties=["charged", "moves"])
    for r in res.properties:
        want = _reach(START, None) if r.name == "charged" else _reward(START)
        assert r.exact == {"value": f"{want.numerator}/{want.denominator}"}, r.name


@pytest.mark.storm
def test_the_simulator_estimates_the_uniform_value() -> None:
    pytest.importorskip("stormpy")
    exact = run("race.afsm", text=RACE).property("charged").value
    est = simulate_file("race.afsm", RACE, {}, 20_000, seed=3)["charged"]
    assert est.low <= exact <= est.high


def test_uniform_is_a_rule_of_the_interleaving_without_interval_constants() -> None:
    for text, message in [
            (RACE.replace("interleaving uniform", "timed uniform"),
             "'uniform' is a rule of the interleaving, not of the timed composition"),
            (RACE.replace("interleaving uniform", "interleaving random"),
             "'random' is no rule of the interleaving"),
            (RACE.replace("const prob P_JOB = 0.9;", "const prob P_JOB = 0.9;\n"
                          "const int LOAD = [0, 1];\nvar load : [0..1] init LOAD;"),
             "the interval constant LOAD's floor or ceil would be a choice, which 'compose "
             "interleaving uniform' (a DTMC) does not have")]:
        with pytest.raises(CompileError) as info:
            load("race.afsm", {}, text=text)
        assert message in [d.message for d in info.value.diagnostics if d.code == "E253"]


@pytest.mark.storm
def test_an_agent_moving_in_place_does_not_end_a_run() -> None:
    """starve.afsm under the uniform pick: r1 wanders in place forever while r2 waits to be
    picked; a run ends only where no agent can move, so the estimate holds the exact value
    (P_PLUG), where a run ended at r1's first step in place would not."""
    pytest.importorskip("stormpy")
    path = os.path.join(os.path.dirname(__file__), "starve.afsm")
    with open(path, encoding="utf-8") as f:
        text = f.read().replace("compose interleaving fair;", "compose interleaving uniform;")
    exact = run(path, text=text).property("both_done").value
    assert exact == pytest.approx(0.8)
    est = simulate_file(path, text, {}, 4000, seed=5, max_steps=200)["both_done"]
    assert est.low <= exact <= est.high
