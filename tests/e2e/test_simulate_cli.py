"""`afsmc simulate` on the command line: traces, usage and model errors, options that would
be ignored, headers, runs that cannot end, dying workers, unreachable Dask schedulers and
interrupts."""

from __future__ import annotations

import json
import math
import os
from pathlib import Path

import pytest

from afsmc.simlib import registry
from afsmc.verify import run
from tests.conftest import run_cli
from tests.unit.sim.test_simulate import MISSION, PATROL, UAV, sim_json, storm_values


def test_a_reward_interval_needs_two_finished_runs() -> None:
    """One run, or no run that finishes, gives no sample variance: the interval of an
    expected reward is unbounded above (not the zero width of a variance taken as 0), and
    with no finished run there is no estimate at all; the text says what to raise. These
    rewards are never negative, so the interval starts at 0."""
    one = sim_json(PATROL, "--runs", "1")
    steps = next(p for p in one["properties"] if p["name"] == "duration")  # type: ignore[union-attr]
    assert steps["low"] == 0 and steps["high"] == "inf" and steps["estimate"] > 0
    none = sim_json(UAV, "--runs", "20", "--max-steps", "1")  # no UAV mission ends in 1 step
    drops = next(p for p in none["properties"] if p["name"] == "drops")  # type: ignore[union-attr]
    assert drops["undecided"] == 20 and drops["estimate"] is None
    assert drops["low"] == 0 and drops["high"] == "inf"
    two = sim_json(PATROL, "--runs", "2")
    steps = next(p for p in two["properties"] if p["name"] == "duration")  # type: ignore[union-attr]
    assert math.isfinite(steps["low"]) and math.isfinite(steps["high"])
    text = run_cli("simulate", str(PATROL), "--runs", "1")
    assert text.code == 0
    line = next(x for x in text.out.splitlines() if x.strip().startswith("duration"))
    assert "[0, inf]" in line and "raise --runs" in line, line
    text = run_cli("simulate", str(UAV), "--runs", "20", "--max-steps", "1")
    line = next(x for x in text.out.splitlines() if x.strip().startswith("drops"))
    assert "n/a  [0, inf]" in line and "raise --max-steps" in line, line


def test_traces_in_mission_terms(tmp_path: Path) -> None:
    out = tmp_path / "traces.json"
    r = run_cli("simulate", str(MISSION), "--runs", "100", "--traces", "2",
                "--traces-out", str(out))
    assert r.code == 0, r.err
    assert r.out.startswith("trace 1 (")
    assert "--Lift--> Search" in r.out
    assert "pos.x=0" in r.out  # display names, not the flat pos_x
    traces = json.loads(out.read_text())
    assert len(traces) == 2
    first = traces[0]
    assert first[0] == {"step": 0, "mode": "TakeOff",
                        "vars": {"t": 0, "b": 100, "obj": 0, "pos.x": 0, "pos.y": 0}}
    assert first[-1]["mode"] in ("Done", "Emergency")


def test_usage_and_model_errors(tmp_path: Path) -> None:
    assert run_cli("simulate", str(PATROL), "--runs", "0").code == 2
    bad = tmp_path / "bad.afsm"
    bad.write_text("machine m;\nvar x : [0..2] init 0;\nmode A = 0 initial;\n"
                   "action Go in A { x := x + nope; }\n")
    r = run_cli("simulate", str(bad))
    assert r.code == 1
    assert "E203" in r.err and "Traceback" not in r.err


@pytest.mark.storm
def test_no_properties_is_e407_as_in_verify_unless_traces_are_asked(tmp_path: Path) -> None:
    """No properties is an error (E407, exit 1), as in verify, not an empty table."""
    f = tmp_path / "bare.afsm"
    f.write_text("machine bare;\nvar x : [0..2] init 0;\nmode A = 0 initial;\nmode B = 1 final;\n"
                 "action Go in A { 0.5: x := 1; 0.5: goto B; }\n")
    for cmd in ("simulate", "verify"):
        r = run_cli(cmd, str(f), *(["--runs", "10"] if cmd == "simulate" else []))
        assert r.code == 1, (cmd, r.err)
        assert f"error[E407]: {f} declares no properties" in r.err and "Traceback" not in r.err
    out = tmp_path / "traces.json"
    r = run_cli("simulate", str(f), "--runs", "10", "--traces", "2", "--traces-out", str(out))
    assert r.code == 0, r.err  # sample runs are a use of a file without properties
    assert r.out.startswith("trace 1 (") and len(json.loads(out.read_text())) == 2


def test_traces_out_is_checked_before_the_runs(tmp_path: Path) -> None:
    blocker = tmp_path / "file"
    blocker.write_text("")
    r = run_cli("simulate", str(PATROL), "--runs", "10", "--traces", "1",
                "--traces-out", str(blocker / "t.json"))
    assert r.code == 1
    assert f"error[E003]: cannot write {blocker / 't.json'}: {blocker} is not a directory" in r.err
    assert "simulate:" not in r.err and not r.out  # no run was made
    r = run_cli("simulate", str(PATROL), "--runs", "10", "--traces", "1", "--traces-out",
                str(PATROL))
    assert r.code == 1 and "error[E002]: refusing to overwrite the input" in r.err


def test_traces_out_without_traces_is_a_usage_error(tmp_path: Path) -> None:
    # Not an empty list: no runs are saved unless --traces K asks for them.
    out = tmp_path / "t.json"
    r = run_cli("simulate", str(PATROL), "--runs", "10", "--traces-out", str(out))
    assert r.code == 2 and "--traces-out needs --traces K" in r.err, r.err
    assert not out.exists()


@pytest.mark.parametrize("command", ["simulate", "sim-check"])
def test_a_negative_seed_is_a_usage_error(command: str) -> None:
    # numpy takes no negative seed: it was a traceback (simulate) or blamed a simulator (E505)
    r = run_cli(command, str(PATROL), "--seed", "-1", "--runs", "10")
    assert r.code == 2 and "--seed: expected an integer from 0 to" in r.err, r.err


def test_options_that_would_be_ignored_are_refused_or_honoured() -> None:
    """More traces than runs, --jobs beside --dask, and --list with a FILE are usage errors
    (each was silently ignored); --json keeps the traces --traces asked for."""
    assert run_cli("simulate", str(PATROL), "--runs", "3", "--traces", "5").code == 2
    assert run_cli("simulate", str(PATROL), "--dask", "tcp://127.0.0.1:1", "--jobs", "2").code == 2
    r = run_cli("sim-check", "--list", str(PATROL))
    assert r.code == 2 and "takes no FILE" in r.err
    # usage errors, before any run: --runs 10^14 (1.5e9 seeds, out of memory), a huge
    # --batch-size (an array per variable), and '' or '-' as the traces' file
    for argv, said in ((["--runs", str(10**14)], "--runs: expected an integer from 1 to "
                        "100,000,000,000"),
                       (["--runs", str(10**9), "--batch-size", "1"],
                        "1,000,000,000 batches, more than 100,000"),
                       (["--batch-size", str(10**8)], "--batch-size: expected an integer "
                        "from 1 to 1,000,000"),
                       (["--traces", "1", "--traces-out", ""], "--traces-out '': give a file"),
                       (["--traces", "1", "--traces-out", "-"], "--traces-out '-': give a")):
        r = run_cli("simulate", str(PATROL), *argv)
        assert r.code == 2 and said in r.err, (argv, r.err)
    # --list --json printed the text listing
    r = run_cli("sim-check", "--list", "--json")
    listed = json.loads(r.out)["outputs"]
    assert r.code == 0 and [o["ref"] for o in listed] == registry.available()
    assert {o["kind"] for o in listed} <= {"duration", "battery", "probability"}
    assert "uav.takeoff.duration" in [o["ref"] for o in listed]
    data = sim_json(PATROL, "--runs", "20", "--traces", "2")
    traces = data["traces"]
    assert isinstance(traces, list) and len(traces) == 2
    assert all(isinstance(t, list) and t for t in traces)
    assert "traces" not in sim_json(PATROL, "--runs", "20")


def test_the_header_names_the_resolution_only_for_a_model_with_intervals(tmp_path: Path) -> None:
    """`--resolve floor` on a model without interval constants does not print 'interval
    constants floor', as if the choice had changed the runs."""
    f = tmp_path / "plain.afsm"
    f.write_text("machine plain;\nvar x : [0..3] init 0;\nmode A = 0 initial;\n"
                 "mode B = 1 final;\naction Go in A when x < 3 { 0.5: x += 1; 0.5: goto B; }\n"
                 "action Stop in A when x == 3 { goto B; }\nlabel top = x == 3;\n"
                 "property top = P=? [ F \"top\" ];\n")
    r = run_cli("simulate", str(f), "--runs", "10", "--resolve", "floor")
    assert r.code == 0, r.err
    assert "plain.afsm: 10 runs, no interval constants, seed 0" in r.out, r.out
    for how, said in (("floor", "at their floor"), ("hi", "at their ceiling"),
                      ("uniform", "uniform")):
        r = run_cli("simulate", str(PATROL), "--runs", "10", "--resolve", how)
        assert f"patrol.afsm: 10 runs, interval constants {said}, seed 0" in r.out, r.out


def test_runs_that_cannot_end_say_why(tmp_path: Path) -> None:
    """A loop whose final mode is unreachable: every run is undecided at --max-steps, and
    "raise --max-steps" could never help. The check's warnings are shown, as
    verify shows them, and the note names W602 instead."""
    f = tmp_path / "loop.afsm"
    f.write_text("machine loop;\nmode A = 0 initial;\nmode B = 1;\nmode Z = 2 final;\n"
                 "action Go in A { goto B; }\naction Back in B { goto A; }\n"
                 "property p = P=? [ F mode == Z ];\nrewards r { true : 1; }\n"
                 'property c = R{"r"}=? [ F mode == Z ];\n')
    r = run_cli("simulate", str(f), "--runs", "20", "--max-steps", "50")
    assert r.code == 0, r.err
    assert "warning[W602]" in r.err and "warning[W601]" in r.err, r.err
    lines = {line.split()[0]: line for line in r.out.splitlines()[1:]}
    assert "20 undecided at --max-steps; some modes cannot reach an end (W602): a run there " \
        "may stay undecided whatever --max-steps" in lines["p"], lines
    data = sim_json(f, "--runs", "20", "--max-steps", "50")
    assert {w["code"] for w in data["warnings"]} == {"W601", "W602"}, data["warnings"]
    assert sim_json(PATROL, "--runs", "10")["warnings"] == []


@pytest.mark.storm
def test_a_large_reward_keeps_a_narrow_interval(tmp_path: Path) -> None:
    """3e9 plus a geometric number of 0.001s: sum(x^2)/m - mean^2 lost every digit of the
    variance, and the 99.9% interval was +-2.6 wide for a standard error of 1e-5.
    It must hold Storm's value and be about as narrow as the spread says."""
    f = tmp_path / "big.afsm"
    f.write_text("machine big;\nmode S = 0 initial;\nmode A = 1;\nmode Z = 2 final;\n"
                 "action Start in S { goto A; }\naction Go in A { 0.5: goto Z; 0.5: skip; }\n"
                 "rewards r { [Start] true : 3000000000; [Go] true : 0.001; }\n"
                 'property c = R{"r"}=? [ F mode == Z ];\n')
    exact = run(str(f), isolate=False).property("c").value
    assert exact == pytest.approx(3e9 + 0.002, abs=1e-6)
    [c] = sim_json(f, "--runs", "10000")["properties"]  # type: ignore[misc]
    assert c["low"] <= exact <= c["high"], (c, exact)
    # the runs' standard deviation is 0.0014: a half-width of 3.3 * 0.0014 / 100
    assert c["high"] - c["low"] < 2e-4, c
    # and verify's and simulate's tables show the digits that differ (they said 3e+09)
    r = run_cli("verify", str(f))
    assert r.code == 0 and " 3000000000.002\n" in r.out, r.out
    r = run_cli("simulate", str(f), "--runs", "10000")
    assert r.code == 0 and "  c         3000000000.002  [3000000000.0019, 3000000000.002]" \
        in r.out, r.out


def test_resolve_min_and_max_are_refused_with_the_reason() -> None:
    """`--resolve min` meant always the floor, which on patrol.afsm gives the *larger*
    probability of finishing: a user reading it as Pmin got Pmax's side.
    lo/hi are the spellings of `compile --resolve`, and run the same as floor/ceil."""
    for which in ("min", "max"):
        r = run_cli("simulate", str(PATROL), "--runs", "10", "--resolve", which)
        assert r.code == 2 and "cannot find the MDP's P" + which in r.err, r.err
        assert "afsmc verify" in r.err and "Traceback" not in r.err
    assert sim_json(PATROL, "--runs", "200", "--resolve", "lo")["properties"] == \
        sim_json(PATROL, "--runs", "200", "--resolve", "floor")["properties"]


@pytest.mark.slow
def test_a_worker_that_dies_is_a_diagnostic_not_an_internal_error() -> None:
    """A killed worker process (the OOM killer) surfaced as BrokenProcessPool: exit 3."""
    import signal
    import subprocess
    import sys
    import time

    proc = subprocess.Popen([sys.executable, "-m", "afsmc.cli", "simulate", str(UAV),
                             "--runs", "5000000", "--jobs", "2"],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                            start_new_session=True)
    try:
        children: list[int] = []
        deadline = time.monotonic() + 60
        while not children and time.monotonic() < deadline and proc.poll() is None:
            time.sleep(0.2)
            with open(f"/proc/{proc.pid}/task/{proc.pid}/children") as f:
                children = [int(c) for c in f.read().split()]
        assert children, "no worker process started"
        time.sleep(1.0)  # let it reach the pool's loop
        os.kill(children[-1], signal.SIGKILL)
        _, err = proc.communicate(timeout=120)
    finally:
        if proc.poll() is None:
            os.killpg(proc.pid, signal.SIGKILL)
    assert proc.returncode == 1, err[-1500:]
    assert "error[E506]" in err and "a worker process died" in err and "internal error" not in err


@pytest.mark.storm
@pytest.mark.parametrize(("command", "code"), [
    (["simulate", "--runs", "10"], "E507"), (["sweep", "--bound", "0:2", "-p", "finish_soon"],
                                             "E413")])
def test_an_unreachable_dask_scheduler_is_a_diagnostic(command: list[str], code: str) -> None:
    """Nothing listens on port 1 of this machine: a diagnostic that asks whether a
    scheduler runs there, not a traceback (simulate's had no hint)."""
    import dask
    import distributed  # noqa: F401  (its defaults first: leaving set() would drop them)

    with dask.config.set({"distributed.comm.timeouts.connect": "1s"}):
        r = run_cli(command[0], str(PATROL), *command[1:], "--dask", "tcp://127.0.0.1:1")
    assert r.code == 1 and f"error[{code}]" in r.err, r.err
    assert "is a Dask scheduler running at tcp://127.0.0.1:1?" in r.err
    assert "Traceback" not in r.err


@pytest.mark.slow
@pytest.mark.storm
@pytest.mark.parametrize(("as_json", "jobs"), [(True, 1), (False, 1), (True, 2)])
def test_an_interrupted_simulation_keeps_the_runs_that_finished(tmp_path: Path,
                                                                as_json: bool,
                                                                jobs: int) -> None:
    # SIGTERM (as `kill` or a batch system's timeout sends it) after the first batches: the
    # estimate of those runs is printed, and for --json is the object's data. With worker
    # processes too, which stop at once (the pool does not run every queued batch first).
    import signal
    import subprocess
    import sys
    import time

    exact = storm_values(PATROL, "uniform", tmp=tmp_path)
    argv = [sys.executable, "-m", "afsmc", "simulate", str(PATROL), "--runs", "100000000",
            "--batch-size", "2000", "--jobs", str(jobs), *(["--json"] if as_json else [])]
    proc = subprocess.Popen(argv, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    assert proc.stderr is not None
    for line in proc.stderr:  # the first progress line follows the first batch
        if line.startswith("simulate: ") and "runs (" in line:
            break
    time.sleep(0.5)
    proc.send_signal(signal.SIGTERM)
    try:
        out, err = proc.communicate(timeout=30)
    except subprocess.TimeoutExpired:
        proc.kill()
        raise AssertionError("SIGTERM did not stop the simulation") from None
    assert proc.returncode == 143, err
    assert "Traceback" not in err and "afsmc: terminated" in err
    assert "runs that finished estimate" in err, err
    if not as_json:
        assert out == "", out
        return
    data = json.loads(out)
    assert data["interrupted"] is True and data["diagnostics"][0]["code"] == "N412"
    assert 2000 <= data["runs"] < 100_000_000 and data["runs"] % 2000 == 0
    assert f"the {data['runs']:,} of 100,000,000 runs" in err
    assert [p["name"] for p in data["properties"]] == list(exact)
    for p in data["properties"]:
        assert p["low"] <= exact[p["name"]] <= p["high"], (p, exact[p["name"]])
