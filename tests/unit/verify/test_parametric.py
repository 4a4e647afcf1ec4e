"""Interval probabilities with Storm's parametric engine: the min and max over the
interval bound every fixed value in it (sampled at 7 points, each verified by an ordinary
Storm model), come within the stated precision of the sampled extremes where the value is
monotone, and the PRISM and JANI routes agree."""

from __future__ import annotations

import pytest

from afsmc.compiler import load, lowered
from afsmc.diagnostics import CompileError
from afsmc.verify.engines.parametric import extremes
from afsmc.verify.plan.precision import PARAMETER_PRECISION as DEFAULT_PRECISION
from tests.conftest import EXAMPLES
from tests.unit.verify.points import value

pytestmark = pytest.mark.storm

LO, HI = 0.05, 0.15
POINTS = [LO + (HI - LO) * i / 6 for i in range(7)]
# the property and the Storm formulas of its min and max at a fixed P_SLIP (an MDP)
ASKED = {"finish": ('Pmin=? [ F "done" ]', 'Pmax=? [ F "done" ]'),
         "fault": ('Pmin=? [ F "halted" ]', 'Pmax=? [ F "halted" ]'),
         "duration": ('R{"steps"}min=? [ F "done" | "halted" ]',
                      'R{"steps"}max=? [ F "done" | "halted" ]')}


@pytest.fixture(scope="module")
def patrol(tmp_path_factory: pytest.TempPathFactory) -> object:
    text = (EXAMPLES / "patrol.afsm").read_text(encoding="utf-8")
    assert "const prob P_SLIP   = 0.1;" in text
    path = tmp_path_factory.mktemp("patrol") / "patrol.afsm"
    path.write_text(text.replace("const prob P_SLIP   = 0.1;",
                                 f"const prob P_SLIP   = [{LO}, {HI}];"), encoding="utf-8")
    return load(str(path)).model


@pytest.mark.slow
def test_min_and_max_bound_every_sampled_value_within_the_precision(patrol: object) -> None:
    model = patrol
    props = [p for p in model.properties if p.name in ASKED]  # type: ignore[attr-defined]
    found = {e.name: e for e in extremes(lowered(model, "nondet"), props)}  # type: ignore[arg-type]
    for name, (fmin, fmax) in ASKED.items():
        lows = [value(model, {"P_SLIP": p}, fmin) for p in POINTS]  # type: ignore[arg-type]
        highs = [value(model, {"P_SLIP": p}, fmax) for p in POINTS]  # type: ignore[arg-type]
        e = found[name]
        assert e.min <= min(lows) + 1e-9 and e.max >= max(highs) - 1e-9, (name, e, lows, highs)
        # each is monotone in P_SLIP here, so the sampled ends are the true extremes
        assert lows == sorted(lows) or lows == sorted(lows, reverse=True), name
        scale = max(1.0, abs(min(lows)), abs(max(highs)))
        slack = DEFAULT_PRECISION + 1e-5 * scale  # Storm's sound value iteration: 1e-6 relative
        assert min(lows) - e.min <= slack, (name, e.min, min(lows))
        assert e.max - max(highs) <= slack, (name, e.max, max(highs))
        assert LO <= e.min_at["P_SLIP"] <= HI and LO <= e.max_at["P_SLIP"] <= HI


def test_the_prism_and_jani_routes_agree(patrol: object) -> None:
    model = patrol
    low = lowered(model, "nondet")  # type: ignore[arg-type]
    props = list(model.properties)  # type: ignore[attr-defined]
    prism = extremes(low, props, via="prism")
    jani = extremes(low, props, via="jani")
    assert [e.name for e in prism] == [e.name for e in jani]
    for a, b in zip(prism, jani, strict=True):
        assert a.min == pytest.approx(b.min, abs=1e-6) and a.max == pytest.approx(b.max, abs=1e-6)


def test_a_bounded_and_an_unbounded_g_are_bounded_through_their_duals(patrol: object) -> None:
    model = patrol
    props = [p for p in model.properties  # type: ignore[attr-defined]
             if p.name in ("safe_soon", "fault")]
    got = {e.name: e for e in extremes(lowered(model, "nondet"), props)}  # type: ignore[arg-type]
    # G !halted = 1 - F halted
    assert got["safe_soon"].min == pytest.approx(1 - got["fault"].max, abs=1e-6)
    assert got["safe_soon"].max == pytest.approx(1 - got["fault"].min, abs=1e-6)


def test_an_interval_reaching_zero_is_ill_defined_and_an_open_bound_is_suggested(
        tmp_path: object) -> None:
    import pathlib

    path = pathlib.Path(str(tmp_path)) / "p.afsm"
    text = (EXAMPLES / "patrol.afsm").read_text(encoding="utf-8")
    path.write_text(text.replace("const prob P_SLIP   = 0.1;", "const prob P_SLIP   = [0, 0.1];"),
                    encoding="utf-8")
    model = load(str(path)).model
    with pytest.raises(CompileError) as info:
        extremes(lowered(model, "nondet"), list(model.properties))
    (d,) = info.value.diagnostics
    assert d.code == "E440" and "P_SLIP=0" in d.message
    # the hint rewrites the file's declaration, not a --param flag of another command
    assert d.hint is not None and "const prob P_SLIP = [1e-6, 0.1];" in d.hint
    assert d.span is not None


def test_a_property_the_parametric_engine_lacks_is_e443(tmp_path: object) -> None:
    import pathlib

    path = pathlib.Path(str(tmp_path)) / "p.afsm"
    text = (EXAMPLES / "patrol.afsm").read_text(encoding="utf-8")
    path.write_text(text.replace("const prob P_SLIP   = 0.1;", f"const prob P_SLIP   = [{LO}, {HI}];")
                    + 'property now = R{"steps"}=? [ I=2 ];\n', encoding="utf-8")
    model = load(str(path)).model
    with pytest.raises(CompileError) as info:
        extremes(lowered(model, "nondet"), [p for p in model.properties if p.name == "now"])
    (d,) = info.value.diagnostics
    assert d.code == "E443" and "now" in d.message and "not supported" in d.message
