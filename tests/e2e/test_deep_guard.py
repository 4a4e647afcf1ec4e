"""Without --max-states, a symbolic build of a variable with more values than the default
state limit is refused before Storm runs (E420, issue 36): `verify patrol --const
CELLS=1000000000` was still building, unwatched, after minutes."""

from __future__ import annotations

import re
import subprocess
import sys
import time

import pytest

from afsmc.compiler import load, lowered
from afsmc.diagnostics import CompileError
from afsmc.verify.engines.guard import default_max_states
from afsmc.verify.plan.deep import refuse_deep
from tests.conftest import EXAMPLES, Result

PATROL = str(EXAMPLES / "patrol.afsm")


@pytest.mark.slow
@pytest.mark.storm
@pytest.mark.parametrize("engine", [None, "hybrid", "dd"])
def test_a_billion_cells_are_refused_before_building(engine: str | None) -> None:
    started = time.monotonic()
    argv = [sys.executable, "-m", "afsmc", "verify", PATROL, "--const", "CELLS=1000000000"]
    p = subprocess.run(argv + ([] if engine is None else ["--engine", engine]),
                       capture_output=True, text=True, timeout=120)
    elapsed = time.monotonic() - started
    r = Result(p.returncode, p.stdout, p.stderr)
    assert r.code == 1, r.out + r.err
    assert "patrol.afsm:14:1: error[E420]: variable 'cell' has 1,000,000,001 values" in r.err
    # the limit printed: what the free memory holds as the child saw it (at most 50 M)
    limit = re.search(r"more than the default --max-states ([\d,]+):", r.err)
    assert limit is not None, r.err
    assert 100_000 <= int(limit[1].replace(",", "")) <= max(default_max_states(), 50_000_000)
    assert f"the {engine or 'auto'} engine's symbolic build" in r.err, r.err
    assert " 14 | var cell    : [0..CELLS] init 0;" in r.err and "^^^^" in r.err, r.err
    assert "hint: --max-states N raises the limit" in r.err, r.err
    assert "building the" not in r.err and "Traceback" not in r.err, r.err
    assert elapsed < 60, elapsed


def test_the_guard_leaves_small_ranges_sparse_and_explicit_limits_alone() -> None:
    low = lowered(load(PATROL, {"CELLS": "1000000"}).model)  # 1,000,001 values
    refuse_deep(low, "hybrid", None, 2_000_000)  # within the limit
    refuse_deep(low, "sparse", None, 1000)  # the sparse engine has its own guard
    refuse_deep(low, "dd", 5000, 1000)  # a --max-states: the build is watched
    with pytest.raises(CompileError) as caught:
        refuse_deep(low, "dd", None, 1000)
    [d] = caught.value.diagnostics
    assert d.code == "E420" and d.span is not None and d.span.line == 14
    assert "variable 'cell' has 1,000,001 values, more than the default --max-states 1,000" \
        in d.message


WIDE = """machine wide;
var x : [0..10] init 0;
var far : [0..1000000000] init 0;
var flag : [0..1000000000] init 0;
mode Run = 0 initial;
mode End = 1 final;
action Go in Run when x < 10 { 0.9: x := x + 1; 0.1: flag := 7; }
action Stop in Run when x >= 10 { goto End; }
property reach = P=? [ F mode == End && far == 0 && flag < 8 ];
"""


def test_a_wide_variable_that_no_update_computes_is_not_deep() -> None:
    # `far` never changes and `flag` is only set to a number: a few values each, a shallow
    # symbolic build, whatever their ranges
    refuse_deep(lowered(load("wide.afsm", {}, text=WIDE).model), "hybrid", None, 1000)
