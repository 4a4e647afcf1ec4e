"""What matters most (afsmc.report.sensitivity): each derivative agrees in sign and to
1e-3 relative with a finite difference of two `verify` runs at another step, and at each
flip value the requirement's verdict flips between two `verify` runs either side."""

from __future__ import annotations

from pathlib import Path

import pytest

from afsmc import verify
from afsmc.compiler import load
from afsmc.report.sensitivity import Sensitivity, figures, sensitivities
from afsmc.sim.evidence import value_spans
from afsmc.verify.core.options import VerifyOptions
from afsmc.verify.outcome.results import PropertyResult
from tests.conftest import EXAMPLES
from tests.specs import patrol_with_requirements

pytestmark = [pytest.mark.storm, pytest.mark.slow]  # ~20 verifications: 6 s



@pytest.fixture(scope="module")
def spec(tmp_path_factory: pytest.TempPathFactory) -> Path:
    return patrol_with_requirements(tmp_path_factory.mktemp("sens"))


def _with(text: str, path: str, name: str, value: float) -> str:
    start, end = value_spans(text, path)[name]
    return text[:start] + repr(value) + text[end:]


def _run(path: Path, text: str, names: list[str], **kw: object) -> dict[str, PropertyResult]:
    res = verify.run(str(path), text=text, properties=names, uniform=False, **kw)  # type: ignore[arg-type]
    return {p.name: p for p in res.properties}


@pytest.fixture(scope="module")
def computed(spec: Path) -> list[Sensitivity]:
    text = spec.read_text(encoding="utf-8")
    model = load(str(spec)).model
    res = verify.run(str(spec), properties=["fault_low", "finish_ok"], uniform=False)
    return list(sensitivities(str(spec), text, model, {}, res.properties,
                              VerifyOptions(engine="auto")))


def test_the_figures_are_the_probabilities_and_double_params() -> None:
    model = load(str(EXAMPLES / "patrol.afsm")).model
    assert [(f.name, f.kind, f.range) for f in figures(model)] == [
        ("P_SLIP", "probability", (0.0, 1.0)), ("P_FAULT", "probability", (0.0, 1.0))]
    uav = load(str(EXAMPLES / "uav.afsm")).model
    kinds = {f.name: f.kind for f in figures(uav)}
    assert kinds["ALPHA"] == "param" and kinds["P_EMERGENCY"] == "probability"
    assert "OBJECTS" not in kinds  # an integer has no derivative


def test_each_derivative_agrees_with_two_verify_runs(spec: Path, computed: list[Sensitivity]) -> None:
    text = spec.read_text(encoding="utf-8")
    assert len(computed) == 4
    for s in computed:
        f, which = s.figure, s.bound
        h = 1e-3 * f.value  # another step than the report's
        up = _run(spec, _with(text, str(spec), f.name, f.value + h), [s.requirement],
                  precision=1e-12)[s.requirement]
        down = _run(spec, _with(text, str(spec), f.name, f.value - h), [s.requirement],
                    precision=1e-12)[s.requirement]
        fd = (float(getattr(up, which)) - float(getattr(down, which))) / (2 * h)
        assert s.derivative is not None
        assert (s.derivative > 0) == (fd > 0), s
        assert s.derivative == pytest.approx(fd, rel=1e-3), s


def test_ranked_most_influential_first(computed: list[Sensitivity]) -> None:
    for name in ("fault_low", "finish_ok"):
        mine = [abs(s.derivative or 0.0) for s in computed if s.requirement == name]
        assert mine == sorted(mine, reverse=True)
        assert next(s.figure.name for s in computed if s.requirement == name) == "P_FAULT"


def test_the_verdict_flips_at_the_flip_value(spec: Path, computed: list[Sensitivity]) -> None:
    text = spec.read_text(encoding="utf-8")
    flips = [s for s in computed if s.flip is not None]
    assert {s.figure.name for s in flips} == {"P_FAULT", "P_SLIP"}
    for s in flips:
        assert s.flip is not None
        lo, hi = s.flip * (1 - 1e-4), s.flip * (1 + 1e-4)
        below, above = (_run(spec, _with(text, str(spec), s.figure.name, x),
                             [s.requirement])[s.requirement] for x in (lo, hi))
        # more faults or slips: the deciding bound crosses the threshold, away from holds
        assert below.verdict is not None and above.verdict is not None
        assert below.verdict.kind == "holds" and above.verdict.kind != "holds", s
        assert (above.verdict.decided_by or "") in ("min", "max")
        threshold = {"fault_low": 0.2, "finish_ok": 0.8}[s.requirement]
        assert s.flip_bound == pytest.approx(threshold, abs=1e-7)
