"""Stopping `afsmc verify` (Ctrl-C, SIGTERM, a killed afsmc): the values it had are printed,
in text or JSON, and no Storm process is left behind."""

from __future__ import annotations

import json
import subprocess
from pathlib import Path

import pytest

from afsmc.verify import run
from tests.unit.backends.test_prism import SMALL
from tests.unit.verify.test_engine_choice import UAV
from tests.unit.verify.test_verify_partial_results import NEXT, _stop_after_first_answer

pytestmark = pytest.mark.storm


@pytest.mark.slow
def test_ctrl_c_prints_the_values_verify_had(monkeypatch: pytest.MonkeyPatch,
                                             capsys: pytest.CaptureFixture[str]) -> None:
    from afsmc.cli import main
    from afsmc.verify.engines.guard import Interrupted

    sparse = run(UAV, consts=SMALL["uav"], properties=["success"], engine="sparse",
                 isolate=False, uniform=False)
    _stop_after_first_answer(monkeypatch, lambda v: Interrupted(dict(v)))
    code = main(["verify", UAV, "-p", "success", "--no-uniform", "--engine", "sparse",
                 *[f"--const={k}={v}" for k, v in SMALL["uav"].items()]])
    err = capsys.readouterr().err
    assert code == 130
    assert "afsmc: interrupted" in err
    assert f"success_min = {sparse.property('success').min!r} on the MDP" in err, err


@pytest.mark.slow
def test_ctrl_c_with_json_still_prints_one_json_object(monkeypatch: pytest.MonkeyPatch,
                                                       capsys: pytest.CaptureFixture[str]) -> None:
    from afsmc.cli import main
    from afsmc.verify.engines.guard import Interrupted

    sparse = run(UAV, consts=SMALL["uav"], properties=["success"], engine="sparse",
                 isolate=False, uniform=False)
    _stop_after_first_answer(monkeypatch, lambda v: Interrupted(dict(v)))
    code = main(["verify", UAV, "-p", "success", "--no-uniform", "--engine", "sparse", "--json",
                 *[f"--const={k}={v}" for k, v in SMALL["uav"].items()]])
    obj = json.loads(capsys.readouterr().out)
    assert code == 130 and obj["interrupted"] is True
    [note] = obj["diagnostics"]
    assert note["code"] == "N412"
    assert f"success_min = {sparse.property('success').min!r} on the MDP" in note["message"]
    # and as data: the answer so far, null for the query it was stopped in
    [prop] = obj["properties"]
    assert (prop["name"], prop["min"], prop["max"]) == \
        ("success", sparse.property("success").min, None), prop


def _interrupt(proc: subprocess.Popen[str], how: str) -> tuple[str, str]:
    """Ctrl-C (SIGINT to the whole process group, as a terminal sends it) or `kill PID`
    (SIGTERM to afsmc alone); its output, once it exited as a shell reports it (130 or
    128 + 15)."""
    import os
    import signal

    if how == "ctrl-c":
        os.killpg(proc.pid, signal.SIGINT)
    else:
        os.kill(proc.pid, signal.SIGTERM)
    out, err = proc.communicate(timeout=60)
    assert proc.returncode == (130 if how == "ctrl-c" else 143), err
    return out, err


def _group_ends(pgid: int, seconds: float = 10.0) -> None:
    """Wait for every process of the group to end; fail with their list if they do not."""
    import os
    import time

    deadline = time.monotonic() + seconds  # multiprocessing's resource tracker ends on its own
    while time.monotonic() < deadline:
        try:
            os.killpg(pgid, 0)
        except ProcessLookupError:
            return
        time.sleep(0.2)
    ps = subprocess.run(["ps", "-o", "pid,args", "-g", str(pgid)], text=True,
                        capture_output=True).stdout
    os.killpg(pgid, 9)
    raise AssertionError(f"processes of the group outlived afsmc:\n{ps}")


def _sigint_as_a_terminal_has_it() -> None:
    """A command started in the background (`cmd &` in a script) ignores SIGINT, and Python
    then raises no KeyboardInterrupt: the test sends Ctrl-C as a terminal would, so its
    afsmc starts with SIGINT's default, whoever started the tests."""
    import signal

    signal.signal(signal.SIGINT, signal.SIG_DFL)


def _verify_building(tmp_path: Path) -> subprocess.Popen[str]:
    """`afsmc verify` on an instance big enough for the guard's child, once it builds."""
    import sys

    argv = [sys.executable, "-m", "afsmc", "verify", UAV, "--json", "--progress",
            "--const", "WIDTH=5,HEIGHT=5,OBJECTS=2,T_LIMIT=400"]
    proc = subprocess.Popen(argv, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                            start_new_session=True, cwd=str(tmp_path),
                            preexec_fn=_sigint_as_a_terminal_has_it)
    assert proc.stderr is not None
    for line in proc.stderr:  # the child has started once it reports its build
        if "building the MDP" in line or "states of the MDP so far" in line:
            break
    return proc


@pytest.mark.slow
@pytest.mark.parametrize("how", ["ctrl-c", "sigterm"])
def test_ctrl_c_and_sigterm_stop_the_watched_storm_process(tmp_path: Path, how: str) -> None:
    # Ctrl-C: SIGINT to the whole process group, as a terminal sends it, exit 130.
    # `kill PID` (a CI timeout, a batch system): SIGTERM to afsmc alone, exit 128 + 15 as a
    # shell reports it. Either while the guard's child builds: one JSON object, no
    # traceback and no Storm process left behind.

    proc = _verify_building(tmp_path)
    out, err = _interrupt(proc, how)
    assert json.loads(out)["interrupted"] is True
    said = "afsmc: interrupted" if how == "ctrl-c" else "afsmc: terminated"
    assert "Traceback" not in err and said in err
    _group_ends(proc.pid)


@pytest.mark.slow
def test_a_killed_afsmc_leaves_no_storm_process_behind(tmp_path: Path) -> None:
    # SIGKILL to afsmc alone (no handler runs): its Storm child must not go on for an hour.
    import os
    import signal

    proc = _verify_building(tmp_path)
    os.kill(proc.pid, signal.SIGKILL)
    proc.communicate(timeout=60)
    assert proc.returncode == -signal.SIGKILL
    _group_ends(proc.pid)


def _terminate(proc: subprocess.Popen[str]) -> tuple[str, str]:
    """SIGTERM to afsmc alone, as `kill PID` does; its output, once it ended with 143."""
    import os
    import signal

    os.kill(proc.pid, signal.SIGTERM)
    try:
        out, err = proc.communicate(timeout=30)
    except subprocess.TimeoutExpired:
        os.killpg(proc.pid, signal.SIGKILL)
        raise AssertionError("SIGTERM did not stop the check") from None
    assert proc.returncode == 143, err
    return out, err


@pytest.mark.slow
def test_sigterm_stops_a_small_model_with_a_huge_step_bound(tmp_path: Path) -> None:
    """A 7-state model with F<=10^11 checks for hours. In afsmc's own process Storm's check
    would not see Ctrl-C or SIGTERM, so such a check runs in a child process: SIGTERM ends
    the command (exit 143) within seconds, and no Storm process is left."""
    import sys
    import time

    path = tmp_path / "long.afsm"
    path.write_text("var x : [0..5] init 0 clamp;\nmode A initial;\nmode B final;\n"
                    "action a in A when x < 5 { 0.5: x += 1; 0.5: skip; }\n"
                    "action b in A when x >= 5 { goto B; }\nlabel done = mode == B;\n"
                    "property p = P=? [ F<=99999999999 \"done\" ];\n")
    proc = subprocess.Popen([sys.executable, "-m", "afsmc", "verify", str(path), "--engine",
                             "sparse"], stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                            text=True, start_new_session=True)
    assert proc.stderr is not None
    for line in proc.stderr:
        if "built the" in line:
            break
    time.sleep(1.0)
    _, err = _terminate(proc)
    assert "afsmc: terminated" in err and "Traceback" not in err
    _group_ends(proc.pid)


@pytest.mark.slow
def test_sigterm_after_a_failed_query_reports_it_as_an_error_in_json(tmp_path: Path) -> None:
    """`--json` after SIGTERM: the query that had failed is an error entry with its place
    in the file, and the values answered since are the N412 note."""
    import sys

    path = tmp_path / "nxl.afsm"
    path.write_text(NEXT.replace("property steps", 'property slow = P=? [ F<=300000000 x == 3 ];'
                                 "\n// "), encoding="utf-8")
    proc = subprocess.Popen([sys.executable, "-m", "afsmc", "verify", str(path), "--via", "jani",
                             "--engine", "hybrid", "--json", "--progress"],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                            start_new_session=True)
    assert proc.stderr is not None
    for line in proc.stderr:
        if line.startswith("afsmc: checked reach"):
            break
    out, err = _terminate(proc)
    data = json.loads(out)
    assert data["interrupted"] is True
    e404, note = data["diagnostics"]
    assert e404["code"] == "E404" and e404["severity"] == "error" and e404["line"] == 8, e404
    assert note["code"] == "N412" and "reach = " in note["message"], note
    assert "error[E404]" in err and "Traceback" not in err
    values = {p["name"]: p["value"] for p in data["properties"]}
    exact = run(str(path), via="jani", engine="sparse", isolate=False, properties=["reach"])
    assert values == {"nxt": None, "reach": exact.property("reach").value, "slow": None}, values
    _group_ends(proc.pid)


@pytest.mark.slow
@pytest.mark.parametrize("how", ["ctrl-c", "sigterm"])
def test_ctrl_c_and_sigterm_remove_the_scratch_directory(tmp_path: Path, how: str) -> None:
    # `verify --scratch DIR` while its watched child writes the layers there: stopped, it
    # leaves DIR as it was (its own subdirectory removed after the child is gone).
    import sys

    scratch = tmp_path / "scratch"
    scratch.mkdir()
    argv = [sys.executable, "-m", "afsmc", "verify", UAV, "--json", "--progress",
            "--scratch", str(scratch), "--const", "WIDTH=4,HEIGHT=4,OBJECTS=2,T_LIMIT=300"]
    proc = subprocess.Popen(argv, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                            start_new_session=True, cwd=str(tmp_path),
                            preexec_fn=_sigint_as_a_terminal_has_it)
    assert proc.stderr is not None
    for line in proc.stderr:  # the layers are being written once it says so
        if "on the scratch disk" in line:
            break
    assert any(scratch.iterdir()), "no scratch directory while exploring"
    out, err = _interrupt(proc, how)
    assert json.loads(out)["interrupted"] is True and "Traceback" not in err
    _group_ends(proc.pid)
    assert list(scratch.iterdir()) == []
