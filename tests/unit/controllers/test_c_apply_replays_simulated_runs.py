"""The C controller's `apply` (and `probability`, which it checks) follows the simulator:
each step of runs that `afsmc simulate --traces-out x.jsonl` wrote (the lowered model's
Monte Carlo, no code shared with the generator) is applied in C to the state before it,
with the logged action, outcome and durations, and must return OK and the state the run
reached. The missions: patrol (an interval constant, a hazard), uav (tuples, clamps,
many intervals), warehouse (an outcome reading two interval constants), drone (a hazard
whose probability depends on the state), auv, rover and overtake (preemptive hazards)."""

from __future__ import annotations

import json
import shutil
import subprocess
from pathlib import Path
from typing import Any

import pytest

from afsmc.api.mission import Mission
from afsmc.model import ir
from tests.conftest import EXAMPLES, run_cli

GCC = shutil.which("gcc")
pytestmark = pytest.mark.skipif(GCC is None, reason="needs gcc")

HARNESS = r"""#include <math.h>
#include <stdio.h>
#include "{p}.h"
int main(void)
{{
    {p}_state s, next;
    double d[{n_iv}];
    long long v;
    int action, hazard, outcome, rc, i;
    for (;;) {{
        if (scanf("%lld", &v) != 1) return 0;
        s.mode = v;
{reads}
        if (scanf("%d %d %d", &action, &hazard, &outcome) != 3) return 1;
        for (i = 0; i < {n_iv}; i++) if (scanf("%lf", &d[i]) != 1) return 1;
        rc = {p}_apply(&s, action, hazard, outcome, d, &next);
        printf("%d %lld", rc, (long long)next.mode);
{writes}
        printf("\n");
    }}
}}
"""


def _build(mission: Mission, tmp: Path) -> Path:
    model = mission.model
    p = model.name.lower()
    files = mission.files("c")
    (tmp / f"{p}.h").write_text(files[".h"], encoding="utf-8")
    (tmp / f"{p}.c").write_text(files[".c"], encoding="utf-8")
    reads = "\n".join(f'        if (scanf("%lld", &v) != 1) return 1;\n        s.{v.name} = '
                      + ("v != 0;" if v.type.value == "bool" else "v;") for v in model.variables)
    writes = "\n".join(f'        printf(" %lld", (long long)next.{v.name});'
                       for v in model.variables)
    n_iv = max(1, len(model.interval_constants))
    (tmp / "main.c").write_text(HARNESS.format(p=p, reads=reads, writes=writes, n_iv=n_iv),
                                encoding="utf-8")
    assert GCC is not None
    built = subprocess.run([GCC, "-std=c99", "-Wall", "-Wextra", "-Werror", "-pedantic", "-o",
                            str(tmp / "apply"), str(tmp / "main.c"), str(tmp / f"{p}.c"), "-lm"],
                           capture_output=True, text=True)
    assert built.returncode == 0, built.stderr
    return tmp / "apply"


def _row(model: ir.Model, state: dict[str, Any]) -> list[int]:
    return [model.mode(state["mode"]).number, *(int(state[v.name]) for v in model.variables)]


@pytest.mark.parametrize("name", ["patrol", "uav", "warehouse", "drone", "auv", "rover", "overtake"])
def test_c_apply_reaches_the_state_each_simulated_step_reached(name: str, tmp_path: Path) -> None:
    mission = Mission.open(str(EXAMPLES / f"{name}.afsm"))
    model = mission.model
    log = tmp_path / "runs.jsonl"
    r = run_cli("simulate", str(EXAMPLES / f"{name}.afsm"), "--runs", "100", "--traces", "100",
                "--traces-out", str(log))
    assert r.code == 0, r.err
    flat = {v.display: v.name for v in model.variables}
    actions = [a.name for a in model.actions]
    hazards = [h.name for h in model.hazards]
    intervals = [c.name for c in model.interval_constants]
    lines, want = [], []
    state: dict[str, Any] = {}
    run = None
    for text in log.read_text(encoding="utf-8").splitlines():
        step = json.loads(text)
        if step["run"] != run:
            run = step["run"]
            state = {"mode": model.initial_mode.name} | {v.name: v.init for v in model.variables}
        key = step["outcome"]
        hazard, outcome = -1, key
        if isinstance(key, str):
            h, _, j = key.partition("/")
            hazard, outcome = hazards.index(h), int(j or 0)
        d = step.get("duration")
        durations = [float(d.get(c, 0) if isinstance(d, dict) else (d if d is not None else 0))
                     for c in intervals] or [0.0]
        lines.append(" ".join(map(str, [*_row(model, state), actions.index(step["action"]),
                                        hazard, outcome, *durations])))
        for k, v in step["changes"].items():
            state["mode" if k == "mode" else flat[k]] = v
        want.append(" ".join(map(str, [0, *_row(model, state)])))
    assert len(lines) > 500
    ran = subprocess.run([str(_build(mission, tmp_path))], input="\n".join(lines) + "\n",
                         capture_output=True, text=True, check=True)
    got = ran.stdout.splitlines()
    wrong = [(i, lines[i], want[i], g) for i, g in enumerate(got) if g != want[i]]
    assert len(got) == len(want) and not wrong, wrong[:3]
