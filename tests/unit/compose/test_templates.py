"""Agent templates (`agent Robot(b0, Grant) { ... }`, `agents r1 = Robot(...), ...;`): an
instance is the template written out, so the charger pair written as one template with
two instances (examples/charging_fleet.afsm) is the model of the pair written out
(examples/charging.afsm): the same PRISM text, states and values; a diagnostic about the
template's text points at the template and names the instance."""

from __future__ import annotations

import os
import re

import pytest

from afsmc.backends.prism import emit
from afsmc.compiler import load, lowered
from afsmc.diagnostics import CompileError, Diagnostic
from afsmc.lower.reduce import Reductions
from afsmc.lsp.analysis import analyse_fast
from afsmc.lsp.index import build, hover
from afsmc.syntax.fmt import format_text
from afsmc.verify.core.api import run
from tests.conftest import ROOT

WRITTEN_OUT = os.path.join(ROOT, "examples", "charging.afsm")
TEMPLATE = os.path.join(ROOT, "examples", "charging_fleet.afsm")
SMALL = {"ORDERS": 2, "T_LIMIT": 10}


def _prism(path: str, reductions: Reductions | None) -> str:
    """The PRISM model without its comments (they name the file and its lines) and the
    mission's name."""
    model = load(path, {k: str(v) for k, v in SMALL.items()}).model
    text = emit(lowered(model, reductions=reductions)).model
    text = re.sub(r"//[^\n]*", "", text)
    return "\n".join(line.rstrip() for line in text.splitlines())


@pytest.mark.parametrize("reductions", [None, Reductions.none()], ids=["reduced", "plain"])
def test_the_template_pair_compiles_to_the_written_out_prism(
        reductions: Reductions | None) -> None:
    written, made = _prism(WRITTEN_OUT, reductions), _prism(TEMPLATE, reductions)
    assert "module r1" in made and "module r2" in made and "Grant2" in made
    assert made == written


@pytest.mark.storm
def test_the_template_pair_has_the_written_out_states_and_values() -> None:
    pytest.importorskip("stormpy")
    a, b = run(WRITTEN_OUT, consts=SMALL), run(TEMPLATE, consts=SMALL)
    assert a.model.states == b.model.states > 100
    assert [p.name for p in a.properties] == [p.name for p in b.properties]
    for x, y in zip(a.properties, b.properties, strict=True):
        for key in ("min", "max", "uniform", "value"):
            assert getattr(x, key) == getattr(y, key), (x.name, key)


PAIR = """machine pair;
compose interleaving;
const int K = 2;
var moves_a : [0..4] init 0 clamp written by a;
var moves_b : [0..4] init 0 clamp written by b;
agent Walker(start, Meet, peer, moves) {
    var x : [0..3] init start;
    mode Go = 0 initial;
    mode Stop = 1 final;
    action Step in Go when x != 2 && x < 3 && peer.mode == Go { x += 1, moves += 1; }
    action Halt in Go when x == 3 || peer.mode == Stop { goto Stop; }
    sync action Meet in Go when x == 2 && peer.mode == Go { x += 1; }
}
agents a = Walker(0, Hello, b, moves_a), b = Walker(K - 1, Hello, a, moves_b);
label met = a.x == 3 && b.x == 3 && moves_a >= 2;
property met = Pmax=? [ F "met" ];
"""


def _errors(text: str) -> list[Diagnostic]:
    with pytest.raises(CompileError) as info:
        load("pair.afsm", {}, text=text)
    return [d for d in info.value.diagnostics if d.is_error]


def test_instances_are_agents_with_the_arguments_in_place() -> None:
    model = load("pair.afsm", {}, text=PAIR).model
    assert model.composition is not None
    agents = {a.name: a for a in model.composition.agents}
    assert list(agents) == ["a", "b"]
    assert agents["a"].syncs == agents["b"].syncs == ("Hello",)
    inits = {v.name: v.init for v in model.variables}
    assert inits["a_x"] == 0 and inits["b_x"] == 1
    assert dict(model.composition.writers) == {"moves_a": ("a",), "moves_b": ("b",)}


@pytest.mark.storm
def test_the_instances_meet() -> None:
    """a walks 0 -> 2 (two moves), b 1 -> 2, they meet (both to 3): one order gets there."""
    pytest.importorskip("stormpy")
    (met,) = run("pair.afsm", text=PAIR).properties
    assert met.max == 1


def test_an_error_in_the_template_points_at_it_and_names_each_instance() -> None:
    text = PAIR.replace("x += 1, moves", "x += y, moves")
    errors = _errors(text)
    assert [d.code for d in errors] == ["E203", "E203"]
    assert [d.message for d in errors] == ["agent a: 'y' is not declared",
                                           "agent b: 'y' is not declared"]
    assert all(d.span is not None and d.span.line == 10 for d in errors)


def test_an_argument_is_checked_where_the_template_uses_it() -> None:
    text = PAIR.replace("Walker(K - 1, Hello, a,", "Walker(K + 5, Hello, a,")
    d = _errors(text)[0]
    assert d.message == "agent b: initial value 7 of 'x' is outside [0..3]"
    assert d.span is not None and d.span.line == 7  # `init start`, in the template


@pytest.mark.parametrize("instances, message, at", [
    ("a = Walker(0, Hello, b, moves_a), b = Walker(1, Hello, a)",
     "agent b: the template Walker(start, Meet, peer, moves) takes 4 arguments, given 3", 14),
    ("a = Walker(0, Hello, b, moves_a), b = Runner(1, Hello, a, moves_b)",
     "'Runner' is no agent template (templates: Walker)", 14),
    ("a = Walker(0, Hello, b, moves_a), b = Walker(1, 2, a, moves_b)",
     "agent b: the parameter 'Meet' of template Walker stands where a name must (a variable "
     "written, an action, a mode, an agent), but its argument is an expression", 12),
])
def test_a_wrong_instance_is_e253(instances: str, message: str, at: int) -> None:
    text = PAIR.replace("a = Walker(0, Hello, b, moves_a), b = Walker(K - 1, Hello, a, moves_b)", instances)
    errors = _errors(text)
    assert [(d.code, d.message) for d in errors] == [("E253", message)]
    assert errors[0].span is not None and errors[0].span.line == at


def test_a_template_formats_and_reads_back_the_same() -> None:
    squeezed = PAIR.replace("\n    ", " ").replace("Walker(K - 1,", "Walker(K-1,")
    out = format_text(squeezed, "pair.afsm")
    assert "agent Walker(start, Meet, peer, moves) {\n    var x" in out
    assert "agents a = Walker(0, Hello, b, moves_a), b = Walker(K - 1, Hello, a, moves_b);" in out
    assert format_text(out, "pair.afsm") == out
    def state(text: str) -> list[tuple[str, int, int, float]]:
        return [(v.name, v.lo, v.hi, v.init) for v in load("pair.afsm", {}, text=text).model.variables]
    assert state(out) == state(PAIR)


def test_the_language_server_takes_a_template() -> None:
    with open(TEMPLATE, encoding="utf-8") as f:
        text = f.read()
    fast = analyse_fast(text, "charging_fleet.afsm")
    assert fast.module is not None and fast.model is not None and not fast.diagnostics
    idx = build(fast.module, text)
    assert ("value", "B_FULL") in idx.defs and ("action", "Pick") in idx.defs
    for offset in range(len(text)):  # every place a hover or a definition may be asked
        occ = idx.at(offset)
        d = idx.definition(occ) if occ is not None else None
        if d is not None:
            assert hover(d, text, fast.model).startswith("```afsm")
    use = text.index("Robot(B_FULL") + len("Robot(")
    occ = idx.at(use)
    assert occ is not None and occ.name == "B_FULL" and idx.definition(occ) is not None
