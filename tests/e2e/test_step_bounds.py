"""Step bounds of properties must be ints >= 0, in the file, in `--formula`, in `--const`
and in a bound sweep."""

from __future__ import annotations

from pathlib import Path

import pytest

from tests.conftest import run_cli

pytestmark = pytest.mark.storm

NEG = """machine nb;
param int K = 2;
mode S = 0 initial;
mode D = 1 final;
action Go in S { 0.5: goto D; 0.5: skip; }
rewards r { true : 1; }
property ok = P=? [ F<=K mode == D ];
"""


@pytest.mark.parametrize("prop", ["P=? [ F<=(0 - 1) mode == D ]", "R{\"r\"}=? [ I=(K - 3) ]",
                                  "R{\"r\"}=? [ C<=(-1) ]", "P=? [ true U<=(K - 5) mode == D ]",
                                  "P=? [ G<=(0 - 1) mode == S ]"])
def test_a_negative_step_bound_is_an_error(tmp_path: Path, prop: str) -> None:
    path = tmp_path / "nb.afsm"
    path.write_text(NEG + f"property bad = {prop};\n", encoding="utf-8")
    r = run_cli("check", str(path))
    assert r.code == 1 and "error[E241]: a step bound must be an int >= 0" in r.err
    path.write_text(NEG, encoding="utf-8")
    assert run_cli("check", str(path)).code == 0
    r = run_cli("verify", str(path), "--formula", prop)
    assert r.code == 1 and "--formula:1:" in r.out + r.err and "E241" in r.out + r.err
    r = run_cli("simulate", str(path), "--runs", "10", "-c", "K=-1")
    assert r.code == 1 and "E241" in r.out + r.err


def test_sweep_refuses_negative_bounds(tmp_path: Path) -> None:
    path = tmp_path / "nb.afsm"
    path.write_text(NEG, encoding="utf-8")
    r = run_cli("sweep", str(path), "--bound=-1,2")
    assert r.code == 1 and "E410" in r.out + r.err
