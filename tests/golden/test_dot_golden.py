"""DOT output pinned by golden files (tests/golden/cases/dot_*/expected.dot), independent of
Python's hash seed."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

from tests.conftest import CASES, EXAMPLES, ROOT, run_cli
from tests.e2e.test_diagram import MISSION


@pytest.mark.parametrize("name,spec", [("dot_patrol", EXAMPLES / "patrol.afsm"),
                                       ("dot_mission17", MISSION)])
def test_dot_output_is_deterministic_and_golden(name: str, spec: Path,
                                                update_golden: bool) -> None:
    first = run_cli("compile", str(spec), "-t", "dot", "-o", "-")
    second = run_cli("compile", str(spec), "-t", "dot", "-o", "-")
    assert first.code == 0, first.err
    assert first.out == second.out
    golden = CASES / name / "expected.dot"
    if update_golden:
        golden.write_text(first.out)
    assert first.out == golden.read_text()


def test_dot_output_does_not_depend_on_the_hash_seed() -> None:
    # The golden file was written by another process, with another string-hash seed.
    env = dict(os.environ, PYTHONHASHSEED="12345")
    p = subprocess.run([sys.executable, "-m", "afsmc.cli", "compile", str(MISSION), "-t", "dot",
                        "-o", "-"], capture_output=True, text=True, env=env, cwd=ROOT, check=True)
    assert p.stdout == (CASES / "dot_mission17" / "expected.dot").read_text()
