"""docs/robot.md's worked example runs as the page shows it: patrol's controller generated,
the page's robot loop (`robot.py`) driving it and logging its runs, `afsmc conform` on the
log (no violation, no drift: exit 0) and on the worn wheel's (P_SLIP drifted, the mean the
page shows); the page's C loop compiled against `compile -t c` and printing what the page
prints."""

from __future__ import annotations

import json
import re
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

from tests.conftest import EXAMPLES, ROOT, run_cli

PAGE = ROOT / "docs" / "robot.md"
GCC = shutil.which("gcc")


def block(lang: str, heading: str) -> str:
    section = PAGE.read_text(encoding="utf-8").split(heading, 1)[1]
    match = re.search(rf"```{lang}\n(.*?)```", section, re.S)
    assert match, f"no {lang} block under {heading!r}"
    return match.group(1)


def test_the_page_s_robot_loop_logs_runs_that_conform(tmp_path: Path) -> None:
    spec = tmp_path / "patrol.afsm"
    shutil.copy(EXAMPLES / "patrol.afsm", spec)
    r = run_cli("compile", str(spec), "-t", "python", "-o", str(tmp_path / "controller.py"))
    assert r.code == 0, r.err
    (tmp_path / "robot.py").write_text(block("python", "## A robot loop"), encoding="utf-8")
    for argv in (["runs.jsonl"], ["worn.jsonl", "--worn"]):
        subprocess.run([sys.executable, "robot.py", *argv], cwd=tmp_path, check=True,
                       timeout=120)
    first = (tmp_path / "runs.jsonl").read_text(encoding="utf-8").splitlines()[0]
    assert first in PAGE.read_text(encoding="utf-8")  # the page's `head -3 runs.jsonl`
    r = run_cli("conform", str(spec), str(tmp_path / "runs.jsonl"), "--json")
    out = json.loads(r.out)
    assert r.code == 0 and out["violations"] == [] and out["steps"] == 3721
    assert all(c["verdict"] == "consistent" for c in out["constants"])
    r = run_cli("conform", str(spec), str(tmp_path / "worn.jsonl"), "--json")
    out = json.loads(r.out)
    assert r.code == 1 and out["violations"] == []
    assert [(c["name"], round(c["mean"], 3)) for c in out["constants"]
            if c["verdict"] == "drifted"] == [("P_SLIP", 0.292)]


@pytest.mark.skipif(GCC is None, reason="needs gcc")
def test_the_page_s_c_loop_prints_what_the_page_shows(tmp_path: Path) -> None:
    assert GCC is not None
    r = run_cli("compile", str(EXAMPLES / "patrol.afsm"), "-t", "c", "-o",
                str(tmp_path / "patrol_ctl.c"))
    assert r.code == 0, r.err
    (tmp_path / "main.c").write_text(block("c", "## The C controller"), encoding="utf-8")
    subprocess.run([GCC, "-std=c99", "-Wall", "-Wextra", "-Werror", "-pedantic", "-o",
                    "patrol_robot", "main.c", "patrol_ctl.c", "-lm"], cwd=tmp_path, check=True)
    ran = subprocess.run([str(tmp_path / "patrol_robot")], capture_output=True, text=True,
                         check=True)
    shown = re.search(r"\$ \./patrol_robot\n(.*?)```", PAGE.read_text(encoding="utf-8"), re.S)
    assert shown and ran.stdout == shown.group(1)
