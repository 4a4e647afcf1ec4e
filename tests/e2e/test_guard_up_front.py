"""Every command that builds a model has verify's guard: patrol's corridor of 10^9 cells
with --max-states 1000 stops with E405 as soon as the explorer passes the limit (checked
inside a round, not only between buckets); without a limit, `diagram --reach` and
`regions` refuse the counter up front (E420), as verify does. The timeouts are generous:
these would otherwise run for hours."""

from __future__ import annotations

import pytest

from tests.conftest import EXAMPLES, run_cli

pytestmark = pytest.mark.storm

PATROL = str(EXAMPLES / "patrol.afsm")
HUGE = ["--const", "CELLS=1000000000"]


def _codes(err: str) -> set[str]:
    return {c for c in ("E405", "E420") if f"error[{c}]" in err}


@pytest.mark.timeout(120)
def test_verify_stops_a_deep_chain_at_max_states() -> None:
    r = run_cli("verify", PATROL, *HUGE, "--max-states", "1000")
    assert r.code == 1, r.err
    assert _codes(r.err) == {"E405"} and "more than --max-states 1,000" in r.err, r.err


@pytest.mark.timeout(120)
def test_diagram_reach_refuses_the_deep_counter_up_front(tmp_path: object) -> None:
    r = run_cli("diagram", PATROL, *HUGE, "--reach", "-o", f"{tmp_path}/d.svg")
    assert r.code == 1, r.err
    assert _codes(r.err) == {"E420"} and "variable 'cell' has 1,000,000,001 values" in r.err
    assert "Storm's build for --reach" in r.err


@pytest.mark.timeout(120)
def test_diagram_reach_with_max_states_stops_at_it(tmp_path: object) -> None:
    r = run_cli("diagram", PATROL, *HUGE, "--reach", "--max-states", "1000",
                "-o", f"{tmp_path}/d.svg")
    assert r.code == 1, r.err
    assert _codes(r.err) == {"E405"}, r.err


@pytest.mark.timeout(120)
def test_regions_refuses_the_deep_counter_up_front() -> None:
    r = run_cli("regions", PATROL, *HUGE, "--require", 'P>=0.5 [ F "done" ]',
                "--param", "P_SLIP=0:0.2")
    assert r.code == 1, r.err
    assert _codes(r.err) == {"E420"} and "Storm's parametric build" in r.err, r.err


def test_the_guard_leaves_a_small_instance_alone(tmp_path: object) -> None:
    r = run_cli("diagram", PATROL, "--reach", "-o", f"{tmp_path}/d.svg")
    assert r.code == 0, r.err
