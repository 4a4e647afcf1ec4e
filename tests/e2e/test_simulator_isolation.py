"""Third-party simulators run in a child process (issue 36): a plugin that exits, hangs,
dies or returns absurd samples gives a failed verdict (exit 1) at the constant, and
`--update` never writes a value that would not check. The plugin is a real installed
package: a module and its .dist-info (entry point group `afsmc.simulators`) in a temporary
directory on PYTHONPATH, found by afsmc as any installed plugin is."""

from __future__ import annotations

import os
import subprocess
import sys
import time
from pathlib import Path

import pytest

from tests.conftest import CASES, ROOT, run_cli

PLUGIN = '''
import os
import time
import numpy as np
from afsmc.simlib.registry import Simulator

def _exit(runs, rng):
    raise SystemExit(0)

def _underscore_exit(runs, rng):
    os._exit(0)

def _hang(runs, rng):
    time.sleep(3600)

def _huge(runs, rng):
    return {"duration": np.full(runs, -1e308)}

def _nan(runs, rng):
    return {"duration": np.full(runs, np.nan)}

def _complex(runs, rng):
    return {"duration": np.full(runs, 1.0 + 2.0j)}

def _objects(runs, rng):
    return {"duration": np.full(runs, 10, dtype=object)}

def _complex_both(runs, rng):
    return {"go": np.full(runs, 1.0 + 1.0j), "fail": np.full(runs, 1.0 + 0.5j)}

def _fractions(runs, rng):
    return {"go": np.full(runs, 10.0), "fail": np.full(runs, 0.3)}

SIMULATORS = tuple(
    Simulator("fake." + name, "misbehaves", {"duration": "duration"}, fn)
    for name, fn in [("exit", _exit), ("osexit", _underscore_exit), ("hang", _hang),
                     ("huge", _huge), ("nan", _nan), ("complex", _complex),
                     ("objects", _objects)]) + tuple(
    Simulator("fake." + name, "misbehaves", {"go": "duration", "fail": "probability"}, fn)
    for name, fn in [("both", _complex_both), ("fractions", _fractions)])
'''

SPEC = """machine m;

const int T_UP = [10, 11] from sim fake.{name}.duration;
var t : [0..60] init 0 clamp;

mode A = 0 initial;
mode Done = 1 final;

action Fly in A when t < 40 {{ t += T_UP; }}
action Land in A when t >= 40 {{ goto Done; }}

property done = P=? [ F mode == Done ];
"""


@pytest.fixture
def plugin(tmp_path: Path) -> dict[str, str]:
    """The environment of an afsmc process that has the plugin installed."""
    site = tmp_path / "site"
    info = site / "fakesims-0.1.dist-info"
    info.mkdir(parents=True)
    (site / "fakesims.py").write_text(PLUGIN, encoding="utf-8")
    (info / "METADATA").write_text("Metadata-Version: 2.1\nName: fakesims\nVersion: 0.1\n",
                                   encoding="utf-8")
    (info / "entry_points.txt").write_text("[afsmc.simulators]\nfake = fakesims:SIMULATORS\n",
                                           encoding="utf-8")
    path = os.environ.get("PYTHONPATH")
    return {**os.environ, "PYTHONPATH": os.pathsep.join(
        [str(site), str(ROOT)] + ([path] if path else []))}


def _sim_check(env: dict[str, str], spec: Path, *args: str) -> subprocess.CompletedProcess[str]:
    return subprocess.run([sys.executable, "-m", "afsmc", "sim-check", str(spec), "--runs", "200",
                           *args], capture_output=True, text=True, env=env, timeout=120)


def _spec(tmp_path: Path, name: str) -> tuple[Path, bytes]:
    path = tmp_path / f"{name}.afsm"
    path.write_text(SPEC.format(name=name), encoding="utf-8")
    return path, path.read_bytes()


@pytest.mark.parametrize(("name", "says"), [
    ("exit", "it raised SystemExit(0) instead of returning samples"),
    ("osexit", "it ended the process (exit code 0) without returning samples"),
    ("nan", "200 of its 200 samples are not finite numbers"),
    ("complex", "simulator 'fake.complex' output 'duration' holds complex numbers, not real "
                "ones"),
    ("objects", "simulator 'fake.objects' output 'duration' holds values of type 'object', "
                "not numbers"),
])
@pytest.mark.slow
def test_a_simulator_that_exits_or_lies_fails_at_the_constant(
        name: str, says: str, plugin: dict[str, str], tmp_path: Path) -> None:
    spec, before = _spec(tmp_path, name)
    r = _sim_check(plugin, spec, "--update")
    assert r.returncode == 1, r.stdout + r.stderr
    assert f"{spec}:3:27: error[E505]: simulator 'fake.{name}.duration' failed: {says}" \
        in r.stderr, r.stderr
    assert "Traceback" not in r.stderr
    assert spec.read_bytes() == before


TWO = """machine m;

const int T_GO = [10, 11] from sim fake.{name}.go;
const prob P_FAIL = 0.1 from sim fake.{name}.fail;
var t : [0..60] init 0 clamp;

mode A = 0 initial;
mode Done = 1 final;
mode Failed = 2 final;

action Fly in A when t < 40 {{ 1 - P_FAIL: t += T_GO; P_FAIL: goto Failed; }}
action Land in A when t >= 40 {{ goto Done; }}

property done = P=? [ F mode == Done ];
"""


@pytest.mark.parametrize(("name", "says"), [
    ("both", "simulator 'fake.both' output 'go' holds complex numbers, not real ones"),
    ("fractions", "simulator 'fake.fractions' output 'fail' holds values other than 0 and 1"),
])
@pytest.mark.slow
def test_update_leaves_the_spec_untouched_when_a_simulator_lies_about_its_kind(
        name: str, says: str, plugin: dict[str, str], tmp_path: Path) -> None:
    # complex samples were cast to real (a ComplexWarning) and --update wrote
    # T_GO = [1, 1] and P_FAIL = 1.0; a probability's 0.3 was cast to True
    spec = tmp_path / f"{name}.afsm"
    spec.write_text(TWO.format(name=name), encoding="utf-8")
    before = spec.read_bytes()
    r = _sim_check(plugin, spec, "--update")
    assert r.returncode == 1, r.stdout + r.stderr
    assert "error[E505]" in r.stderr and says in r.stderr, r.stderr
    assert "Warning" not in r.stderr and "Traceback" not in r.stderr, r.stderr
    assert spec.read_bytes() == before


@pytest.mark.slow
def test_a_simulator_that_exits_gives_a_json_verdict(plugin: dict[str, str],
                                                     tmp_path: Path) -> None:
    # SystemExit(0) made sim-check exit 0 with no verdict and no JSON
    import json

    spec, _ = _spec(tmp_path, "exit")
    r = _sim_check(plugin, spec, "--json")
    assert r.returncode == 1
    diags = json.loads(r.stdout)["diagnostics"]
    assert [(d["code"], d["line"], d["column"]) for d in diags] == [("E505", 3, 27)]


@pytest.mark.slow
def test_a_hanging_simulator_is_stopped_at_the_timeout(plugin: dict[str, str],
                                                       tmp_path: Path) -> None:
    spec, before = _spec(tmp_path, "hang")
    started = time.monotonic()
    r = _sim_check(plugin, spec, "--timeout", "2", "--update")
    assert time.monotonic() - started < 60
    assert r.returncode == 1, r.stdout + r.stderr
    assert ("error[E505]: simulator 'fake.hang.duration' failed: it did not finish within "
            "--timeout 2 s (raise --timeout SECONDS if it needs longer)") in r.stderr, r.stderr
    assert spec.read_bytes() == before


@pytest.mark.slow
def test_update_refuses_a_value_that_would_not_check(plugin: dict[str, str],
                                                     tmp_path: Path) -> None:
    # -1e308 per run: the suggested interval is two 309-digit integers (E245 in check)
    spec, before = _spec(tmp_path, "huge")
    r = _sim_check(plugin, spec, "--update")
    assert r.returncode == 1, r.stdout + r.stderr
    assert f"{spec}:3:1: error[E509]: --update would write T_UP = [-1000" in r.stderr, r.stderr
    assert "which does not check: E245" in r.stderr and "is left unchanged" in r.stderr
    assert "Warning" not in r.stderr and "Traceback" not in r.stderr, r.stderr
    assert spec.read_bytes() == before
    # without --update it is a drift, as for any simulator
    r = _sim_check(plugin, spec)
    assert r.returncode == 1 and "error[E502]" in r.stderr, r.stderr


@pytest.mark.parametrize("bad", ["0", "-1", "nan", "soon"])
def test_timeout_must_be_a_positive_number(bad: str) -> None:
    r = run_cli("sim-check", str(CASES / "sim_mission" / "mission.afsm"), "--timeout", bad)
    assert r.code == 2 and "--timeout" in r.err, r.err


@pytest.mark.slow
def test_runs_that_memory_cannot_hold_are_refused(plugin: dict[str, str],
                                                  tmp_path: Path) -> None:
    # 10^9 runs reached 12.8 GB in 60 s
    spec, _ = _spec(tmp_path, "exit")
    # (10^9, the largest --runs takes: its samples need far more than this machine's memory)
    r = subprocess.run([sys.executable, "-m", "afsmc", "sim-check", str(spec), "--runs",
                        str(10**9)], capture_output=True, text=True, env=plugin, timeout=120)
    assert r.returncode == 2, r.stderr
    assert "--runs 1,000,000,000 is more than the" in r.stderr
    assert "lower --runs, or free memory to raise the limit" in r.stderr
