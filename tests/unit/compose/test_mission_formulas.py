"""A mission's formulas inside its agents: visible when they read only constants, shared
variables, the agent's own variables and other agents' modes; one reading another
agent's own variable is E254 at the use, naming the agent and the variable."""

from __future__ import annotations

import pytest

from afsmc.compiler import load
from afsmc.diagnostics import CompileError
from afsmc.verify.core.api import run

MISSION = """machine f;
compose interleaving;
const int N = 3;
var c : [0..N] init 0 written by a;
formula half = N - 1;
formula room = c < half;
formula busy = b.mode == Run && room;
formula bx = b.x > 0;
agent a {
    var x : [0..N] init 0;
    mode Idle = 0 initial;
    mode Done = 1 final;
    action Go in Idle when x < half && (busy || b.mode == Stop) {
        x += 1, c := min(c + 1, N);
    }
    action Wait in Idle when x < half && !(busy || b.mode == Stop) {
        0.5: goto Idle;
        0.5: goto Done;
    }
    action End in Idle when x >= half {
        goto Done;
    }
}
agent b {
    var x : [0..N] init 0;
    mode Run = 0 initial;
    mode Stop = 1 final;
    action Go in Run when x < half {
        0.9: x += 1;
        0.1: goto Stop;
    }
    action End in Run when x >= half {
        goto Stop;
    }
}
label done = a.mode == Done && a.x == 2 && b.mode == Run;
property p = P=? [ F "done" ];
"""
# the same mission with the formulas written out inside the agents
INLINED = (MISSION.replace("x < half && (busy || b.mode == Stop)",
                           "x < N - 1 && (b.mode == 0 && c < N - 1 || b.mode == 1)")
           .replace("x < half && !(busy || b.mode == Stop)",
                    "x < N - 1 && !(b.mode == 0 && c < N - 1 || b.mode == 1)")
           .replace("x >= half", "x >= N - 1").replace("x < half", "x < N - 1"))


def test_an_agent_reads_the_missions_formulas() -> None:
    checked = load("f.afsm", {}, text=MISSION)
    assert not [d for d in checked.diagnostics if d.is_error]


@pytest.mark.storm
def test_the_formulas_mean_what_they_say_written_out() -> None:
    pytest.importorskip("stormpy")
    assert "half" not in INLINED.split("agent a", 1)[1].split("label", 1)[0]
    got = run("f.afsm", text=MISSION, uniform=False).property("p")
    want = run("f.afsm", text=INLINED, uniform=False).property("p")
    assert got.min is not None and want.min is not None and got.max is not None
    assert (got.min, got.max) == pytest.approx((want.min, want.max), abs=1e-9)
    assert got.min < got.max  # the order of the agents matters: the formulas are read


def test_a_formula_over_another_agents_variable_is_named() -> None:
    text = MISSION.replace("action End in Idle when x >= half", "action End in Idle when bx")
    with pytest.raises(CompileError) as err:
        load("f.afsm", {}, text=text)
    diags = [d for d in err.value.diagnostics if d.is_error]
    assert [d.code for d in diags] == ["E254"], diags
    msg = diags[0].message
    assert "agent a" in msg and "'bx'" in msg and "b.x" in msg
    assert diags[0].span is not None and text[diags[0].span.start:].startswith("bx {")
