"""`afsmc.verify.run` from a plain script, without an `if __name__ == "__main__":` guard
(issue 34): the watched Storm process must not run the script again."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

from afsmc.verify.engines.guard import IN_PROCESS_STATES
from tests.conftest import ROOT

# An upper bound of 600,002 states sends the build to the watched child; 3 are reachable.
SPEC = """machine wide;
var x : [0..300000] init 0;
mode A = 0 initial;
mode B = 1 final;
action Step in A when x < 2 { x := x + 1; }
action Stop in A when x == 2 { goto B; }
label done = mode == B;
property reach = P=? [ F "done" ];
"""


def _script(spec: Path) -> str:
    return ("import afsmc.verify\n"
            f"r = afsmc.verify.run({str(spec)!r})\n"
            "print('states', r.model.states, 'value', r.properties[0].value)\n")


def _env() -> dict[str, str]:
    path = os.environ.get("PYTHONPATH")
    return {**os.environ, "PYTHONPATH": str(ROOT) + (os.pathsep + path if path else "")}


@pytest.mark.slow
@pytest.mark.storm
@pytest.mark.parametrize("how", ["file", "stdin"])
def test_a_script_without_a_main_guard_verifies_in_the_watched_process(
        how: str, tmp_path: Path) -> None:
    from afsmc.compiler import load
    from afsmc.verify import upper_bound

    spec = tmp_path / "wide.afsm"
    spec.write_text(SPEC, encoding="utf-8")
    assert upper_bound(load(str(spec)).model) > IN_PROCESS_STATES
    script = tmp_path / "plain.py"
    script.write_text(_script(spec), encoding="utf-8")
    if how == "file":
        r = subprocess.run([sys.executable, str(script)], capture_output=True, text=True,
                           timeout=300, env=_env(), cwd=tmp_path)
    else:
        r = subprocess.run([sys.executable, "-"], input=script.read_text(), capture_output=True,
                           text=True, timeout=300, env=_env(), cwd=tmp_path)
    assert r.returncode == 0, r.stderr
    assert "bootstrapping" not in r.stderr and "internal error" not in r.stderr, r.stderr
    assert r.stdout.count("states") == 1  # the script ran once, not again in the child
    assert r.stdout.split() == ["states", "4", "value", "1.0"], r.stdout


@pytest.mark.slow
@pytest.mark.storm
def test_a_script_without_a_main_guard_sweeps_on_worker_processes(tmp_path: Path) -> None:
    script = tmp_path / "plain_sweep.py"
    script.write_text("from afsmc.verify import sweep\n"
                      f"fig = sweep({str(ROOT / 'examples' / 'patrol.afsm')!r}, 'CELLS', [3, 4],"
                      " properties=['finish'], jobs=2)\n"
                      "print('points', len(fig.points))\n", encoding="utf-8")
    r = subprocess.run([sys.executable, str(script)], capture_output=True, text=True,
                       timeout=300, env=_env(), cwd=tmp_path)
    assert r.returncode == 0, r.stderr
    assert r.stdout.split() == ["points", "2"], r.stdout
