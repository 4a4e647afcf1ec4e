"""`simulate` with interval probabilities: each run draws its own p, uniform in the
interval, once when it starts (the default), or every run at the midpoint or an end.

The oracle is the closed form: two independent trials of probability p both succeed with
probability p^2. Drawn once per run from U[a, b], that is E[p^2] = (b^3 - a^3) / (3 (b - a));
drawn afresh at each step it would be E[p]^2, the midpoint's (a + b)^2 / 4."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from afsmc.sim.run import job_for, simulate
from tests.conftest import run_cli

LO, HI = 0.2, 0.8
TWICE = f"""
machine twice;
const prob PS = [{LO}, {HI}];
var ok : [0..2] init 0 clamp;
var tries : [0..2] init 0;
mode Try = 0 initial;
mode Done = 1 final;
action Trial in Try when tries < 2 {{
    PS: ok += 1, tries += 1;
    1 - PS: tries += 1;
}}
action Finish in Try when tries == 2 {{ goto Done; }}
label both = mode == Done && ok == 2;
property both = P=? [ F "both" ];
"""


@pytest.fixture
def twice(tmp_path: Path) -> str:
    p = tmp_path / "twice.afsm"
    p.write_text(TWICE)
    return str(p)


@pytest.mark.parametrize(("at", "exact"), [
    ("draw", (HI**3 - LO**3) / (3 * (HI - LO))),  # 0.28: once per run
    ("mid", ((LO + HI) / 2) ** 2),  # 0.25
    ("min", LO**2),
    ("max", HI**2),
])
def test_each_way_of_setting_p_gives_its_closed_form(twice: str, at: str, exact: float) -> None:
    job = job_for(twice, Path(twice).read_text(), {}, "uniform", 100, at)
    (e,) = simulate(job, 60_000, 1, confidence=0.999).estimates
    assert e.low <= exact <= e.high, (at, e)
    if at == "draw":  # and not the midpoint's value, which p drawn per step would give
        assert not e.low <= ((LO + HI) / 2) ** 2 <= e.high


def test_the_default_draws_and_says_so(twice: str) -> None:
    r = run_cli("simulate", twice, "--runs", "2000", "--json")
    assert r.code == 0, r.err
    assert json.loads(r.out)["at"] == "draw"
    r = run_cli("simulate", twice, "--runs", "2000")
    assert "interval probabilities drawn once per run (uniform)" in r.out
    r = run_cli("simulate", twice, "--runs", "2000", "--at", "mid")
    assert "interval probabilities at their midpoints" in r.out


def test_draws_do_not_depend_on_the_workers(twice: str) -> None:
    job = job_for(twice, Path(twice).read_text(), {}, "uniform", 100, "draw")
    one = simulate(job, 20_000, 7, batch_size=5_000).estimates[0]
    two = simulate(job, 20_000, 7, batch_size=5_000, jobs=2).estimates[0]
    assert one.estimate == two.estimate
