"""Verification at scale: the automatic engine choice, bisimulation and the reductions
through `afsmc verify` give the same values as the plain sparse route."""

from __future__ import annotations

import dataclasses
import json
import re
import subprocess
from collections.abc import Callable
from pathlib import Path

import pytest

from afsmc.backends.prism import PrismOutput, emit, property_variants
from afsmc.compiler import load, lowered
from afsmc.lower.reduce import Reductions
from afsmc.model import ir
from afsmc.verify import run
from afsmc.verify.guard import IN_PROCESS_STATES
from afsmc.verify.storm import Job, execute
from tests.conftest import EXAMPLES, run_cli
from tests.test_prism import SMALL

UAV = str(EXAMPLES / "uav.afsm")


def _values(res: object) -> dict[str, tuple[float | None, ...]]:
    return {p.name: (p.min, p.max, p.uniform, p.value) for p in res.properties}  # type: ignore[attr-defined]


def _close(a: dict[str, tuple[float | None, ...]], b: dict[str, tuple[float | None, ...]],
           tol: float, rel: float | None = None) -> None:
    """Equal to `tol` (absolute), or also to `rel` (relative) if given."""
    assert a.keys() == b.keys()
    for name in a:
        for x, y in zip(a[name], b[name], strict=True):
            assert (x is None) == (y is None), name
            if x is not None and y is not None:
                assert x == pytest.approx(y, rel=rel, abs=tol), name


@pytest.mark.parametrize("path,consts", [(str(EXAMPLES / "patrol.afsm"), {}), (UAV, SMALL["uav"])])
def test_bisimulation_and_reductions_keep_every_value(path: str, consts: dict[str, str]) -> None:
    plain = run(path, consts=consts, engine="sparse", isolate=False)  # default reductions
    unreduced = run(path, consts=consts, engine="sparse", isolate=False,
                    reductions=Reductions.none())
    bisim = run(path, consts=consts, engine="sparse", isolate=False, bisimulation=True)
    _close(_values(plain), _values(unreduced), 1e-9)
    _close(_values(plain), _values(bisim), 1e-9)
    assert plain.model.states <= unreduced.model.states
    assert bisim.model.quotient_states is not None
    assert bisim.model.quotient_states <= plain.model.states


def test_auto_picks_sparse_for_small_models_and_says_why() -> None:
    res = run(str(EXAMPLES / "patrol.afsm"), engine="auto", isolate=False)
    assert res.model.engine == "sparse"
    assert "sparse engine is fastest" in res.model.engine_reason, res.model.engine_reason


def _small_uav(keep: Callable[[ir.Property], bool]) -> tuple[PrismOutput, tuple[str, ...]]:
    """The small UAV's PRISM text and the query names of the properties `keep` selects."""
    model = load(UAV, SMALL["uav"]).model
    low = lowered(model, "nondet")
    names = tuple(n for p in model.properties if keep(p) for n, _ in property_variants(low, p))
    return emit(low), names


def test_auto_falls_back_to_hybrid_when_sparse_would_not_fit() -> None:
    out, names = _small_uav(lambda p: p.kind == "P")
    sparse = execute(Job("prism", out.model, out.properties, names, "sparse"))
    tiny = execute(Job("prism", out.model, out.properties, names, "auto", memory_budget=1))
    roomy = execute(Job("prism", out.model, out.properties, names, "auto",
                        memory_budget=1 << 40))
    assert sparse.failure is None and tiny.failure is None and roomy.failure is None
    assert tiny.engine == "hybrid" and "more than" in tiny.engine_reason
    assert roomy.engine == "sparse"
    assert tiny.states == roomy.states == sparse.states
    for name in names:
        assert tiny.values[name] == pytest.approx(sparse.values[name], abs=1e-6)
        assert roomy.values[name] == pytest.approx(sparse.values[name], abs=1e-9)


def test_verify_cli_reports_the_engine_and_quotient() -> None:
    r = run_cli("verify", str(EXAMPLES / "patrol.afsm"), "--bisim", "--json")
    assert r.code == 0, r.err
    data = json.loads(r.out)
    assert data["model"]["engine"] == "sparse"
    assert data["model"]["quotient_states"] <= data["model"]["states"]
    r = run_cli("verify", str(EXAMPLES / "patrol.afsm"), "--no-reduce", "--json")
    assert json.loads(r.out)["model"]["states"] > data["model"]["states"]


def test_split_checks_each_property_in_its_own_process_with_the_same_values() -> None:
    names = ["success", "emergency"]
    together = run(UAV, consts=SMALL["uav"], properties=names, engine="sparse", isolate=False)
    said: list[str] = []
    split = run(UAV, consts=SMALL["uav"], properties=names, engine="sparse", split=True,
                progress=said.append)
    _close(_values(together), _values(split), 1e-12)
    # each process is announced, with the time spent so far
    queries = [s for s in said if ", query " in s]
    assert len(queries) == 2 * len(names) + len(names), said
    assert queries[0].startswith("MDP, query 1 of 4 (success_min)"), queries
    assert all(re.search(r"; \d+ (s|min) so far$", s) for s in queries), queries
    assert split.model.processes == 2 * len(names) and together.model.processes == 1
    assert split.uniform_model is not None and split.uniform_model.processes == len(names)
    assert split.model.states == together.model.states


def test_split_is_reported_by_the_cli() -> None:
    r = run_cli("verify", UAV, "--split", "-p", "success", "-p", "drops", "--no-uniform",
                "--json", *[f"--const={k}={v}" for k, v in SMALL["uav"].items()])
    assert r.code == 0, r.err
    assert json.loads(r.out)["model"]["processes"] == 4  # min and max of each


# Few states, but an upper bound (modes × ranges) above AUTO_SPARSE_BOUND, so that "auto"
# counts the states symbolically and decides with the memory budget.
WIDE = """machine wide;
const int STEP = [1, 2];
var x : [0..10] init 0 clamp;
var far : [0..1000000000] init 0;
mode Run = 0 initial;
mode End = 1 final;
action Go in Run when x < 10 { 0.9: x += STEP; 0.1: x += 1; }
action Stop in Run when x >= 10 { goto End; }
label done = mode == End && far == 0;
rewards steps { [Go] true : 1; }
property reach = P=? [ F "done" ];
property steps = R{"steps"}=? [ F "done" ];
"""


def test_auto_with_hybrid_groups_the_queries_in_two_processes(tmp_path: object) -> None:
    import pathlib

    path = pathlib.Path(str(tmp_path)) / "wide.afsm"
    path.write_text(WIDE, encoding="utf-8")
    sparse = run(str(path), engine="sparse", isolate=False)
    said: list[str] = []
    tight = run(str(path), engine="auto", memory_budget=1, progress=said.append)
    roomy = run(str(path), engine="auto", memory_budget=1 << 40)
    # the expected rewards where "auto" counted the states; then the probabilities, reach_max
    # as 1 - Pmin (whether every path ends, and the rest), with larger tables
    assert tight.model.engine == "hybrid" and tight.model.processes == 2
    assert "queries grouped" in tight.model.engine_reason
    assert any("process 2 of 2: 3 queries (reach_min, termination, reach_max as 1 - Pmin) in "
               "one Storm process with 4096 MB" in s for s in said), said
    assert tight.uniform_model is not None and tight.uniform_model.processes == 2
    # each answer is reported as it comes, by what it is, not by afsmc's internal name
    assert any(s.startswith("checked reach_max as 1 - Pmin on the MDP") for s in said), said
    assert not any("__afsmc" in s for s in said), said
    assert roomy.model.engine == "sparse" and roomy.model.processes == 1
    _close(_values(tight), _values(sparse), 1e-6)
    _close(_values(roomy), _values(sparse), 1e-9)
    # each answer has its check time, the Pmax asked as 1 - Pmin included
    for res in (tight, roomy, sparse):
        assert all(set(p.seconds) == {"min", "max", "uniform"} for p in res.properties), res


def test_auto_with_hybrid_refuses_total_rewards_before_checking(tmp_path: Path) -> None:
    # When "auto" picks hybrid, an unbounded R [ C ] has no answer there: the process says so
    # as soon as it knows the engine, before any query is checked; the other queries are
    # then checked on the model it has built (no second build), and their values come with
    # the error (E404).
    from afsmc.diagnostics import CompileError

    path = tmp_path / "wide.afsm"
    path.write_text(WIDE + 'property total = R{"steps"}=? [ C ];\n', encoding="utf-8")
    said: list[str] = []
    with pytest.raises(CompileError) as info:
        run(str(path), properties=["steps", "total"], engine="auto", memory_budget=1,
            progress=said.append)
    # one error for total's min and max on the MDP, one on the uniform DTMC
    d, on_dtmc, answered = info.value.diagnostics
    assert d.code == "E404" and "too many for the sparse engine" in d.message, d.message
    assert d.message.replace("on the MDP", "on the uniform DTMC") == on_dtmc.message
    assert "cannot check this property" in d.message and d.span is not None
    assert d.hint is not None and "C<=k" in d.hint, d.hint
    first = next(i for i, s in enumerate(said) if s.startswith(
        "the hybrid engine cannot check total_min, total_max: E404 follows"))
    assert not any(s.startswith("checked") for s in said[:first]), said
    assert any(s.startswith("checked steps_max") for s in said[first:]), said
    # one build of each model: the refused queries cost no process of their own
    assert sum(s.startswith("built the MDP") for s in said) == 1, said
    assert sum(s.startswith("built the uniform DTMC") for s in said) == 1, said
    values, missing = answered.message.rsplit("\n", 1)
    assert answered.code == "N412" and "steps_min = " in values \
        and "steps_max = " in values and "total" not in values, answered
    assert missing == ("not answered: total_min on the MDP, total_max on the MDP, "
                       "total on the uniform DTMC"), missing
    # one query per process: the processes after the one where "auto" picked hybrid refuse
    # it before they build, and the answers so far are kept
    said.clear()
    with pytest.raises(CompileError) as info:
        run(str(path), properties=["steps", "total"], engine="auto", memory_budget=1,
            split=True, progress=said.append)
    e404, kept = info.value.diagnostics
    assert e404.code == "E404" and "cannot check 'total', an unbounded" in e404.message, \
        e404.message
    assert kept.code == "N412" and "steps_min = " in kept.message, kept.message
    assert sum(s.startswith("built the MDP") for s in said) == 2, said  # steps' min and max
    # with room for the sparse engine, "auto" checks it, as the sparse engine does
    roomy = run(str(path), properties=["total"], engine="auto", memory_budget=1 << 40)
    sparse = run(str(path), properties=["total"], engine="sparse", isolate=False)
    assert roomy.model.engine == "sparse"
    _close(_values(roomy), _values(sparse), 1e-12)


def test_auto_with_hybrid_checks_probabilities_only_in_one_process(tmp_path: object) -> None:
    # With no expected reward, the process where "auto" counted the states also asks the
    # complementary queries that give each Pmax: no second build.
    import pathlib

    path = pathlib.Path(str(tmp_path)) / "wide.afsm"
    path.write_text(WIDE, encoding="utf-8")
    sparse = run(str(path), properties=["reach"], engine="sparse", isolate=False)
    said: list[str] = []
    tight = run(str(path), properties=["reach"], engine="auto", memory_budget=1,
                progress=said.append)
    assert tight.model.engine == "hybrid" and tight.model.processes == 1, said
    assert tight.uniform_model is not None and tight.uniform_model.processes == 1
    assert any(s.startswith("checked reach_max as 1 - Pmin on the MDP") for s in said), said
    assert any("ends in a final mode" in s for s in said), said
    assert not any("one more Storm process" in s for s in said), said
    _close(_values(tight), _values(sparse), 1e-6)
    # with room for the sparse engine, the same job asks Pmax itself
    roomy = run(str(path), properties=["reach"], engine="auto", memory_budget=1 << 40)
    assert roomy.model.engine == "sparse" and roomy.model.processes == 1
    _close(_values(roomy), _values(sparse), 1e-9)


def test_auto_hybrid_process_stopped_keeps_its_answers(
        tmp_path: object, monkeypatch: pytest.MonkeyPatch) -> None:
    # The memory guard stops the process where "auto" picked hybrid after its first answer
    # (stand in for its verdict with Storm's real answers): the answer is kept, and the
    # rest (termination, the complement) run one per process.
    import pathlib

    from afsmc.verify import runner
    from afsmc.verify.guard import run_job as real
    from afsmc.verify.storm import JobResult, StormFailure

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


def test_hybrid_pmax_through_the_complementary_pmin_is_exact() -> None:
    said: list[str] = []
    names = ["success", "emergency", "drops"]
    hybrid = run(UAV, consts=SMALL["uav"], properties=names, engine="hybrid", isolate=False,
                 progress=said.append)
    sparse = run(UAV, consts=SMALL["uav"], properties=names, engine="sparse", isolate=False)
    assert any("1 - Pmin [F (final & !target)]" in s for s in said), said
    _close(_values(hybrid), _values(sparse), 1e-6)
    assert [p.name for p in hybrid.properties] == names


# A machine that may run forever (the Spin loop): Pmax cannot be had from the complement.
FOREVER = """machine forever;
const int STEP = [1, 2];
var x : [0..6] init 0 clamp;
mode Run = 0 initial;
mode End = 1 final;
action Go in Run when x < 6 { 0.3: goto End; 0.7: x += STEP; }
action Spin in Run when x >= 6 { x := 6; }
label done = mode == End;
property reach = P=? [ F "done" ];
"""


def test_hybrid_pmax_falls_back_when_paths_need_not_end(tmp_path: object) -> None:
    import pathlib

    path = pathlib.Path(str(tmp_path)) / "forever.afsm"
    path.write_text(FOREVER, encoding="utf-8")
    said: list[str] = []
    hybrid = run(str(path), engine="hybrid", isolate=False, progress=said.append)
    sparse = run(str(path), engine="sparse", isolate=False)
    assert not any("ends in a final mode" in s for s in said), said
    assert any("(reach_max) in its own Storm process" in s for s in said), said
    _close(_values(hybrid), _values(sparse), 1e-6)
    reach = hybrid.property("reach")
    assert reach.min is not None and reach.max is not None and reach.min < reach.max < 1


def test_too_small_decision_diagram_tables_are_retried_with_storm_s_default() -> None:
    # Sylvan ends the process when its tables are full; the guard runs the job again.
    from afsmc.verify.guard import run_isolated
    from afsmc.verify.storm import DD_MEMORY_RETRY

    out, names = _small_uav(lambda p: p.name == "success")
    said: list[str] = []
    tight = run_isolated(Job("prism", out.model, out.properties, names, "hybrid",
                             dd_memory_mb=1), said.append)
    sparse = execute(Job("prism", out.model, out.properties, names, "sparse"))
    assert tight.failure is None and sparse.failure is None
    assert any(f"retrying with {DD_MEMORY_RETRY} MB" in s for s in said), said
    assert tight.states == sparse.states
    for name in names:
        assert tight.values[name] == pytest.approx(sparse.values[name], abs=1e-6)


def test_complementary_queries_keep_the_larger_tables_once_one_needed_them(
        monkeypatch: pytest.MonkeyPatch) -> None:
    # Every first attempt gets 1 MB tables, too small for any query of the small UAV.
    from afsmc.verify import runner
    from afsmc.verify.storm import DD_MEMORY_RETRY

    make_job = runner.make_job
    monkeypatch.setattr(runner, "make_job", lambda *a, **k: dataclasses.replace(
        make_job(*a, **k), dd_memory_mb=1))
    said: list[str] = []
    names = ["success", "missed"]
    hybrid = run(UAV, consts=SMALL["uav"], properties=names, engine="hybrid", split=True,
                 uniform=False, progress=said.append)
    sparse = run(UAV, consts=SMALL["uav"], properties=names, engine="sparse", isolate=False,
                 uniform=False)
    _close(_values(hybrid), _values(sparse), 1e-6)
    starts = [i for i, s in enumerate(said) if ", query " in s]
    retried = [any("retrying with" in s for s in said[i:j])
               for i, j in zip(starts, [*starts[1:], len(said)], strict=True)]
    queries = [said[i].split("(", 1)[1] for i in starts]
    assert [q.split(")")[0] for q in queries] == [
        "success_min", "termination", "success_max as 1 - Pmin", "missed_min",
        "missed_max as 1 - Pmin"], queries
    # the second complementary query starts with the tables the first one ended with
    assert retried == [True, True, True, True, False], said
    assert any(f"start with {DD_MEMORY_RETRY} MB" in s for s in said), said


def test_in_process_checks_carry_no_tables_over_without_a_rerun() -> None:
    # In process (a Dask worker) a big model starts with full tables: nothing was rerun.
    said: list[str] = []
    run(UAV, consts=SMALL["uav"], properties=["success"], engine="hybrid", isolate=False,
        split=True, uniform=False, progress=said.append)
    assert any("1 - Pmin [F (final & !target)]" in s for s in said), said
    assert not any("further complementary" in s or "retrying" in s for s in said), said


@pytest.mark.parametrize("answered", [1, 0])
def test_full_tables_in_a_grouped_process_replan_the_queries_it_had_not_answered(
        monkeypatch: pytest.MonkeyPatch, answered: int) -> None:
    # The guard's verdict when Sylvan ends a process of several queries while checking
    # (seen on scenario 1 after one answer): stand in for it with Storm's real answers.
    from afsmc.verify import runner
    from afsmc.verify.storm import JobResult, StormFailure

    names = ["success", "drops"]
    sparse = run(UAV, consts=SMALL["uav"], properties=names, engine="sparse", isolate=False,
                 uniform=False)
    from afsmc.verify.guard import run_job as real
    calls: list[tuple[str, ...]] = []

    def run_job(job: Job, bound: int, *, isolate: bool | None,
                progress: Callable[[str], None] | None) -> JobResult:
        calls.append(job.names)
        if len(calls) > 1:
            return real(job, bound, isolate=isolate, progress=progress)
        res = real(dataclasses.replace(job, names=job.names[:answered]), bound,
                   isolate=isolate, progress=progress) if answered else JobResult(states=1)
        res.failure = StormFailure("tables", "the decision-diagram tables (1024 MB) of the "
                                   f"MDP were full after {answered} of its 2 queries")
        return res

    monkeypatch.setattr(runner, "run_job", run_job)
    said: list[str] = []
    hybrid = run(UAV, consts=SMALL["uav"], properties=names, engine="hybrid", uniform=False,
                 progress=said.append)
    _close(_values(hybrid), _values(sparse), 1e-6)
    rewards = ("drops_min", "drops_max")
    probabilities = ("success_min", "__afsmc_terminates", "__afsmc_rest_success")
    if answered:
        # the one it had not answered goes on in a fresh process
        assert calls == [rewards, ("drops_max",), probabilities], calls
        assert any("the others follow in a fresh process" in s for s in said), said
    else:
        # full at its first query: that one alone, then the others
        assert calls == [rewards, ("drops_min",), ("drops_max",), probabilities], calls
        assert any("drops_min follows alone" in s for s in said), said


def _stop_after_first_answer(monkeypatch: pytest.MonkeyPatch, stop: Callable[
        [dict[str, float]], BaseException | None]) -> None:
    """Run the first Storm job for real, then fail it (or raise) with its first answer only:
    what a memory stop or a Ctrl-C leaves, with Storm's real value."""
    from afsmc.verify import runner
    from afsmc.verify.guard import run_job as real
    from afsmc.verify.storm import JobResult, StormFailure

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


def test_ctrl_c_prints_the_values_verify_had(monkeypatch: pytest.MonkeyPatch,
                                             capsys: pytest.CaptureFixture[str]) -> None:
    from afsmc.cli import main
    from afsmc.verify.guard import Interrupted

    sparse = run(UAV, consts=SMALL["uav"], properties=["success"], engine="sparse",
                 isolate=False, uniform=False)
    _stop_after_first_answer(monkeypatch, lambda v: Interrupted(dict(v)))
    code = main(["verify", UAV, "-p", "success", "--no-uniform", "--engine", "sparse",
                 *[f"--const={k}={v}" for k, v in SMALL["uav"].items()]])
    err = capsys.readouterr().err
    assert code == 130
    assert "afsmc: interrupted" in err
    assert f"success_min = {sparse.property('success').min!r} on the MDP" in err, err


def test_ctrl_c_with_json_still_prints_one_json_object(monkeypatch: pytest.MonkeyPatch,
                                                       capsys: pytest.CaptureFixture[str]) -> None:
    from afsmc.cli import main
    from afsmc.verify.guard import Interrupted

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


def test_kept_values_give_each_pmax_from_its_complement() -> None:
    from afsmc.verify.queries import TERMINATES, complements, kept_note

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


def test_a_users_address_space_limit_is_kept_not_raised(tmp_path: Path) -> None:
    # Under `ulimit -v` the watched Storm process may only lower the limit: raising it
    # was a ValueError in the child, reported as a crash ("killed by signal 9").
    import resource
    import subprocess
    import sys

    model = tmp_path / "grid.afsm"
    model.write_text("machine grid;\nparam int N = 700;\nvar a : [0..N] init 0;\n"
                     "var c : [0..N] init 0;\nmode A = 0 initial;\nmode B = 1 final;\n"
                     "action Inc in A when a < N { 0.5: a := a + 1; 0.5: c := min(c + 1, N); }\n"
                     "action Stop in A when a >= N { goto B; }\n"
                     "property p = P=? [ F mode == B ];\n", encoding="utf-8")
    limit = 12 * 2**30

    def cap() -> None:
        resource.setrlimit(resource.RLIMIT_AS, (limit, limit))

    r = subprocess.run([sys.executable, "-m", "afsmc", "verify", str(model), "--json"],
                       capture_output=True, text=True, preexec_fn=cap, timeout=300)
    assert r.returncode == 0, r.stderr
    assert "Traceback" not in r.stderr and "signal" not in r.stderr, r.stderr
    res = json.loads(r.stdout)
    assert res["model"]["states"] > IN_PROCESS_STATES  # so it ran in the watched process
    assert res["properties"][0]["value"] == pytest.approx(1.0)


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
        if "building the MDP" in line:
            break
    return proc


@pytest.mark.parametrize("how", ["ctrl-c", "sigterm"])
def test_ctrl_c_and_sigterm_stop_the_watched_storm_process(tmp_path: Path, how: str) -> None:
    # Ctrl-C: SIGINT to the whole process group, as a terminal sends it, exit 130.
    # `kill PID` (a CI timeout, a batch system): SIGTERM to afsmc alone, exit 128 + 15 as a
    # shell reports it. Either while the guard's child builds: one JSON object, no
    # traceback and no Storm process left behind.
    import os
    import signal

    proc = _verify_building(tmp_path)
    if how == "ctrl-c":
        os.killpg(proc.pid, signal.SIGINT)
    else:
        os.kill(proc.pid, signal.SIGTERM)
    out, err = proc.communicate(timeout=60)
    assert proc.returncode == (130 if how == "ctrl-c" else 143), err
    assert json.loads(out)["interrupted"] is True
    said = "afsmc: interrupted" if how == "ctrl-c" else "afsmc: terminated"
    assert "Traceback" not in err and said in err
    _group_ends(proc.pid)


def test_a_killed_afsmc_leaves_no_storm_process_behind(tmp_path: Path) -> None:
    # SIGKILL to afsmc alone (no handler runs): its Storm child must not go on for an hour.
    import os
    import signal

    proc = _verify_building(tmp_path)
    os.kill(proc.pid, signal.SIGKILL)
    proc.communicate(timeout=60)
    assert proc.returncode == -signal.SIGKILL
    _group_ends(proc.pid)


def test_progress_lines_thin_out_as_a_phase_goes_on() -> None:
    # An hour's check would otherwise log a line every 5 s (700 lines).
    from afsmc.verify.guard import report_interval

    assert [report_interval(s, 5.0) for s in (0, 59, 60, 599, 600, 3600)] == \
        [5.0, 5.0, 30.0, 30.0, 60.0, 60.0]
    lines = 0
    t = 0.0
    while t < 3600:  # one line per interval, as the guard reports them
        t += report_interval(t, 5.0)
        lines += 1
    assert 75 <= lines <= 85, lines
    assert report_interval(100, 45.0) == 45.0  # never more often than asked


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
    # the same when the query that fails is the last one (review 17: its process was the
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


def test_a_memory_stop_names_the_query_and_the_others_go_on(
        monkeypatch: pytest.MonkeyPatch) -> None:
    """The guard names the query it stopped (its "check" phase); the run goes on with the
    process's other queries in a fresh one, and the error says which query it was."""
    from afsmc.diagnostics import CompileError
    from afsmc.verify import runner
    from afsmc.verify.guard import _checking
    from afsmc.verify.guard import run_job as real
    from afsmc.verify.storm import JobResult, StormFailure

    assert _checking("check success_min") == "success_min" and _checking("build") is None
    calls: list[tuple[str, ...]] = []

    def run_job(job: Job, bound: int, *, isolate: bool | None,
                progress: Callable[[str], None] | None) -> JobResult:
        calls.append(job.names)
        res = real(job, bound, isolate=isolate, progress=progress)
        if len(calls) == 1:  # stopped while checking the second query, as the guard would
            first, second = job.names[:2]
            res.values = {first: res.values[first]}
            res.failure = StormFailure("memory", "stopped the MDP after 1 s: it used 9.9 GB, "
                                       "85% of the memory that was available", prop=second)
        return res

    names = ["success", "drops"]
    sparse = run(UAV, consts=SMALL["uav"], properties=names, engine="sparse", isolate=False,
                 uniform=False)
    monkeypatch.setattr(runner, "run_job", run_job)
    with pytest.raises(CompileError) as info:
        run(UAV, consts=SMALL["uav"], properties=names, engine="sparse", uniform=False)
    e406, note = info.value.diagnostics
    assert e406.code == "E406" and e406.message.endswith("while checking success_max"), e406
    assert calls == [("success_min", "success_max", "drops_min", "drops_max"),
                     ("drops_min", "drops_max")], calls
    assert note.message == (
        "the other queries were answered:\n"
        f"  success_min = {sparse.property('success').min!r} on the MDP\n"
        f"  drops_min = {sparse.property('drops').min!r} on the MDP\n"
        f"  drops_max = {sparse.property('drops').max!r} on the MDP\n"
        "not answered: success_max on the MDP"), note.message


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


def test_a_failed_complement_does_not_matter_where_not_every_path_ends(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """Mode C traps some paths outside the final modes, so each Pmax is asked itself, not as
    1 - Pmin of its complement. A complement that failed (here, faked to run out of memory)
    is then no error: every value is answered, equal to the sparse engine's, and no error
    is raised."""
    from afsmc.verify import runner
    from afsmc.verify.guard import run_job as real
    from afsmc.verify.storm import JobResult, StormFailure

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
    from afsmc.verify.sweep_tasks import Task, user_words

    made = [Diagnostic("E406", Severity.ERROR, f"stopped while checking reach__at{i}_max as "
                       "1 - Pmin", None) for i in range(3)]
    made.append(Diagnostic("N412", Severity.NOTE, "answered:\n  reach__at1_min = 0.5", None))
    task = Task("m.afsm", "", (), (), (), "K", "const", (3, 5), "prism", "hybrid", None, True,
                None)
    d, note = user_words(made, task)
    assert d.message == "stopped while checking reach_max as 1 - Pmin", d.message
    assert note.message == "answered:\n  reach_min at K=5 = 0.5", note.message
