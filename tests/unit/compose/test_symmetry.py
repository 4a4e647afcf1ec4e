"""Symmetry reduction (`--symmetry`, afsmc.lower.symmetry): alike agents kept in a
canonical order. The oracle is the mission without it: the same min and max for every
property (1e-9), on far fewer states (four robots: at most 1/12, as up to 4! = 24
orderings of their local states fold into one). Refused, with the reason in the
compiled header, where the mission or a property tells the agents apart."""

from __future__ import annotations

import os
import tempfile
from pathlib import Path

import pytest

from afsmc.backends.prism import emit
from afsmc.compiler import load, lowered
from afsmc.lower.reduce import Reductions
from afsmc.verify.core.api import run
from afsmc.verify.outcome.results import VerifyResult

HERE = os.path.dirname(__file__)
FLEET4 = os.path.join(HERE, "fleet4.afsm")
SYMMETRY = Reductions(symmetry="on")
WHOLE = Reductions(symmetry="off")
TEXT = Path(FLEET4).read_text(encoding="utf-8")


def _values(r: VerifyResult) -> dict[str, tuple[float | None, float | None, float | None]]:
    return {p.name: (p.min, p.max, p.value) for p in r.properties}


def _close(a: float | None, b: float | None) -> bool:
    return (a is None and b is None) or (a is not None and b is not None
                                         and abs(a - b) <= 1e-9)


def _assert_same(full: VerifyResult, reduced: VerifyResult) -> None:
    a, b = _values(full), _values(reduced)
    assert a.keys() == b.keys()
    for name in a:
        assert all(_close(x, y) for x, y in zip(a[name], b[name], strict=True)), (name, a, b)


def _header(text: str, reductions: Reductions = SYMMETRY) -> str:
    """The compiled PRISM header's line of reductions for the mission `text`."""
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "m.afsm"
        path.write_text(text, encoding="utf-8")
        out = emit(lowered(load(str(path)).model, reductions=reductions)).model
    return next(line for line in out.splitlines() if line.startswith("// Exact reductions"))


@pytest.mark.storm
def test_four_alike_robots_fold_into_a_twelfth_with_the_same_values() -> None:
    full = run(FLEET4, isolate=False, reductions=WHOLE)
    reduced = run(FLEET4, isolate=False, reductions=SYMMETRY)
    assert reduced.model.states * 12 <= full.model.states, (reduced.model.states,
                                                            full.model.states)
    _assert_same(full, reduced)


@pytest.mark.storm
def test_the_uniform_interleaving_keeps_its_values(tmp_path: Path) -> None:
    path = tmp_path / "u.afsm"
    path.write_text(TEXT.replace("compose interleaving;", "compose interleaving uniform;"),
                    encoding="utf-8")
    full = run(str(path), isolate=False, reductions=WHOLE)
    reduced = run(str(path), isolate=False, reductions=SYMMETRY)
    assert full.model.type == reduced.model.type == "dtmc"
    assert reduced.model.states < full.model.states
    _assert_same(full, reduced)


@pytest.mark.storm
def test_the_jani_route_agrees_on_the_quotient() -> None:
    prism = run(FLEET4, isolate=False, reductions=SYMMETRY)
    jani = run(FLEET4, isolate=False, reductions=SYMMETRY, via="jani")
    assert prism.model.states == jani.model.states
    _assert_same(prism, jani)


def test_the_header_names_the_reduction() -> None:
    assert "symmetry (r1, r2, r3, r4)" in _header(TEXT)
    assert "symmetry" not in _header(TEXT, Reductions())


def test_a_property_naming_one_robot_is_refused_by_name() -> None:
    text = TEXT + \
        "property one = P=? [ F r1.mode == Finished ];\n"
    assert "no symmetry: the property one tells r1 and r2 apart" in _header(text)


def test_a_label_naming_one_robot_is_refused_by_name() -> None:
    text = TEXT.replace(
        "label finished = r1.mode == Finished &&", "label finished = r1.mode == Stranded &&")
    assert "no symmetry: the label finished tells r1 and r2 apart" in _header(text)


def test_a_robot_that_starts_apart_stays_out_of_the_group() -> None:
    text = TEXT.replace(
        "agent Robot() {", "agent Robot(b0) {").replace(
        "init B_FULL clamp", "init b0 clamp").replace(
        "r1 = Robot()", "r1 = Robot(B_FULL - 1)").replace("= Robot()", "= Robot(B_FULL)")
    assert "symmetry (r2, r3, r4)" in _header(text)
    alone = text.replace("r3 = Robot(B_FULL)", "r3 = Robot(B_FULL - 2)").replace(
        "r4 = Robot(B_FULL)", "r4 = Robot(B_FULL - 3)").replace(
        "r2 = Robot(B_FULL)", "r2 = Robot(B_FULL - 1)")
    assert "symmetry (r1, r2)" in _header(alone)
    apart = alone.replace("r2 = Robot(B_FULL - 1)", "r2 = Robot(B_FULL)")
    assert "no symmetry: no two agents are alike" in _header(apart)


def test_the_charger_pair_is_refused_with_its_reason() -> None:
    root = os.path.dirname(os.path.dirname(os.path.dirname(HERE)))
    model = load(os.path.join(root, "examples", "charging.afsm")).model
    out = emit(lowered(model, reductions=SYMMETRY)).model
    assert "no symmetry:" in out


def test_fairness_is_refused() -> None:
    text = TEXT.replace("compose interleaving;",
                                                         "compose interleaving fair;")
    assert "no symmetry: fairness" in _header(text)


@pytest.mark.storm
def test_verify_notes_a_refusal_at_the_property_and_checks_the_mission_whole(
        tmp_path: Path) -> None:
    text = TEXT + "property one = P=? [ F r1.mode == Finished ];\n"
    path = tmp_path / "one.afsm"
    path.write_text(text, encoding="utf-8")
    asked = run(str(path), isolate=False, reductions=SYMMETRY, properties=["one", "shift"])
    whole = run(str(path), isolate=False, reductions=WHOLE, properties=["one", "shift"])
    notes = [d for d in asked.warnings if d.code == "N421"]
    assert len(notes) == 1 and "the property one tells r1 and r2 apart" in notes[0].message
    assert notes[0].span is not None and notes[0].span.line == text.count("\n")
    assert asked.model.states == whole.model.states
    _assert_same(whole, asked)
