"""The diagnostics of composition: each names the agent and points at the text."""

from __future__ import annotations

import pytest

from afsmc.compiler import load
from afsmc.diagnostics import CompileError, Diagnostic

HEAD = "machine pair;\ncompose interleaving;\nvar found : [0..2] init 0 written by a;\n"
A = """agent a {
    var n : [0..2] init 0;
    mode Work = 0 initial;
    mode Done = 1 final;
    action Step in Work when n < 2 weight 0.5 { n += 1; }
    action Finish in Work when n == 2 weight 0.7 { found := 1, goto Done; }
    %s
}
"""
B = """agent b {
    mode Work = 0 initial;
    mode Done = 1 final;
    action Finish in Work when %s weight 0.2 { goto Done; }
    %s
}
property done = P=? [ F b.mode == Done ];
"""


def _errors(text: str) -> list[Diagnostic]:
    with pytest.raises(CompileError) as info:
        load("pair.afsm", {}, text=text)
    return [d for d in info.value.diagnostics if d.is_error]


def _one(text: str, code: str) -> Diagnostic:
    errors = _errors(text)
    assert [d.code for d in errors] == [code], [(d.code, d.message) for d in errors]
    return errors[0]


def _at(d: Diagnostic, text: str) -> str:
    assert d.span is not None
    return text[d.span.start:d.span.end]


def test_a_write_conflict_names_both_agents_and_the_second_write() -> None:
    text = HEAD.replace(" written by a", "") + A % "sync action Meet in Work { found := 2; }" \
        + B % ("true", "sync action Meet in Work { found := 0; }")
    d = _one(text, "E311")
    assert "agents a and b" in d.message and "Meet" in d.message
    assert _at(d, text) == "found := 0"
    assert d.related and _at_related(d, text) == "found := 2"


def _at_related(d: Diagnostic, text: str) -> str:
    span = d.related[0].span
    return text[span.start:span.end]


def test_a_sync_without_partner_names_its_agent_and_the_action() -> None:
    text = HEAD + A % "sync action Meet in Work { skip; }" + B % ("true", "")
    d = _one(text, "E312")
    assert d.message.startswith("agent a:") and "Meet" in d.message
    assert _at(d, text) == "Meet"


def test_reading_another_agent_s_variable_names_both_and_the_reference() -> None:
    text = HEAD + A % "" + B % ("a.n == 2", "")
    d = _one(text, "E254")
    assert "agent b reads a.n" in d.message
    assert _at(d, text) == "a.n"


def test_writing_a_shared_variable_of_another_writer_is_refused() -> None:
    text = HEAD + A % "" + B % ("true", "action Mark in Work { found := 2; }")
    d = _one(text, "E255")
    assert "agent b writes 'found'" in d.message
    assert _at(d, text) == "found := 2"


def test_a_weight_tie_within_an_agent_names_the_agent_and_a_state() -> None:
    text = HEAD + A.replace("weight 0.7", "weight 0.5").replace("n == 2", "n >= 0") % "" \
        + B % ("true", "")
    d = _one(text, "E313")
    assert d.message.startswith("agent a:") and "Step" in d.message and "Finish" in d.message
    assert "n = " in d.message  # the witness state
    assert _at(d, text) == "0.5"  # the weight of one of them


def test_reading_another_agent_s_mode_is_allowed() -> None:
    text = HEAD + A % "" + B % ("a.mode == Done", "")
    checked = load("pair.afsm", {}, text=text)
    assert checked.model.composition is not None
    assert [a.name for a in checked.model.composition.agents] == ["a", "b"]


def test_an_agent_without_modes_is_an_error_at_its_name() -> None:
    text = "machine x;\nagent a { mode A = 0 initial final; }\nagent b { }\n"
    d = _one(text, "E213")
    assert d.message.startswith("agent b: ") and d.span is not None
    assert text[d.span.start:d.span.end] == "b"
