"""Indexed families (`agent r[1..N] : Robot;`, afsmc.resolve.templates): the agents r1 ..
rN, each an instance of the template, its index the template's one parameter if it has
one. The oracle is the same mission with its agents written out (`agents r1 = Robot(),
...`): the same PRISM text. A diagnostic about the template names the instance and points
at the template's line; bad bounds are E253 at the family."""

from __future__ import annotations

import os
import re
from pathlib import Path

import pytest

from afsmc.backends.prism import emit
from afsmc.compiler import load, lowered
from afsmc.diagnostics import CompileError, Diagnostic
from afsmc.syntax.fmt import format_text

HERE = Path(os.path.dirname(__file__))
WRITTEN = (HERE / "fleet4.afsm").read_text(encoding="utf-8")
AGENTS = "agents r1 = Robot(), r2 = Robot(), r3 = Robot(), r4 = Robot();"
FAMILY = WRITTEN.replace(AGENTS, "param int N = 4;\nagent r[1..N] : Robot;")


def _prism(text: str, consts: dict[str, str] | None = None) -> str:
    model = load("fleet.afsm", consts or {}, text=text).model
    out = re.sub(r"//[^\n]*", "", emit(lowered(model)).model)
    return "\n".join(line.rstrip() for line in out.splitlines() if line.strip())


def _errors(text: str) -> list[Diagnostic]:
    with pytest.raises(CompileError) as info:
        load("fleet.afsm", {}, text=text)
    return [d for d in info.value.diagnostics if d.is_error]


def test_a_family_compiles_to_its_agents_written_out() -> None:
    assert AGENTS in WRITTEN
    family = _prism(FAMILY)
    assert "module r4" in family and "module r5" not in family
    lines = family.splitlines()
    assert "const int N = 4;" in lines  # the family's size, a param
    assert [x for x in lines if x != "const int N = 4;"] == _prism(WRITTEN).splitlines()


def test_its_size_is_a_param_given_on_the_command_line() -> None:
    # labels and rewards over a count kept in a shared variable, so that N may vary
    text = re.sub(r"label finished = [^;]*;", "label finished = free == K;", FAMILY)
    text = re.sub(r"label stranded = [^;]*;", "label stranded = free == 0;", text)
    text = re.sub(r"rewards picks \{[^}]*\}", "rewards picks { true : 1; }", text)
    model = load("fleet.afsm", {"N": "2"}, text=text).model
    assert model.composition is not None
    assert [a.name for a in model.composition.agents] == ["r1", "r2"]


def test_the_template_s_parameter_is_the_index() -> None:
    text = FAMILY.replace("agent Robot() {", "agent Robot(id) {").replace(
        "var done : [0..ORDERS] init 0;", "var done : [0..ORDERS] init 0;\n    var me : [0..9] init id;")
    model = load("fleet.afsm", {}, text=text).model
    inits = {v.name: v.init for v in model.variables}
    assert [inits[f"r{i}_me"] for i in range(1, 5)] == [1, 2, 3, 4]


def test_an_error_in_the_template_names_each_instance_at_the_template_line() -> None:
    text = FAMILY.replace("init B_FULL clamp", "init B_FULL + 5 clamp")
    errors = [d for d in _errors(text) if d.message.startswith("agent ")]
    line = next(i for i, s in enumerate(text.splitlines(), 1) if "B_FULL + 5" in s)
    assert [d.message.split(":")[0] for d in errors] == ["agent r1", "agent r2", "agent r3",
                                                         "agent r4"]
    assert all(d.span is not None and d.span.line == line for d in errors)


@pytest.mark.parametrize("family, message", [
    ("agent r[1..0] : Robot;", "the family r[1..0] must have from 1 to 64 agents"),
    ("agent r[1..M] : Robot;", "the bounds of the family r must be integers"),
    ("agent r[1..100] : Robot;", "the family r[1..100] must have from 1 to 64 agents"),
])
def test_bad_bounds_are_e253_at_the_family(family: str, message: str) -> None:
    text = WRITTEN.replace(AGENTS, family)
    errors = _errors(text)
    assert errors and errors[0].code == "E253" and message in errors[0].message, errors
    line = next(i for i, s in enumerate(text.splitlines(), 1) if s.startswith("agent r["))
    assert errors[0].span is not None and errors[0].span.line == line


def test_a_template_of_two_parameters_is_refused() -> None:
    text = FAMILY.replace("agent Robot() {", "agent Robot(a, b) {")
    errors = _errors(text)
    assert errors[0].code == "E253" and "takes 2 parameters" in errors[0].message


def test_fmt_prints_a_family_back() -> None:
    assert "agent r[1..N] : Robot;" in format_text(FAMILY)
    assert format_text(format_text(FAMILY)) == format_text(FAMILY)


def test_prism_renames_the_module_of_an_alike_instance() -> None:
    text = _prism(FAMILY)
    assert "module r2" in text.splitlines()
    for r in ("r3", "r4"):
        assert (f"module {r} = r2 [r2_mode={r}_mode, r2_b={r}_b, r2_done={r}_done, "
                f"r2_Pick={r}_Pick,") in text
    # the first module holds the mission's self-loop, so it is written out
    assert "module r1" in text.splitlines()


@pytest.mark.storm
def test_the_renamed_prism_and_the_jani_network_agree() -> None:
    from afsmc.lower.reduce import Reductions
    from afsmc.verify.core.api import run

    # the renaming is of the mission whole: the symmetry reduction's modules write each
    # other's variables
    whole = Reductions(symmetry="off")
    prism = run(str(HERE / "fleet4.afsm"), isolate=False, reductions=whole)
    jani = run(str(HERE / "fleet4.afsm"), isolate=False, via="jani", reductions=whole)
    assert prism.model.states == jani.model.states == 60_368
    for a, b in zip(prism.properties, jani.properties, strict=True):
        assert a.min is not None and b.min is not None and a.max is not None and b.max is not None
        assert abs(a.min - b.min) <= 1e-9 and abs(a.max - b.max) <= 1e-9, a.name
