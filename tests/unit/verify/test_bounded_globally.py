"""Step-bounded G, which Storm cannot check: afsmc asks P[F<=k !φ] and reports 1 - it, with
min and max swapped. Oracles: the dual written by hand, and Monte Carlo (whose simulator
decides G<=k on the runs themselves)."""

from __future__ import annotations

from pathlib import Path

import pytest

from afsmc.sim.run import job_for, simulate
from afsmc.verify import run
from tests.conftest import run_cli

TEXT = """machine bounded;
const int STEP = [1, 2];
var x : [0..8] init 0 clamp;
mode Run = 0 initial;
mode End = 1 final;
action Go in Run when x < 8 { 0.8: x += STEP; 0.2: x += 1; }
action Stop in Run when x >= 8 { goto End; }
hazard Trip from {0} with probability 0.05 { goto End; }
label low = x <= 5;
property stay       = P=? [ G<=4 "low" ];
property stay_dual  = P=? [ F<=4 !"low" ];
property short      = Pmin=? [ G<=3 "low" ];
property short_dual = Pmax=? [ F<=3 !"low" ];
"""


@pytest.fixture()
def model(tmp_path: Path) -> Path:
    path = tmp_path / "bounded.afsm"
    path.write_text(TEXT, encoding="utf-8")
    return path


@pytest.mark.storm
@pytest.mark.parametrize(("engine", "via"), [("sparse", "prism"), ("hybrid", "prism"),
                                             ("sparse", "jani")])
def test_bounded_g_is_one_minus_its_dual(model: Path, engine: str, via: str) -> None:
    res = run(str(model), engine=engine, via=via, isolate=False)  # type: ignore[arg-type]
    stay, dual = res.property("stay"), res.property("stay_dual")
    short, short_dual = res.property("short"), res.property("short_dual")
    assert stay.formula == 'P=? [ G<=4 "low" ]'
    for g, f in ((stay.min, dual.max), (stay.max, dual.min), (stay.uniform, dual.uniform),
                 (short.min, short_dual.max), (short.uniform, short_dual.uniform)):
        assert g is not None and f is not None
        assert g == pytest.approx(1.0 - f, abs=1e-12)
    assert stay.min is not None and stay.max is not None and stay.min < stay.max
    assert short.max is None


@pytest.mark.storm
def test_monte_carlo_agrees_with_the_bounded_g_values(model: Path) -> None:
    exact = run(str(model), engine="sparse", isolate=False)
    job = job_for(str(model), TEXT, {}, "uniform", 1000)
    mc = simulate(job, 20_000, 11)
    for name in ("stay", "short"):
        est = next(e for e in mc.estimates if e.name == name)
        value = exact.property(name).uniform
        assert value is not None and est.low <= value <= est.high, (name, est, value)


@pytest.mark.slow
@pytest.mark.storm
def test_progress_names_the_dual_queries(model: Path) -> None:
    said: list[str] = []
    run(str(model), properties=["stay"], engine="sparse", isolate=True, progress=said.append)
    checked = [s for s in said if s.startswith("checked ")]
    assert any(s.startswith("checked stay_max as 1 - Pmin [F<=k !φ] on the MDP")
               for s in checked), said
    assert not any("__afsmc" in s for s in said), said


@pytest.mark.slow
@pytest.mark.storm
def test_progress_words_a_dual_by_its_property_not_its_name(tmp_path: Path) -> None:
    # A DTMC property whose own name ends in _min: its dual is no "max as 1 - Pmin".
    path = tmp_path / "dtmc.afsm"
    path.write_text(TEXT.replace("const int STEP = [1, 2];", "const int STEP = 1;")
                    .replace("property stay ", "property stay_min "), encoding="utf-8")
    said: list[str] = []
    res = run(str(path), properties=["stay_min", "stay_dual"], engine="sparse", isolate=True,
              progress=said.append)
    assert any(s.startswith("checked stay_min as 1 - P [F<=k !φ] on the DTMC")
               for s in said), said
    assert not any("stay_max" in s for s in said), said
    g, f = res.property("stay_min").value, res.property("stay_dual").value
    assert g is not None and f is not None and g == pytest.approx(1.0 - f, abs=1e-12)


def test_bounded_g_in_the_generated_prism(model: Path, tmp_path: Path) -> None:
    # PRISM itself checks G<=k: the .props file keeps the property as written.
    r = run_cli("compile", str(model), "-o", str(tmp_path))
    assert r.code == 0, r.err
    props = (tmp_path / "bounded.props").read_text(encoding="utf-8")
    assert '"stay_min": Pmin=? [ G<=4 "low" ];' in props, props
