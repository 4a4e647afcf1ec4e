"""The generated controllers (`compile -t python`, `compile -t c`) choose, in every reachable
state of every single-agent example, the action the model fires there: the states and the
model's choices are enumerated from the lowering by afsmc's evaluator (reachable.py), an
oracle that shares nothing with the generators but the IR. The C compiles with
`gcc -std=c99 -Wall -Wextra -Werror -pedantic`.

uav.afsm runs at T_LIMIT=100 (about 19,000 reachable states, in place of 90,000 at the
default) to keep the test fast; every other example at its defaults."""

from __future__ import annotations

import importlib.util
import shutil
import subprocess
import sys
from pathlib import Path
from types import ModuleType
from typing import Any

import pytest

from afsmc.api.mission import Mission
from afsmc.lower.lowering import lower
from afsmc.model import ir
from tests.conftest import EXAMPLES, run_cli
from tests.unit.controllers.reachable import State, reachable

CONSTS: dict[str, dict[str, Any]] = {"uav": {"T_LIMIT": 100}}
# the examples, and a spec of the kernel's delicate operators (Storm's mod, pow with a
# negative exponent, floor/ceil, == of doubles within 1e-12) in guards and weights
SINGLE = [p for p in sorted(EXAMPLES.glob("*.afsm"))
          if Mission.open(str(p), CONSTS.get(p.stem)).model.composition is None] + [
    Path(__file__).parent / "specs" / "kernel_ops.afsm"]
GCC = shutil.which("gcc")


def _mission(path: Path) -> Mission:
    return Mission.open(str(path), CONSTS.get(path.stem))


def import_module(path: Path, text: str) -> ModuleType:
    path.write_text(text, encoding="utf-8")
    spec = importlib.util.spec_from_file_location(path.stem, path)
    assert spec is not None and spec.loader is not None
    mod = importlib.util.module_from_spec(spec)
    sys.modules[path.stem] = mod
    spec.loader.exec_module(mod)
    return mod


def as_dict(model: ir.Model, s: State) -> dict[str, Any]:
    out: dict[str, Any] = {"mode": model.mode_by_number(s[0]).name}
    for v, x in zip(model.variables, s[1:], strict=True):
        out[v.name] = bool(x) if v.type.value == "bool" else x
    return out


def test_there_are_single_agent_examples() -> None:
    assert {p.stem for p in SINGLE} >= {"patrol", "uav", "auv", "drone", "rover", "warehouse"}


def test_the_kernel_spec_takes_every_action() -> None:
    """Each delicate operator decides the choice in some state (else the spec tests
    nothing of it)."""
    spec = SINGLE[-1]
    states = reachable(lower(_mission(spec).model, "nondet"))
    assert len(states) == 33  # 32 states of A, and Done
    assert set(states.values()) == {"Base", "Mod", "Pow", "Round", "Mixed", "Tol", "Tick",
                                    "Stop", None}


@pytest.mark.parametrize("path", SINGLE, ids=[p.stem for p in SINGLE])
def test_python_choose_is_the_model_s_choice_in_every_reachable_state(
        path: Path, tmp_path: Path) -> None:
    mission = _mission(path)
    model = mission.model
    states = reachable(lower(model, "nondet"))
    mod = import_module(tmp_path / f"ctl_{path.stem}.py", mission.files("python")[".py"])
    wrong = [(s, want, got) for s, want in states.items()
             if (got := mod.choose(as_dict(model, s))) != want]
    assert not wrong, f"{len(wrong)} of {len(states)} states differ, e.g. {wrong[:3]}"


HARNESS = r"""#include <stdio.h>
#include "{p}.h"
int main(void)
{{
    {p}_state s;
    long long v;
    int i;
    for (;;) {{
        if (scanf("%lld", &v) != 1) return 0;
        s.mode = v;
{reads}
        i = {p}_choose(&s);
        printf("%s\n", i < 0 ? "-" : {p}_action_name(i));
    }}
}}
"""


@pytest.mark.skipif(GCC is None, reason="needs gcc")
@pytest.mark.parametrize("path", SINGLE, ids=[p.stem for p in SINGLE])
def test_c_choose_is_the_model_s_choice_in_every_reachable_state(
        path: Path, tmp_path: Path) -> None:
    assert GCC is not None
    mission = _mission(path)
    model = mission.model
    p = model.name.lower()
    files = mission.files("c")
    (tmp_path / f"{p}.h").write_text(files[".h"], encoding="utf-8")
    (tmp_path / f"{p}.c").write_text(files[".c"], encoding="utf-8")
    reads = "\n".join(
        f"        if (scanf(\"%lld\", &v) != 1) return 1;\n        s.{v.name} = "
        + ("v != 0;" if v.type.value == "bool" else "v;") for v in model.variables)
    (tmp_path / "main.c").write_text(HARNESS.format(p=p, reads=reads), encoding="utf-8")
    flags = ["-std=c99", "-Wall", "-Wextra", "-Werror", "-pedantic"]
    built = subprocess.run([GCC, *flags, "-o", str(tmp_path / "ctl"), str(tmp_path / "main.c"),
                            str(tmp_path / f"{p}.c"), "-lm"], capture_output=True, text=True)
    assert built.returncode == 0, built.stderr
    states = reachable(lower(model, "nondet"))
    order = list(states)
    feed = "".join(" ".join(map(str, s)) + "\n" for s in order)
    ran = subprocess.run([str(tmp_path / "ctl")], input=feed, capture_output=True, text=True,
                         check=True)
    got = ran.stdout.split("\n")[:-1]
    assert len(got) == len(order)
    wrong = [(s, states[s], g) for s, g in zip(order, got, strict=True)
             if (states[s] or "-") != g]
    assert not wrong, f"{len(wrong)} of {len(states)} states differ, e.g. {wrong[:3]}"


def test_a_composed_mission_has_no_controller(tmp_path: Path) -> None:
    for target in ("python", "c"):
        r = run_cli("compile", str(EXAMPLES / "two_uav.afsm"), "-t", target, "-o",
                    str(tmp_path / "out"))
        assert r.code == 1 and "Traceback" not in r.err
        assert f"error[E701]: 'compile -t {target}' writes the controller of one machine; " \
               "two_uav is a mission of 2 agents" in r.err
    assert not list(tmp_path.iterdir())


def test_the_c_source_includes_the_header_by_the_name_it_is_written_as(tmp_path: Path) -> None:
    r = run_cli("compile", str(EXAMPLES / "patrol.afsm"), "-t", "c", "-o",
                str(tmp_path / "ctl.c"))
    assert r.code == 0, r.err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["ctl.c", "ctl.h"]
    assert '#include "ctl.h"' in (tmp_path / "ctl.c").read_text(encoding="utf-8")
    # byte-deterministic: the same files again
    again = tmp_path / "again"
    again.mkdir()
    assert run_cli("compile", str(EXAMPLES / "patrol.afsm"), "-t", "c", "-o",
                   str(again / "ctl.c")).code == 0
    for name in ("ctl.c", "ctl.h"):
        assert (again / name).read_bytes() == (tmp_path / name).read_bytes()
