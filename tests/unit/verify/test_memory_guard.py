"""The memory guard around Storm: a user's address-space limit is kept, a memory stop names
the query it stopped, and progress lines thin out over a long phase."""

from __future__ import annotations

import json
from collections.abc import Callable
from pathlib import Path

import pytest

from afsmc.verify import run
from afsmc.verify.engines.guard import IN_PROCESS_STATES
from afsmc.verify.engines.storm import Job
from tests.unit.backends.test_prism import SMALL
from tests.unit.verify.test_engine_choice import UAV


@pytest.mark.slow
@pytest.mark.storm
def test_a_users_address_space_limit_is_kept_not_raised(tmp_path: Path) -> None:
    # Under `ulimit -v` the watched Storm process may only lower the limit: raising it
    # was a ValueError in the child, reported as a crash ("killed by signal 9").
    import resource
    import subprocess
    import sys

    # N = 450: 203,401 states, just past IN_PROCESS_STATES, so it runs in the watched process
    model = tmp_path / "grid.afsm"
    model.write_text("machine grid;\nparam int N = 450;\nvar a : [0..N] init 0;\n"
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


def test_progress_lines_thin_out_as_a_phase_goes_on() -> None:
    # An hour's check would otherwise log a line every 5 s (700 lines).
    from afsmc.verify.engines.guard import report_interval

    assert [report_interval(s, 5.0) for s in (0, 59, 60, 599, 600, 3600)] == \
        [5.0, 5.0, 30.0, 30.0, 60.0, 60.0]
    lines = 0
    t = 0.0
    while t < 3600:  # one line per interval, as the guard reports them
        t += report_interval(t, 5.0)
        lines += 1
    assert 75 <= lines <= 85, lines
    assert report_interval(100, 45.0) == 45.0  # never more often than asked


@pytest.mark.slow
@pytest.mark.storm
def test_a_memory_stop_names_the_query_and_the_others_go_on(
        monkeypatch: pytest.MonkeyPatch) -> None:
    """The guard names the query it stopped (its "check" phase); the run goes on with the
    process's other queries in a fresh one, and the error says which query it was."""
    from afsmc.diagnostics import CompileError
    from afsmc.verify.core import model_loop as runner
    from afsmc.verify.engines.guard import _checking
    from afsmc.verify.engines.guard import run_job as real
    from afsmc.verify.engines.storm import JobResult, StormFailure

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
