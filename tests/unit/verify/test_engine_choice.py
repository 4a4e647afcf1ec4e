"""Verification at scale: the automatic engine choice (sparse or hybrid, one process or
several), decision-diagram tables, bisimulation and the reductions give the same values as
the plain sparse route."""

from __future__ import annotations

import dataclasses
import json
import re
from collections.abc import Callable
from pathlib import Path

import pytest

from afsmc.backends.prism import PrismOutput, emit, property_variants
from afsmc.compiler import load, lowered
from afsmc.lower.reduce import Reductions
from afsmc.model import ir
from afsmc.verify import run
from afsmc.verify.engines.storm import Job, execute
from tests.conftest import EXAMPLES, run_cli
from tests.unit.backends.test_prism import SMALL

pytestmark = pytest.mark.storm

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


@pytest.mark.slow
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
    assert "few enough for the sparse engine" in res.model.engine_reason, res.model.engine_reason


def _small_uav(keep: Callable[[ir.Property], bool]) -> tuple[PrismOutput, tuple[str, ...]]:
    """The small UAV's PRISM text and the query names of the properties `keep` selects."""
    model = load(UAV, SMALL["uav"]).model
    low = lowered(model, "nondet")
    names = tuple(n for p in model.properties if keep(p) for n, _ in property_variants(low, p))
    return emit(low), names


@pytest.mark.slow
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


@pytest.mark.slow
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


@pytest.mark.slow
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


@pytest.mark.slow
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
    # with room, afsmc's own exploration answers first (afsmc.verify.engines.explicit); with none,
    # it gives up within the budget and the hybrid path above runs
    assert roomy.model.engine == "explicit" and roomy.model.processes == 1
    _close(_values(tight), _values(sparse), 1e-6)
    _close(_values(roomy), _values(sparse), 1e-9)
    # each answer has its check time, the Pmax asked as 1 - Pmin included
    for res in (tight, roomy, sparse):
        assert all(set(p.seconds) == {"min", "max", "uniform"} for p in res.properties), res


@pytest.mark.slow
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


@pytest.mark.slow
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
    # with room, afsmc's own exploration answers first (afsmc.verify.engines.explicit); with none,
    # it gives up within the budget and the hybrid path above runs
    assert roomy.model.engine == "explicit" and roomy.model.processes == 1
    _close(_values(roomy), _values(sparse), 1e-9)


@pytest.mark.slow
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


@pytest.mark.slow
def test_too_small_decision_diagram_tables_are_retried_with_storm_s_default() -> None:
    # Sylvan ends the process when its tables are full; the guard runs the job again.
    from afsmc.verify.engines.guard import run_isolated
    from afsmc.verify.engines.storm import DD_MEMORY_RETRY

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


@pytest.mark.slow
def test_complementary_queries_keep_the_larger_tables_once_one_needed_them(
        monkeypatch: pytest.MonkeyPatch) -> None:
    # Every first attempt gets 1 MB tables, too small for any query of the small UAV.
    from afsmc.verify.core import model_loop as runner
    from afsmc.verify.engines.storm import DD_MEMORY_RETRY

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


@pytest.mark.slow
def test_in_process_checks_carry_no_tables_over_without_a_rerun() -> None:
    # In process (a Dask worker) a big model starts with full tables: nothing was rerun.
    said: list[str] = []
    run(UAV, consts=SMALL["uav"], properties=["success"], engine="hybrid", isolate=False,
        split=True, uniform=False, progress=said.append)
    assert any("1 - Pmin [F (final & !target)]" in s for s in said), said
    assert not any("further complementary" in s or "retrying" in s for s in said), said


@pytest.mark.slow
@pytest.mark.parametrize("answered", [1, 0])
def test_full_tables_in_a_grouped_process_replan_the_queries_it_had_not_answered(
        monkeypatch: pytest.MonkeyPatch, answered: int) -> None:
    # The guard's verdict when Sylvan ends a process of several queries while checking
    # (seen on scenario 1 after one answer): stand in for it with Storm's real answers.
    from afsmc.verify.core import model_loop as runner
    from afsmc.verify.engines.storm import JobResult, StormFailure

    names = ["success", "drops"]
    sparse = run(UAV, consts=SMALL["uav"], properties=names, engine="sparse", isolate=False,
                 uniform=False)
    from afsmc.verify.engines.guard import run_job as real
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
