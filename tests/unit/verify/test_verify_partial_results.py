"""Partial results: a Storm process that fails, dies or is stopped keeps the answers it had,
the open queries go on in a fresh process, and the values kept are reported as answered."""

from __future__ import annotations

import json
from collections.abc import Callable
from pathlib import Path

import pytest

from afsmc.compiler import load
from afsmc.verify import run
from afsmc.verify.engines.storm import Job
from tests.conftest import run_cli
from tests.unit.backends.test_prism import SMALL
from tests.unit.verify.test_engine_choice import UAV, WIDE, _close, _values


@pytest.mark.slow
@pytest.mark.storm
def test_auto_hybrid_process_stopped_keeps_its_answers(
        tmp_path: object, monkeypatch: pytest.MonkeyPatch) -> None:
    # The memory guard stops the process where "auto" picked hybrid after its first answer
    # (stand in for its verdict with Storm's real answers): the answer is kept, and the
    # rest (termination, the complement) run one per process.
    import pathlib

    from afsmc.verify.core import model_loop as runner
    from afsmc.verify.engines.guard import run_job as real
    from afsmc.verify.engines.storm import JobResult, StormFailure

    path = pathlib.Path(str(tmp_path)) / "wide.afsm"
    path.write_text(WIDE, encoding="utf-8")
    calls: list[tuple[str, ...]] = []

    def run_job(job: Job, bound: int, *, isolate: bool | None,
                progress: Callable[[str], None] | None) -> JobResult:
        calls.append(job.names + job.hybrid_extra)
        res = real(job, bound, isolate=isolate, progress=progress)
        if len(calls) == 1:
            first = next(iter(res.values))
            res.values = {first: res.values[first]}
            res.failure = StormFailure("memory", "stopped the MDP after 1 s: it used 9.9 GB, "
                                       "85% of the memory that was available")
        return res

    sparse = run(str(path), properties=["reach"], engine="sparse", isolate=False,
                 uniform=False)
    monkeypatch.setattr(runner, "run_job", run_job)
    said: list[str] = []
    tight = run(str(path), properties=["reach"], engine="auto", memory_budget=1,
                uniform=False, progress=said.append)
    stopped = [s for s in said if "queries were answered" in s]
    assert len(stopped) == 1 and "1 of its 3 queries" in stopped[0], said
    assert calls == [("reach_min", "reach_max", "__afsmc_terminates", "__afsmc_rest_reach"),
                     ("__afsmc_terminates",), ("__afsmc_rest_reach",)], calls
    assert tight.model.processes == 3, said
    _close(_values(tight), _values(sparse), 1e-6)


@pytest.mark.slow
@pytest.mark.storm
def test_a_grouped_process_that_dies_keeps_its_answers_and_the_rest_run_alone() -> None:
    # Kill the first process as soon as it has answered one query, as the memory guard
    # would: the answered value is kept, the others each get a process of their own.
    import multiprocessing
    import os
    import signal

    said: list[str] = []
    killed: list[int] = []

    def progress(s: str) -> None:
        said.append(s)
        if s.startswith("checked ") and not killed:
            for child in multiprocessing.active_children():
                if child.pid is not None:
                    os.kill(child.pid, signal.SIGKILL)
                    killed.append(child.pid)

    names = ["success", "drops"]
    hybrid = run(UAV, consts=SMALL["uav"], properties=names, engine="hybrid", uniform=False,
                 progress=progress)
    sparse = run(UAV, consts=SMALL["uav"], properties=names, engine="sparse", isolate=False,
                 uniform=False)
    assert killed, said
    _close(_values(hybrid), _values(sparse), 1e-6)
    stopped = [s for s in said if "queries were answered" in s]
    assert len(stopped) == 1 and "1 of its 2 queries" in stopped[0], said
    # drops_min and drops_max together; then the one the process had not answered alone;
    # then the probabilities (success_max as 1 - Pmin): the stopped process counts too
    assert hybrid.model.processes == 3, said
    assert sum("(drops_max) in its own Storm process" in s for s in said) == 1, said


def _stop_after_first_answer(monkeypatch: pytest.MonkeyPatch, stop: Callable[
        [dict[str, float]], BaseException | None]) -> None:
    """Run the first Storm job for real, then fail it (or raise) with its first answer only:
    what a memory stop or a Ctrl-C leaves, with Storm's real value."""
    from afsmc.verify.core import model_loop as runner
    from afsmc.verify.engines.guard import run_job as real
    from afsmc.verify.engines.storm import JobResult, StormFailure

    calls: list[int] = []

    def run_job(job: Job, bound: int, *, isolate: bool | None,
                progress: Callable[[str], None] | None) -> JobResult:
        calls.append(1)
        res = real(job, bound, isolate=isolate, progress=progress)
        first = job.names[0]
        res.values = {first: res.values[first]}
        exc = stop(res.values)
        if exc is not None:
            raise exc
        res.failure = StormFailure("memory", "stopped the MDP after 1 s: it used 9.9 GB, 85% "
                                   "of the memory that was available")
        return res

    monkeypatch.setattr(runner, "run_job", run_job)


@pytest.mark.slow
@pytest.mark.storm
def test_a_failed_run_reports_the_values_it_had(monkeypatch: pytest.MonkeyPatch) -> None:
    from afsmc.diagnostics import CompileError, Severity

    names = ["success", "drops"]
    sparse = run(UAV, consts=SMALL["uav"], properties=names, engine="sparse", isolate=False,
                 uniform=False)
    _stop_after_first_answer(monkeypatch, lambda _v: None)
    with pytest.raises(CompileError) as info:
        run(UAV, consts=SMALL["uav"], properties=names, engine="sparse", uniform=False)
    codes = [(d.code, d.severity) for d in info.value.diagnostics]
    assert codes == [("E406", Severity.ERROR), ("N412", Severity.NOTE)], codes
    note = info.value.diagnostics[1].message
    # the check ran out of memory after the build: that process's other queries are not
    # asked again (they would need as much), and the run ends with what it has
    assert note == ("the other queries were answered:\n"
                    f"  success_min = {sparse.property('success').min!r} on the MDP\n"
                    "not answered: success_max on the MDP, drops_min on the MDP, "
                    "drops_max on the MDP"), note


def test_kept_values_give_each_pmax_from_its_complement() -> None:
    from afsmc.verify.plan.queries import TERMINATES, complements, kept_note

    model = load(UAV, SMALL["uav"]).model
    comp = complements(model, [p for p in model.properties if p.name == "success"])
    rest = comp["success_max"].name
    ends = kept_note([("MDP", {"success_min": 0.5, TERMINATES: 1.0, rest: 0.25})], comp)
    assert [d.message for d in ends] == [
        "answered before this:\n  success_min = 0.5 on the MDP\n  success_max = 0.75 on the MDP"]
    # if not every path ends, the complement does not give the Pmax: it is left out
    open_ = kept_note([("MDP", {"success_min": 0.5, TERMINATES: 0.9, rest: 0.25})], comp)
    assert [d.message for d in open_] == ["answered before this:\n  success_min = 0.5 on the MDP"]
    assert kept_note([("MDP", {})], comp) == []


NEXT = """machine nx;
var x : [0..3] init 0;
mode A = 0 initial;
mode B = 1 final;
action Go in A when x < 3 { 0.3: x := x + 1; 0.7: goto B; }
action Stop in A when x >= 3 { goto B; }
rewards steps { true : 1; }
property nxt   = P=? [ X x == 1 ];
property reach = P=? [ F x == 2 ];
property steps = R{"steps"}=? [ F mode == B ];
"""


@pytest.mark.slow
@pytest.mark.storm
def test_a_query_storm_cannot_check_does_not_cost_the_others(tmp_path: Path) -> None:
    """Storm's hybrid engine cannot check X from JANI (a one-step bounded until); that is
    its error, but the queries after it in the same process, and the other process's, are
    still asked, and their values come with the error."""
    from afsmc.diagnostics import CompileError, Severity

    path = tmp_path / "nx.afsm"
    path.write_text(NEXT, encoding="utf-8")
    said: list[str] = []
    with pytest.raises(CompileError) as info:
        run(str(path), via="jani", engine="hybrid", progress=said.append)
    codes = [(d.code, d.severity) for d in info.value.diagnostics]
    assert codes == [("E404", Severity.ERROR), ("N412", Severity.NOTE)], codes
    e404, note = info.value.diagnostics
    assert "'nxt'" in e404.message and e404.span is not None and e404.span.line == 8
    assert any("the other queries go on" in s for s in said), said
    exact = run(str(path), via="jani", engine="sparse", isolate=False)
    assert note.message == ("the other queries were answered:\n"
                            f"  steps = {exact.property('steps').value!r} on the DTMC\n"
                            f"  reach = {exact.property('reach').value!r} on the DTMC\n"
                            "not answered: nxt on the DTMC"), \
        note.message
    # the same through the CLI: exit 1, the error, then the values
    r = run_cli("verify", str(path), "--via", "jani", "--engine", "hybrid")
    assert r.code == 1 and "error[E404]" in r.err and "the other queries were answered" in r.err
    assert "reach = " in r.err and "Traceback" not in r.err, r.err
    # --json: the values answered as data, null where the query failed
    r = run_cli("verify", str(path), "--via", "jani", "--engine", "hybrid", "--json")
    assert r.code == 1, r.err
    obj = json.loads(r.out)
    assert [d["code"] for d in obj["diagnostics"]] == ["E404", "N412"], obj
    assert {p["name"]: p["value"] for p in obj["properties"]} == {
        "nxt": None, "reach": exact.property("reach").value,
        "steps": exact.property("steps").value}, obj["properties"]
    assert obj["model"]["states"] == exact.model.states, obj["model"]
    # the same when the query that fails is the last one (its process was the
    # only one of the model to build it, and the model's sizes were null)
    nxt = "property nxt   = P=? [ X x == 1 ];\n"
    last = tmp_path / "nx_last.afsm"
    last.write_text(NEXT.replace(nxt, "") + nxt, encoding="utf-8")
    r = run_cli("verify", str(last), "--via", "jani", "--engine", "hybrid", "--json",
                "-p", "reach", "-p", "nxt")
    obj = json.loads(r.out)
    assert r.code == 1 and obj["model"] is not None, r.out
    assert (obj["model"]["states"], obj["model"]["transitions"]) == \
        (exact.model.states, exact.model.transitions), obj["model"]


@pytest.mark.slow
@pytest.mark.storm
def test_the_fresh_process_after_a_failed_query_asks_only_what_is_open(tmp_path: Path) -> None:
    """`reach` is answered before `nxt` fails in the same process: the fresh process that
    follows asks `again` only, not `reach` a second time."""
    from afsmc.diagnostics import CompileError

    path = tmp_path / "nx2.afsm"
    path.write_text(NEXT.replace("property nxt", "property again = P=? [ F x == 3 ];\n"
                                 "property nxt").replace("property steps", "// "),
                    encoding="utf-8")
    said: list[str] = []
    with pytest.raises(CompileError) as info:
        run(str(path), via="jani", engine="hybrid", isolate=True, progress=said.append)
    checked = [s.split()[1] for s in said if s.startswith("checked ")]
    assert sorted(checked) == ["again", "reach"], said
    e404, note = info.value.diagnostics
    assert e404.code == "E404" and "'nxt'" in e404.message
    assert "reach = " in note.message and "again = " in note.message, note.message


@pytest.mark.slow
@pytest.mark.storm
def test_auto_one_query_per_process_goes_on_past_what_hybrid_refuses(tmp_path: Path) -> None:
    """With --split, "auto" learns in the first process that it checks with hybrid, which has
    no R [ C ]: `total` is an error on each model (its min and max one), and every other
    query of both models is still answered, with the sparse engine's values."""
    from afsmc.diagnostics import CompileError

    path = tmp_path / "wide.afsm"
    path.write_text(WIDE + 'property total = R{"steps"}=? [ C ];\n', encoding="utf-8")
    with pytest.raises(CompileError) as info:
        run(str(path), properties=["total", "steps", "reach"], engine="auto", memory_budget=1,
            split=True)
    *errors, note = info.value.diagnostics
    assert [(d.code, "'total'" in d.message) for d in errors] == [("E404", True)] * 2, errors
    assert "on the MDP" in errors[0].message and "uniform DTMC" in errors[1].message
    exact = run(str(path), properties=["steps", "reach"], engine="sparse", isolate=False)
    *lines, missing = note.message.splitlines()[1:]
    assert missing == ("not answered: total_min on the MDP, total_max on the MDP, "
                       "total on the uniform DTMC"), missing
    got = dict(line.strip().split(" = ", 1) for line in lines)
    assert set(got) == {"steps_min", "steps_max", "reach_min", "reach_max", "steps", "reach"}
    for key, value in got.items():
        v = float(value.split(" on the ")[0])
        base = key.rsplit("_", 1)
        truth = exact.property(base[0]) if base[-1] in ("min", "max") else exact.property(key)
        ref = {"min": truth.min, "max": truth.max}.get(base[-1], truth.uniform)
        assert ref is not None and abs(v - ref) < 1e-6, (key, v, ref)


TRAP = """machine trap;
const int D = [1, 2];
var x : [0..3] init 0 clamp;
mode A = 0 initial;
mode B = 1 final;
mode C = 2;
action Stay in C { goto C; }
hazard Trap from A with probability 0.05 { goto C; }
action Go in A when x < 3 { 0.3: x += D; 0.7: goto B; }
action Stop in A when x >= 3 { goto B; }
property r1 = P=? [ F mode == B & x == 1 ];
property r3 = P=? [ F mode == B & x == 3 ];
"""


@pytest.mark.slow
@pytest.mark.storm
def test_a_failed_complement_does_not_matter_where_not_every_path_ends(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """Mode C traps some paths outside the final modes, so each Pmax is asked itself, not as
    1 - Pmin of its complement. A complement that failed (here, faked to run out of memory)
    is then no error: every value is answered, equal to the sparse engine's, and no error
    is raised."""
    from afsmc.verify.core import model_loop as runner
    from afsmc.verify.engines.guard import run_job as real
    from afsmc.verify.engines.storm import JobResult, StormFailure

    path = tmp_path / "trap.afsm"
    path.write_text(TRAP, encoding="utf-8")
    exact = run(str(path), engine="sparse", isolate=False, uniform=False)

    def run_job(job: Job, bound: int, *, isolate: bool | None,
                progress: Callable[[str], None] | None) -> JobResult:
        res = real(job, bound, isolate=isolate, progress=progress)
        if "__afsmc_rest_r1" in res.values:
            order = list(res.values)
            res.values = {k: res.values[k] for k in order[:order.index("__afsmc_rest_r1")]}
            res.failure = StormFailure("memory", "stopped the MDP", prop="__afsmc_rest_r1")
        return res

    monkeypatch.setattr(runner, "run_job", run_job)
    said: list[str] = []
    got = run(str(path), engine="hybrid", uniform=False, split=True, progress=said.append)
    assert any("while checking r1_max as 1 - Pmin" in s for s in said), said
    _close(_values(got), _values(exact), 1e-9)


def test_a_sweep_names_its_points_properties_as_written() -> None:
    from afsmc.diagnostics import Diagnostic, Severity
    from afsmc.verify.core.options import VerifyOptions
    from afsmc.verify.reports.sweep_tasks import Task, user_words

    made = [Diagnostic("E406", Severity.ERROR, f"stopped while checking reach__at{i}_max as "
                       "1 - Pmin", None) for i in range(3)]
    made.append(Diagnostic("N412", Severity.NOTE, "answered:\n  reach__at1_min = 0.5", None))
    task = Task("m.afsm", "", (), (), (), "K", "const", (3, 5),
                VerifyOptions(engine="hybrid"))
    d, note = user_words(made, task)
    assert d.message == "stopped while checking reach_max as 1 - Pmin", d.message
    assert note.message == "answered:\n  reach_min at K=5 = 0.5", note.message
