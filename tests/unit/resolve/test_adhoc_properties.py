"""Ad-hoc properties (`verify --formula`) are resolved against the checked model, as its
own properties are, and never by adding them to the file's text and loading it again
(afsmc.compiler.with_properties, afsmc.resolve.resolver.PropertyScope)."""

from __future__ import annotations

from pathlib import Path

import pytest

import afsmc
from afsmc import compiler
from afsmc.diagnostics import CompileError
from afsmc.model.pretty import show
from afsmc.verify import load_with_formulas

ROOT = Path(__file__).resolve().parents[3]
PATROL = str(ROOT / "examples" / "patrol.afsm")
TWO_UAV = str(ROOT / "examples" / "two_uav.afsm")

SMALL = """machine small;
const int N = 3;
formula far = x >= N;
var x : [0..5] init 0;
mode A = 0 initial;
mode B = 1 final;
label there = mode == B;
action Go in A when x < 5 weight 1 { 0.5: x += 1; 0.5: goto B; }
action Stop in A when x == 5 weight 0.9 { goto B; }
property reach = P=? [ F "there" & x > 1 ];
"""


def test_an_adhoc_property_is_the_declared_property_of_the_same_text(tmp_path: Path) -> None:
    path = tmp_path / "small.afsm"
    path.write_text(SMALL)
    loaded = load_with_formulas(str(path), None, ['P=? [ F "there" & x > 1 ]'])
    declared, adhoc = loaded.model.properties
    assert loaded.adhoc == ["adhoc"] and adhoc.name == "adhoc"
    # the same IR: the same expression, printed as the backends print it
    assert show.show(declared.path.target, 0) == show.show(adhoc.path.target, 0) \
        == '"there" && x > 1'
    assert declared.path.kind == adhoc.path.kind == "F"
    assert (declared.kind, declared.opt, declared.reward, declared.text) == (
        adhoc.kind, adhoc.opt, adhoc.reward, adhoc.text)
    assert adhoc.span is not None and adhoc.span.source.path == "--formula"


def test_the_file_is_loaded_once_and_its_checked_model_is_kept(tmp_path: Path,
                                                                monkeypatch: pytest.MonkeyPatch
                                                                ) -> None:
    path = tmp_path / "small.afsm"
    path.write_text(SMALL)
    mission = afsmc.load(str(path))
    loads: list[str] = []
    real = compiler.load

    def counted(*args: object, **kwargs: object) -> compiler.Checked:
        loads.append(str(args[0]))
        return real(*args, **kwargs)  # type: ignore[arg-type]

    monkeypatch.setattr("afsmc.verify.core.api.load", counted)
    res = mission.verify(formulas=["P=? [ F x >= 2 ]"], uniform=False)
    assert loads == []  # Mission.verify used the mission's own checked model
    assert mission.model.properties[-1].name == "reach"  # and left it as it was
    # the value of the ad-hoc formula is that of the same declared property
    direct = afsmc.load(str(path)).verify(formulas=["P=? [ F x >= 2 ]"], uniform=False)
    assert res.value("adhoc") == direct.value("adhoc")


def test_each_formulas_errors_are_its_own_even_at_the_same_column(tmp_path: Path) -> None:
    path = tmp_path / "small.afsm"
    path.write_text(SMALL)
    with pytest.raises(CompileError) as err:
        load_with_formulas(str(path), None, ["P=? [ F y > 1 ]", "P=? [ F z > 1 ]"])
    assert [(d.code, d.span.source.text if d.span else None) for d in err.value.diagnostics
            if d.is_error] == [("E203", "P=? [ F y > 1 ]"), ("E203", "P=? [ F z > 1 ]")]


def test_a_formulas_undefined_expression_is_reported_in_the_formula(tmp_path: Path) -> None:
    path = tmp_path / "small.afsm"
    path.write_text(SMALL)
    with pytest.raises(CompileError) as err:
        load_with_formulas(str(path), None, ["P=? [ F x / 0 > 1 ]"])
    (d,) = [d for d in err.value.diagnostics if d.is_error]
    assert d.code == "E245" and d.span is not None and d.span.source.path == "--formula"
    assert (d.span.line, d.span.column) == (1, 9)


def test_what_a_formula_reads_is_no_longer_said_to_be_unused(tmp_path: Path) -> None:
    path = tmp_path / "small.afsm"
    path.write_text(SMALL)
    plain = compiler.load(str(path))
    assert any(d.code == "W304" and "formula far" in d.message for d in plain.diagnostics)
    loaded = load_with_formulas(str(path), None, ["P=? [ F far ]"])
    assert not any(d.code == "W304" and "formula far" in d.message for d in loaded.warnings)
    # the file's model and warnings are not changed by it
    assert any(d.code == "W304" and "formula far" in d.message for d in plain.diagnostics)
    assert [p.name for p in plain.model.properties] == ["reach"]


def test_a_composed_missions_formula_names_an_agents_mode() -> None:
    loaded = load_with_formulas(TWO_UAV, None, ["P=? [ F uav1.mode == Search ]"])
    prop = loaded.model.properties[-1]
    assert prop.name == "adhoc" and "uav1_mode" in str(prop.path.target)
    with pytest.raises(CompileError) as err:
        load_with_formulas(TWO_UAV, None, ["P=? [ F mode == 2 ]"])
    assert "E253" in [d.code for d in err.value.diagnostics]  # which agent's mode?
    assert all(d.span is not None and d.span.source.path == "--formula"
               for d in err.value.diagnostics)


def test_adhoc_names_avoid_every_word_of_the_file() -> None:
    text = Path(PATROL).read_text() + "// adhoc adhoc2\n"
    loaded = load_with_formulas(PATROL, None, ['P=? [ F "done" ]'] * 2, text=text)
    assert loaded.adhoc == ["adhoc3", "adhoc4"]
