"""`agent.mode in {...}` in a composed mission: in an agent, another agent's or its own
mode; in the mission's labels and properties, any agent's. It means what the comparisons
it stands for mean (`b.mode == Idle || b.mode == Busy`): the same compiled model. A mode
that agent lacks is E215 naming the agent; an agent that is none, or an agent's mode in a
single machine, E253."""

from __future__ import annotations

import re

import pytest

from afsmc.backends.prism import emit
from afsmc.compiler import load, lowered
from afsmc.diagnostics import CompileError
from afsmc.lower.reduce import Reductions
from afsmc.syntax.fmt import format_text

PAIR = """machine mi;
compose interleaving;
agent a {
    var n : [0..2] init 0;
    mode Work = 0 initial;
    mode Rest = 1;
    mode Done = 2 final;
    action Step in Work when n < 2 && b.mode in {Idle, 1} { n += 1, goto Rest; }
    action Back in Rest when a.mode in {Rest} { goto Work; }
    action Finish in Work when n == 2 { goto Done; }
}
agent b {
    mode Idle = 0 initial;
    mode Busy = 1;
    mode Off = 2 final;
    action Go in Idle when a.mode in {Work, Rest} { goto Busy; }
    action Stop in Busy when a.mode in {0..1} { goto Idle; }
    action End in {Idle, Busy} when a.mode in * except {Work, Rest} { goto Off; }
}
label both = a.mode in {Done} && b.mode in {Off};
property both = Pmax=? [ F "both" ];
"""
WRITTEN = (PAIR.replace("b.mode in {Idle, 1}", "(b.mode == Idle || b.mode == Busy)")
           .replace("a.mode in {Rest}", "mode == Rest")
           .replace("a.mode in {Work, Rest}", "(a.mode == Work || a.mode == Rest)")
           .replace("a.mode in {0..1}", "(a.mode == Work || a.mode == Rest)")
           .replace("a.mode in * except {Work, Rest}", "a.mode == Done")
           .replace("a.mode in {Done}", "a.mode == Done")
           .replace("b.mode in {Off}", "b.mode == Off"))


def _prism(text: str) -> str:
    model = load("mi.afsm", {}, text=text).model
    out = emit(lowered(model, reductions=Reductions.none())).model
    return re.sub(r"//[^\n]*", "", out)


def test_mode_in_compiles_as_the_comparisons_it_stands_for() -> None:
    assert ".mode in" not in WRITTEN
    assert _prism(PAIR) == _prism(WRITTEN)


def test_mode_in_is_formatted_back() -> None:
    out = format_text(PAIR, "mi.afsm")
    assert "b.mode in {Idle, 1}" in out and "a.mode in * except {Work, Rest}" in out
    assert _prism(out) == _prism(PAIR)


@pytest.mark.parametrize("text, code, message", [
    (PAIR.replace("{Idle, 1}", "{Idle, Nap}"), "E215", "'Nap' is not a mode of agent b"),
    (PAIR.replace("{Idle, 1}", "{Idle, 7}"), "E215", "no mode of agent b has number 7"),
    (PAIR.replace("a.mode in {Done} &&", "c.mode in {Done} &&"), "E253", "'c' is no agent"),
    ("machine m;\nmode A initial final;\nlabel l = x.mode in {A};\n", "E253",
     "'x.mode' is the mode of an agent, and this machine has no agents"),
])
def test_a_wrong_mode_in_is_precise(text: str, code: str, message: str) -> None:
    with pytest.raises(CompileError) as info:
        load("mi.afsm", {}, text=text)
    assert [(d.code, d.message) for d in info.value.diagnostics if d.is_error] == [
        (code, message)]
