"""Every numeric option has a stated upper bound: past it, a usage error (exit 2) within
seconds that says the bound, before any model is built or any run made."""

from __future__ import annotations

import argparse
import time

import pytest

from afsmc.commands.common import MIN_JOBS_CAP, max_jobs
from afsmc.simlib import sandbox
from tests.conftest import EXAMPLES, run_cli

PATROL = str(EXAMPLES / "patrol.afsm")
REQUIRE = 'P>=0.5 [ F "done" ]'
REGIONS = ["regions", PATROL, "--require", REQUIRE, "--param", "P_SLIP=0:0.2"]


def _usage_error(argv: list[str], said: str) -> None:
    t0 = time.monotonic()
    r = run_cli(*argv)
    assert r.code == 2, (r.code, r.err)
    assert said in r.err, r.err
    assert time.monotonic() - t0 < 30


@pytest.mark.parametrize(("argv", "said"), [
    (["verify", PATROL, "-p", "done", "--witness", "1000000000"],
     "--witness: expected an integer from 1 to 1,000"),
    (["verify", PATROL, "--max-states", "100000000000"],
     "--max-states: expected an integer from 1 to 10,000,000,000"),
    (["diagram", PATROL, "--reach", "--max-states", "0"], "--max-states: expected an integer"),
    (["simulate", PATROL, "--jobs", "100000"], "--jobs/-j: expected an integer from 1 to 4,096"),
    (["simulate", PATROL, "--runs", "1000000000000"], "--runs: expected an integer from 1 to"),
    (["simulate", PATROL, "--max-steps", "10000000000"], "--max-steps: expected an integer"),
    (["simulate", PATROL, "--traces", "200000"], "--traces: expected an integer from 0 to 100,000"),
    (["simulate", PATROL, "--batch-size", "2000000"], "--batch-size: expected an integer"),
    (["simulate", PATROL, "--confidence", "1"], "expected a confidence in (0, 1)"),
    (["simulate", PATROL, "--seed", str(2**64)], "--seed: expected an integer from 0 to"),
    (["sweep", PATROL, "--const", "CELLS=1:3", "--jobs", "100000"], "--jobs/-j: expected"),
    ([*REGIONS, "--max-rounds", "1000"], "--max-rounds: expected an integer from 1 to 24"),
    ([*REGIONS, "--coverage", "2"], "--coverage: expected a number in (0, 1]"),
    ([*REGIONS, "--jobs", "100000"], "--jobs/-j: expected an integer"),
    (["sim-check", PATROL, "--runs", "10000000000"], "--runs: expected an integer from 2 to"),
    (["sim-check", PATROL, "--timeout", "1e9"], "--timeout: expected a number of seconds"),
    (["verify", PATROL, "--precision", "5"], "--precision: expected a number strictly between"),
], ids=lambda v: "-".join(v[:1] + v[-2:-1]) if isinstance(v, list) else "")
def test_a_number_past_its_bound_is_a_usage_error(argv: list[str], said: str) -> None:
    _usage_error(argv, said)


@pytest.mark.parametrize("argv", [
    ["simulate", PATROL, "--runs", "10"],
    ["sweep", PATROL, "--const", "CELLS=1:3"],
    REGIONS,
], ids=["simulate", "sweep", "regions"])
def test_local_jobs_are_at_most_the_cores(argv: list[str]) -> None:
    """--jobs 100000 starts no processes: at most the cores (or MIN_JOBS_CAP)."""
    assert max_jobs() >= MIN_JOBS_CAP
    _usage_error([*argv, "--jobs", str(max_jobs() + 1)],
                 f"--jobs {max_jobs() + 1:,}: at most {max_jobs()} local processes")


def test_sim_check_refuses_runs_whose_samples_do_not_fit(tmp_path: object) -> None:
    budget = sandbox.memory_budget()
    if budget is None:
        pytest.skip("no /proc/meminfo: the memory check is off")
    fit = sandbox.runs_that_fit(budget)
    assert fit is not None and fit * sandbox.BYTES_PER_RUN <= budget
    r = run_cli("sim-check", str(EXAMPLES / "uav.afsm"), "--runs", str(min(10**9, fit * 2)))
    if fit * 2 > 10**9:
        pytest.skip("this machine's memory holds the largest --runs")
    assert r.code == 2 and f"at {sandbox.BYTES_PER_RUN} bytes per run" in r.err, r.err


def test_every_numeric_option_has_a_bound() -> None:
    """No option of any command parses a bare int or float: each goes through a type that
    states its range (afsmc.commands.common.integer / number, or a checked parser)."""
    from afsmc.cli import build_parser, commands

    build_parser()
    unbounded = [f"{name} {'/'.join(a.option_strings)}" for name, p in commands.items()
                 for a in p._actions
                 if isinstance(a, argparse.Action) and a.type in (int, float)]
    assert unbounded == []
