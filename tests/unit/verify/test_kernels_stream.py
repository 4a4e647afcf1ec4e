"""The streamed route's compiled kernels (afsmc.verify.kernels.streamed): resolving a
bucket's successors by hash lookups, its dies by marks, and the backward pass over the
files without a sparse matrix. Oracle: the numpy reference path of afsmc.verify.stream
(AFSMC_KERNELS=numpy): every array written to the scratch the same, and every value and
the uniform DTMC's transition count the same to the bit, on models with many buckets and
sinks (the UAV), late states (rover) and self-loops, the successors' keys waiting in
memory or in files, the layers solved in one thread or cut between several; and with the kernels taken part way through an exploration (its
window and sinks moved to hash sets)."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
import pytest

from afsmc.verify import kernels
from afsmc.verify.stream import layers, scratch, sweep
from tests.unit.verify.test_streaming import CASES, _loops, _plan

pytestmark = pytest.mark.storm


def _streamed(path: str, consts: dict[str, str], where: Path
              ) -> tuple[dict[str, float], int, dict[str, dict[str, Any]], layers.Streamed]:
    """The run's values, transition count and every file's arrays, and what the
    exploration recorded."""
    p, c = _plan(path, consts)
    with scratch.made(str(where)) as d:
        st = layers.explore(c, scratch.Scratch(d))
        files = {f.name: st.scratch.load(f.name) for f in sorted(d.iterdir())}
        got, pairs = sweep.run(st, p.queries, c.reward_names, len(p.targets))
    return got, pairs, files, st


def _same(a: tuple[dict[str, float], int, dict[str, dict[str, Any]], layers.Streamed],
          b: tuple[dict[str, float], int, dict[str, dict[str, Any]], layers.Streamed]) -> None:
    assert a[0] == b[0]  # to the bit
    assert a[1] == b[1]
    assert a[2].keys() == b[2].keys()
    for name, arrays in a[2].items():
        assert arrays.keys() == b[2][name].keys(), name
        for k, v in arrays.items():
            w = b[2][name][k]
            if name.startswith("keys"):  # a bucket's keys, in any order
                v, w = np.sort(v), np.sort(w)
            assert np.array_equal(v, w), (name, k)
    for field in ("start", "size", "reach", "dies", "sink_start", "sinks", "late",
                  "initial", "choices", "transitions"):
        assert getattr(a[3], field) == getattr(b[3], field), field


@pytest.mark.parametrize("case", [*CASES, "loops"])
def test_the_compiled_streamed_route_writes_and_solves_what_numpy_does(
        case: str, tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    path, consts = CASES[case] if case != "loops" else (_loops(tmp_path), {})
    monkeypatch.setenv("AFSMC_KERNELS", "numpy")
    # the numpy run's successors' keys wait in files, the compiled run's in memory
    monkeypatch.setattr(layers, "HOLD_BYTES", 0)
    want = _streamed(path, consts, tmp_path)
    monkeypatch.undo()
    monkeypatch.setenv("AFSMC_KERNELS", "numba")
    monkeypatch.setattr(sweep, "SPLIT", 1)  # every layer cut between the threads
    got = _streamed(path, consts, tmp_path)
    _same(got, want)
    assert case != "uav" or (len(want[3].start) > 10 and want[3].sinks > 0)
    assert case != "rover" or want[3].late > 0


def test_kernels_taken_part_way_through_an_exploration_change_nothing(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    path, consts = CASES["uav"]
    monkeypatch.setenv("AFSMC_KERNELS", "numpy")
    want = _streamed(path, consts, tmp_path)
    monkeypatch.delenv("AFSMC_KERNELS")
    # past a third of the states: buckets and sinks numbered already move to hash sets
    monkeypatch.setattr(kernels, "THRESHOLD", want[3].states // 3)
    got = _streamed(path, consts, tmp_path)
    _same(got, want)
