"""The Python API's `answer()`: the one answer of a verification, a sweep or a simulation
as the frozen pydantic model of its published schema, the same object `--json` prints."""

from __future__ import annotations

import json

import pytest
from pydantic import ValidationError

import afsmc
from afsmc.answer.simulate import Simulation
from afsmc.answer.sweep import Sweep
from afsmc.answer.verify import Verification
from tests.conftest import ROOT, run_cli

PATROL = str(ROOT / "examples" / "patrol.afsm")


@pytest.mark.storm
def test_verify_answer_is_the_typed_json_of_the_command() -> None:
    res = afsmc.load(PATROL).verify(formulas=['P>=0.8 [ F "done" ]'])
    answer = res.answer()
    assert isinstance(answer, Verification)
    (p,) = answer.properties
    assert p.verdict == "holds" and p.decided_by == "min"
    assert (p.min, p.max) == (res["adhoc"].min, res["adhoc"].max)
    with pytest.raises(ValidationError):
        p.min = 0.0  # frozen: the answer is computed once
    cli = run_cli("verify", PATROL, "-f", 'P>=0.8 [ F "done" ]', "--json")
    printed = json.loads(cli.out)
    assert cli.code == 0
    mine = answer.model_dump(mode="json", by_alias=True)
    # the same answer but for the times of the two runs
    for d in (printed, mine):
        _drop_times(d)
    assert mine == printed


def _drop_times(node: object) -> None:
    if isinstance(node, dict):
        for k in [k for k in node if "seconds" in k or k == "timings"]:
            del node[k]
        for v in node.values():
            _drop_times(v)
    elif isinstance(node, list):
        for v in node:
            _drop_times(v)


@pytest.mark.storm
def test_sweep_and_simulate_answers_are_typed() -> None:
    m = afsmc.load(PATROL)
    sw = m.sweep("CELLS", [2, 3], properties="finish").answer()
    assert isinstance(sw, Sweep) and [pt.x for pt in sw.points] == [2, 3]
    sim = m.simulate(runs=2000, seed=1).answer()
    assert isinstance(sim, Simulation)
    assert {e.name for e in sim.properties} == set(m.properties)
