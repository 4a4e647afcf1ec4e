"""`afsmc sweep` and `afsmc.verify.reports.sweep`: deadline curves (Figure 2 of the paper), CSV and
plots, closed forms, and local processes / Dask giving the same numbers as one process."""

from __future__ import annotations

import csv
import io
import itertools
import json
import re
from pathlib import Path

import pytest

from afsmc.commands.sweep import split_consts
from afsmc.diagnostics import CompileError
from afsmc.verify import parse_values, sweep
from tests.conftest import EXAMPLES, run_cli
from tests.specs import BOOL_PARAM
from tests.unit.verify.test_verify import DEADLINE, GEO, RECORD

TOL = 1e-6  # Storm's value iteration stops at a relative precision of 1e-6


@pytest.fixture
def deadline(tmp_path: Path) -> str:
    p = tmp_path / "deadline.afsm"
    p.write_text(DEADLINE)
    return str(p)


def rows(text: str) -> list[dict[str, str]]:
    return list(csv.DictReader(io.StringIO(text)))


def assert_deadline_curves(lo: list[float], hi: list[float], uni: list[float]) -> None:
    for curve in (lo, hi, uni):
        assert all(b >= a - TOL for a, b in itertools.pairwise(curve)), curve
    for a, b, c in zip(lo, uni, hi, strict=True):
        assert a - TOL <= b <= c + TOL


def test_parse_values() -> None:
    assert parse_values("0:900:300") == [0, 300, 600, 900]
    assert parse_values("0:10:4") == [0, 4, 8]  # stop is included only when reached
    assert parse_values("0:1:0.25") == [0, 0.25, 0.5, 0.75, 1]
    assert parse_values("3") == [3]
    assert parse_values("1, 2,5") == [1, 2, 5]
    assert parse_values("30,10,20") == [10, 20, 30]  # the curves join neighbours
    for bad in ("0:10:0", "5:1", "a:b", "1,x", "", "0:1000000", "3,3", "1,2.0,2"):
        with pytest.raises(ValueError):
            parse_values(bad)


@pytest.mark.storm
def test_deadline_sweep_writes_csv_and_png(deadline: str, tmp_path: Path) -> None:
    out, png = tmp_path / "out.csv", tmp_path / "fig.png"
    r = run_cli("sweep", deadline, "--const", "D=0:14", "-p", "by_deadline", "-o", str(out),
                "--plot", str(png), "--jobs", "1")
    assert r.code == 0, r.err
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    data = rows(out.read_text())
    assert [int(d["D"]) for d in data] == list(range(15))
    lo, hi, uni = ([float(d[k]) for d in data] for k in ("min", "max", "uniform"))
    assert_deadline_curves(lo, hi, uni)
    assert lo[0] == hi[0] == 0.0 and hi[-1] > 0.9  # from nothing to almost surely
    assert any(b < c - 0.01 for b, c in zip(uni, hi, strict=True))  # the bounds differ
    # Without failures the hand computation of test_verify holds at D=4, 5.
    r = run_cli("sweep", deadline, "--const", "D=4,5", "-c", "P_FAIL=0", "-p", "by_deadline",
                "--jobs", "1")
    assert r.code == 0, r.err
    got = [(float(d["min"]), float(d["max"]), float(d["uniform"])) for d in rows(r.out)]
    assert got == [pytest.approx((0, 1, 0.25)), pytest.approx((0, 1, 0.75))]


@pytest.mark.slow
@pytest.mark.storm
def test_parallel_local_and_dask_equal_one_process(deadline: str) -> None:
    distributed = pytest.importorskip("distributed")
    args = dict(properties=["by_deadline", "steps"], consts={"P_FAIL": "0.1"})
    one = sweep(deadline, "D", [3, 5, 7, 9], jobs=1, **args)  # type: ignore[arg-type]
    two = sweep(deadline, "D", [3, 5, 7, 9], jobs=2, **args)  # type: ignore[arg-type]
    assert two.to_csv() == one.to_csv()
    with distributed.LocalCluster(n_workers=1, threads_per_worker=1, processes=False,
                                  dashboard_address=None) as cluster:
        remote = sweep(deadline, "D", [3, 5, 7, 9], dask=cluster.scheduler_address,
                       **args)  # type: ignore[arg-type]
    assert remote.to_csv() == one.to_csv()
    assert remote.to_json() == one.to_json()


@pytest.mark.storm
def test_constant_in_the_model_rebuilds_per_point(deadline: str) -> None:
    # Each job takes a geometric number of attempts: E[steps] = 2 / (1 - P_FAIL).
    res = sweep(deadline, "P_FAIL", parse_values("0:0.5:0.25"), properties=["steps"], jobs=1)
    for pt in res.points:
        r = pt.property("steps")
        want = 2 / (1 - pt.x)
        assert r.min == pytest.approx(want, rel=1e-5)
        assert r.max == pytest.approx(want, rel=1e-5)
        assert r.uniform == pytest.approx(want, rel=1e-5)


NOT_MONOTONE = """machine nm;
param int K = 1;
var x : [0..K * (2 - K) + 1] init 0 clamp;
mode Run = 0 initial;
mode End = 1 final;
action Inc in Run when x < 5 weight 1 { 0.5: x += 1; 0.5: goto End; }
label top = x == 2;
property top = P=? [ F "top" ];
"""


@pytest.mark.storm
def test_a_model_equal_at_the_ends_but_not_between_is_built_per_point(tmp_path: Path) -> None:
    """The model reads K, but is the same at both ends of the sweep (x's range is 0..1 at
    K = 0 and K = 2, 0..2 at K = 1): every point still equals verify at that K
    (P [F x = 2] = 0.25 at K = 1, 0 otherwise), not the first point's model."""
    path = tmp_path / "nm.afsm"
    path.write_text(NOT_MONOTONE)
    res = sweep(str(path), "K", parse_values("0:2"), properties=["top"], jobs=1)
    for pt in res.points:
        got = pt.property("top").value
        r = run_cli("verify", str(path), "--const", f"K={int(pt.x)}", "--json", "-p", "top")
        want = json.loads(r.out)["properties"][0]["value"]
        assert got == pytest.approx(want, abs=1e-12), pt.x
        assert got == pytest.approx(0.25 if pt.x == 1 else 0.0, abs=1e-12), pt.x


@pytest.mark.slow
@pytest.mark.storm
def test_bound_sweep_matches_closed_form(tmp_path: Path) -> None:
    p = tmp_path / "geo.afsm"
    p.write_text(GEO)
    r = run_cli("sweep", str(p), "--bound", "0:8:2", "-p", "soon", "--json", "--jobs", "2")
    assert r.code == 0, r.err
    obj = json.loads(r.out)
    assert obj["kind"] == "bound" and obj["type"] == "dtmc"
    for pt in obj["points"]:
        (prop,) = pt["properties"]
        assert prop["value"] == pytest.approx(1 - 0.7 ** pt["x"], abs=1e-9)
        assert prop["formula"] == f'P=? [ F<={pt["x"]} "done" ]'


@pytest.mark.storm
def test_bound_sweep_formulas_are_written_as_in_the_file(tmp_path: Path) -> None:
    """Each point shows the property as written with its bound put in, and it re-parses."""
    from afsmc.syntax.parser import parse_property

    p = tmp_path / "rec.afsm"
    p.write_text(RECORD)
    r = run_cli("sweep", str(p), "--bound", "0:2", "-p", "g", "-p", "u", "--json", "--jobs", "1")
    assert r.code == 0, r.err
    for pt in json.loads(r.out)["points"]:
        g, u = pt["properties"]
        assert g["formula"] == f"P=? [ G<={pt['x']} !(mode in {{Run, Walk}}) ]"
        assert u["formula"] == f"P=? [ mode == Start U<={pt['x']} ret.px == 1 ]"
        parse_property(g["formula"])
        parse_property(u["formula"])


@pytest.mark.storm
def test_usage_errors(deadline: str) -> None:
    # (two constants with ranges sweep their grid: tests/e2e/test_sweep_grid.py)
    assert run_cli("sweep", deadline, "--const", "D=1:3", "--const", "D=4:5").code == 2
    assert run_cli("sweep", deadline).code == 2
    assert run_cli("sweep", deadline, "--const", "D=5:1").code == 2
    assert run_cli("sweep", deadline, "--const", "D=1:3", "--plot", "x.gif").code == 2
    r = run_cli("sweep", deadline, "--const", "D=1:3", "--bound", "1:3")
    assert r.code == 2


@pytest.fixture
def no_points(monkeypatch: pytest.MonkeyPatch) -> None:
    """Fail the test if the sweep computes any point."""
    import importlib

    sweep_mod = importlib.import_module("afsmc.verify.reports.sweep")  # afsmc.verify.reports.sweep is a function

    def boom(*_a: object, **_k: object) -> None:
        raise AssertionError("a point was computed before the error was reported")

    monkeypatch.setattr(sweep_mod, "_run", boom)


@pytest.mark.storm
def test_bound_sweep_rejects_properties_without_a_step_bound(tmp_path: Path,
                                                             no_points: None) -> None:
    """An unbounded F or G is not given the bound silently (P[F "done"] coming out as
    P[F<=k "done"], exit 0), and R[F] is refused once, before any point is checked."""
    p = tmp_path / "geo.afsm"
    p.write_text(GEO + 'property pd = P=? [ F "done" ];\nproperty pg = P=? [ G !"done" ];\n')
    r = run_cli("sweep", str(p), "--bound", "0:10:5", "-p", "soon", "-p", "pd", "-p", "pg",
                "-p", "tries", "--formula", 'R{"tries"}=? [ C ]', "--jobs", "2")
    assert r.code == 1, r.err
    errors = re.findall(r"^(\S+): error\[E410\]: property '(\w+)' has no step bound to sweep",
                        r.err, re.M)
    where = {name: at for at, name in errors}
    assert list(where) == ["pd", "pg", "tries", "adhoc"]  # each once, in order
    assert where["pd"] == f"{p}:14:1" and where["adhoc"] == "--formula:1:1"
    assert "at bounds" not in r.err and "Traceback" not in r.err
    assert "soon" not in r.err  # F<=5 has a bound to sweep


@pytest.mark.storm
def test_bound_sweep_rejects_a_bad_bound_once(tmp_path: Path, no_points: None) -> None:
    p = tmp_path / "geo.afsm"
    p.write_text(GEO)
    r = run_cli("sweep", str(p), "--bound", "0:2:0.5", "-p", "soon", "--jobs", "2")
    assert r.code == 1
    assert r.err.count("error[E410]") == 1 and "--bound 0.5, 1.5: step bounds are integers" in r.err
    # beyond 64 bits: every point ran, then failed in Storm's parser (E402)
    r = run_cli("sweep", str(p), "--bound", f"{2**63}:{2**63 + 1}", "-p", "soon")
    assert r.code == 1 and r.err.count("error[E410]") == 1, r.err
    assert f"--bound {2**63}, {2**63 + 1}: step bounds are integers from 0 to 2^63 - 1" in r.err
    # a range that starts below 0 reaches afsmc's check: argparse took it for an option
    for value in ("-2:1", "-1,0"):
        r = run_cli("sweep", str(p), "--bound", value, "-p", "soon")
        assert r.code == 1 and r.err.count("error[E410]") == 1, r.err
        assert "--bound -" in r.err and "expected one argument" not in r.err, r.err


@pytest.mark.storm
def test_outputs_are_checked_before_any_point(deadline: str, tmp_path: Path,
                                              no_points: None) -> None:
    blocker = tmp_path / "file"
    blocker.write_text("")
    for opt, name in (("-o", "out.csv"), ("--plot", "out.png")):
        r = run_cli("sweep", deadline, "--const", "D=1:3", opt, str(blocker / name))
        assert r.code == 1, r.err
        assert f"error[E003]: cannot write {blocker / name}: {blocker} is not a directory" in r.err
        # the same as compile, diagram and simulate --traces-out: E002, exit 1 (was 2)
        src = tmp_path / f"model{Path(name).suffix}"  # an .afsm file named like a plot
        src.write_text(Path(deadline).read_text())
        r = run_cli("sweep", str(src), "--const", "D=1:3", opt, str(src))
        assert r.code == 1 and f"error[E002]: refusing to overwrite the input {src}" in r.err
        assert "Traceback" not in r.err


@pytest.mark.storm
def test_csv_and_plot_on_the_same_file_is_a_usage_error(deadline: str, tmp_path: Path,
                                                         no_points: None) -> None:
    same = tmp_path / "s.svg"
    r = run_cli("sweep", deadline, "--const", "D=1:3", "-o", str(same), "--plot",
                str(tmp_path / "." / "s.svg"))
    assert r.code == 2 and "-o and --plot name the same file" in r.err, r.err
    assert not same.exists()


@pytest.mark.storm
def test_failure_at_a_point_is_a_diagnostic(deadline: str) -> None:
    r = run_cli("sweep", deadline, "--const", "D=1:2", "-p", "nope", "--jobs", "1")
    assert r.code == 1 and "E407" in r.err and "Traceback" not in r.err


@pytest.mark.slow
@pytest.mark.storm
def test_uav_deadline_sweep(tmp_path: Path) -> None:
    """The paper's Figure 2 on a small UAV instance: one build, checked per deadline."""
    out, png = tmp_path / "uav.csv", tmp_path / "uav.png"
    r = run_cli("sweep", str(EXAMPLES / "uav.afsm"), "-c", "WIDTH=2,HEIGHT=2,T_LIMIT=100",
                "--const", "DEADLINE=40:100:15", "-p", "success_by", "-o", str(out),
                "--plot", str(png), "--jobs", "1")
    assert r.code == 0, r.err
    assert png.read_bytes()[:4] == b"\x89PNG"
    data = rows(out.read_text())
    assert [int(d["DEADLINE"]) for d in data] == [40, 55, 70, 85, 100]
    lo, hi, uni = ([float(d[k]) for d in data] for k in ("min", "max", "uniform"))
    assert_deadline_curves(lo, hi, uni)
    assert hi[-1] > lo[-1] + 0.05  # timing uncertainty matters at the limit


@pytest.mark.slow
@pytest.mark.storm
def test_uav_deadline_sweep_equals_verify_at_each_point() -> None:
    """The shared build of a deadline sweep gives exactly what `verify` gives per point
    (the model must not be saturated at the first deadline it was built with)."""
    from afsmc.verify import run, sweep

    uav = str(Path(__file__).resolve().parents[2] / "examples" / "uav.afsm")
    consts = {"WIDTH": "2", "HEIGHT": "2", "T_LIMIT": "60"}
    xs = [40, 70, 110]
    res = sweep(uav, "DEADLINE", xs, consts=consts, properties=["success_by"], jobs=1)
    for point in res.points:
        alone = run(uav, consts=consts | {"DEADLINE": str(point.x)}, properties=["success_by"],
                    isolate=False)
        one = alone.property("success_by")
        # The shared model is saturated above the sweep's largest deadline, no further.
        assert point.states >= alone.model.states
        if point.x == max(xs):
            assert point.states == alone.model.states
        got = point.properties[0]
        for key in ("min", "max", "uniform"):
            assert getattr(got, key) == pytest.approx(getattr(one, key), abs=1e-9), (point.x, key)


@pytest.mark.storm
def test_a_failed_point_keeps_the_others(deadline: str) -> None:
    # P_FAIL = 1.5 is no probability: that point fails, the two before it are reported.
    from afsmc.diagnostics import CompileError, Severity

    with pytest.raises(CompileError) as info:
        sweep(deadline, "P_FAIL", [0, 0.25, 1.5], properties=["steps"], jobs=1)
    diags = info.value.diagnostics
    assert diags[0].is_error and "at P_FAIL=1.5" in diags[0].message, diags
    note = diags[-1]
    assert note.code == "N412" and note.severity is Severity.NOTE
    head, *lines = note.message.split("\n")
    assert head == "2 points were evaluated before this:"
    got = rows("\n".join(lines) + "\n")
    assert [(r["P_FAIL"], r["property"]) for r in got] == [("0", "steps"), ("0.25", "steps")]
    for r in got:
        want = 2 / (1 - float(r["P_FAIL"]))
        assert float(r["min"]) == pytest.approx(want, rel=1e-5)


@pytest.mark.storm
def test_ctrl_c_prints_the_points_a_sweep_had(deadline: str, monkeypatch: pytest.MonkeyPatch,
                                               capsys: pytest.CaptureFixture[str]) -> None:
    # Stop the sweep as a Ctrl-C would, once its first point is done.
    import importlib

    from afsmc.cli import main

    sweep_module = importlib.import_module("afsmc.verify.reports.sweep")
    real = sweep_module.evaluate
    calls: list[int] = []

    def evaluate(task: object) -> object:
        calls.append(1)
        if len(calls) > 1:
            raise KeyboardInterrupt
        return real(task)  # type: ignore[arg-type]

    monkeypatch.setattr(sweep_module, "evaluate", evaluate)
    code = main(["sweep", deadline, "--const", "P_FAIL=0,0.25", "-p", "steps", "--jobs", "1"])
    err = capsys.readouterr().err
    assert code == 130 and "afsmc: interrupted" in err
    assert "1 point was evaluated before this:" in err, err
    assert "\n0,steps,2.0," in err, err
    # --json: one object, with the point as data
    calls.clear()
    code = main(["sweep", deadline, "--const", "P_FAIL=0,0.25", "-p", "steps", "--jobs", "1",
                 "--json"])
    obj = json.loads(capsys.readouterr().out)
    assert code == 130 and obj["interrupted"] is True, obj
    assert [(pt["x"], [p["min"] for p in pt["properties"]]) for pt in obj["points"]] == \
        [(0, [2.0])], obj["points"]


@pytest.mark.storm
@pytest.mark.parametrize("command", ["sweep", "simulate"])
def test_a_malformed_dask_address_is_a_usage_error(deadline: str, command: str) -> None:
    # Dask's own parser failed only when connecting, with a traceback.
    extra = ["--const", "D=1:2"] if command == "sweep" else []
    r = run_cli(command, deadline, *extra, "--dask", "notanaddress")
    assert r.code == 2 and "expected a Dask scheduler address" in r.err, r.err


@pytest.mark.storm
@pytest.mark.parametrize("engine", ["hybrid", "dd"])
def test_bisim_on_a_symbolic_engine_is_refused_not_ignored(deadline: str, engine: str) -> None:
    for argv in (["verify", deadline], ["sweep", deadline, "--const", "D=1:2"]):
        r = run_cli(*argv, "--bisim", "--engine", engine)
        assert r.code == 2 and "--bisim needs the sparse model" in r.err, r.err


SHARED = """machine pc;
param double DD = 0.5;
param int N = 2;
var x : [0..N] init 0;
mode S = 0 initial;
mode D = 1 final;
action Go in S { 0.3: x := min(x + 1, N); 0.7: goto D; }
action Stop in S when false weight DD { goto D; }
property p = P=? [ F x == N ];
"""


@pytest.mark.slow
@pytest.mark.storm
@pytest.mark.parametrize("sweep_args", [["--const", "DD=0.1:0.3:0.1"], ["--bound", "0:4:1"]])
def test_the_csv_does_not_depend_on_jobs(tmp_path: Path, sweep_args: list[str]) -> None:
    # Given a single property, Storm makes its targets absorbing: a chunk holding one
    # point built fewer states than one holding two (5 against 6 here), so the state
    # columns changed with --jobs.
    spec = tmp_path / "pc.afsm"
    spec.write_text(SHARED if sweep_args[0] == "--const" else SHARED.replace(
        "F x == N", "F<=3 x == N"))
    outs = []
    for jobs in ("1", "2", "3"):
        r = run_cli("sweep", str(spec), *sweep_args, "--jobs", jobs)
        assert r.code == 0, r.err
        outs.append(r.out)
    assert outs[0] == outs[1] == outs[2]
    assert {row["states"] for row in rows(outs[0])} == {"6"}


@pytest.mark.storm
def test_an_output_in_a_directory_that_takes_no_files_is_refused_before_any_point() -> None:
    # /proc passes os.access for root but takes no new file: the sweep computed every point
    # and then failed, losing them. The path is now tried before any work.
    import os

    if not os.path.isdir("/proc"):
        pytest.skip("needs Linux's /proc")
    for flag, name in (("-o", "x.csv"), ("--plot", "x.png")):
        r = run_cli("sweep", str(EXAMPLES / "patrol.afsm"), "--bound", "2:4", "-p",
                    "finish_soon", flag, f"/proc/{name}", "--progress")
        assert r.code == 1 and "error[E003]" in r.err and "cannot create files in /proc" \
            in r.err, r.err
        assert "N412" not in r.err and "point" not in r.err.lower().replace("e003", ""), r.err


@pytest.mark.slow
@pytest.mark.storm
def test_output_format_follows_the_name_and_dash_is_stdout(deadline: str, tmp_path: Path) -> None:
    """-o x.json writes the JSON of --json (not CSV under a .json name); -o - prints the
    CSV, as compile -o - does, even beside --plot, instead of a file named '-'."""
    as_json = tmp_path / "points.json"
    assert run_cli("sweep", deadline, "--const", "D=1:2", "-o", str(as_json)).code == 0
    data = json.loads(as_json.read_text())
    printed = run_cli("sweep", deadline, "--const", "D=1:2", "--json")
    assert data == json.loads(printed.out)
    plot = tmp_path / "p.png"
    r = run_cli("sweep", deadline, "--const", "D=1:2", "-o", "-", "--plot", str(plot))
    assert r.code == 0 and plot.exists()
    assert sorted({row["D"] for row in rows(r.out)}) == ["1", "2"]
    assert not Path("-").exists()
    assert run_cli("sweep", deadline, "--const", "D=1:2", "-o", "-", "--json").code == 2


@pytest.mark.storm
def test_an_unknown_property_is_reported_once_before_any_point(deadline: str,
                                                              no_points: None) -> None:
    r = run_cli("sweep", deadline, "--const", "D=1:30", "-p", "nope")
    assert r.code == 1 and r.err.count("error[E407]") == 1, r.err


@pytest.mark.slow
@pytest.mark.storm
def test_json_on_stdout_keeps_a_csv_file_csv(deadline: str, tmp_path: Path) -> None:
    """--json sets what goes to stdout; -o out.csv stays CSV beside it."""
    out = tmp_path / "points.csv"
    r = run_cli("sweep", deadline, "--const", "D=1:2", "--json", "-o", str(out))
    assert r.code == 0 and json.loads(r.out)["points"]
    assert rows(out.read_text())[0]["D"] == "1"


@pytest.mark.storm
def test_an_int_constant_swept_over_doubles_is_e208_once(deadline: str, no_points: None) -> None:
    """`D=1e0:3` is not swept as 1, 2, 3, since `verify --const D=1e0` is E208: a value
    is an int only as written so, and an int constant refuses the others before any point."""
    assert parse_values("1e0:2") == [1.0, 2.0] and isinstance(parse_values("1e0:2")[0], float)
    assert all(isinstance(x, int) for x in parse_values("1:3") + parse_values("4,2"))
    for spec, shown in (("D=1e0:3", "1.0, 2.0, 3.0 are not ints"), ("D=1,2.5", "2.5 is not an int")):
        r = run_cli("sweep", deadline, "--const", spec)
        assert r.code == 1 and r.err.count("error[E208]") == 1, r.err
        assert f"--const D: {shown}" in r.err and ":3:1:" in r.err, r.err
    r = run_cli("verify", deadline, "--const", "D=1e0")
    assert r.code == 1 and "error[E208]" in r.err


@pytest.mark.slow
@pytest.mark.storm
def test_a_double_constant_takes_every_number(deadline: str) -> None:
    r = run_cli("sweep", deadline, "--const", "P_FAIL=0:0.5:0.25", "-p", "steps")
    assert r.code == 0, r.err
    assert [row["P_FAIL"] for row in rows(r.out)] == ["0.0", "0.25", "0.5"]


@pytest.mark.storm
def test_a_worker_that_dies_is_a_diagnostic_with_the_points_it_had(
        deadline: str, monkeypatch: pytest.MonkeyPatch) -> None:
    """A killed worker (the OOM killer) surfaced as BrokenProcessPool: 'internal error',
    exit 3, and the finished points were lost."""
    import importlib
    from concurrent.futures.process import BrokenProcessPool

    sweep_mod = importlib.import_module("afsmc.verify.reports.sweep")
    real_run = sweep_mod._run

    def dies_after_the_first(tasks, jobs, dask, progress, total, results):  # type: ignore[no-untyped-def]
        real_run(tasks[:1], 1, None, None, total, results)  # the first chunk finishes
        raise BrokenProcessPool("a child process terminated abruptly")

    monkeypatch.setattr(sweep_mod, "_run", dies_after_the_first)
    with pytest.raises(CompileError) as info:
        sweep(deadline, "P_FAIL", [0.1, 0.2, 0.3], properties=["steps"], jobs=3)
    (died, kept) = info.value.diagnostics
    assert died.code == "E414" and "1 of 3 points were evaluated" in died.message
    assert kept.code == "N412" and "\n0.1,steps," in kept.message
    assert info.value.partial.xs == [0.1], info.value.partial  # written by the CLI


def _stop_after_first_task(monkeypatch: pytest.MonkeyPatch, stop: BaseException) -> None:
    """The first task finishes, then the sweep stops with `stop` (a Ctrl-C, a dead worker)."""
    import importlib

    sweep_mod = importlib.import_module("afsmc.verify.reports.sweep")
    real_run = sweep_mod._run

    def stops(tasks, jobs, dask, progress, total, results):  # type: ignore[no-untyped-def]
        real_run(tasks[:1], 1, None, None, total, results)
        raise stop

    monkeypatch.setattr(sweep_mod, "_run", stops)


@pytest.mark.slow
@pytest.mark.storm
@pytest.mark.parametrize("how", ["ctrl-c", "died"])
def test_a_stopped_sweep_keeps_a_point_answered_in_part(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str],
        how: str) -> None:
    """The first point answered reach and failed nxt; then a Ctrl-C, or a worker died. That
    point was dropped: neither its value nor its error was shown."""
    from concurrent.futures.process import BrokenProcessPool

    from afsmc.cli import main

    path = tmp_path / "sw.afsm"
    path.write_text(SW, encoding="utf-8")
    exact = sweep(str(path), "K", [1], properties=["reach"], jobs=1)
    _stop_after_first_task(monkeypatch, KeyboardInterrupt() if how == "ctrl-c" else
                           BrokenProcessPool("a child process terminated abruptly"))
    out = tmp_path / "out.json"
    code = main(["sweep", str(path), "--const", "K=1:3", "--via", "jani", "--engine", "hybrid",
                 "-j", "1", "--json", *(["-o", str(out)] if how == "died" else [])])
    captured = capsys.readouterr()
    obj = json.loads(captured.out)
    assert code == (130 if how == "ctrl-c" else 1), captured.err
    codes = [d["code"] for d in obj["diagnostics"]]
    assert codes == (["E404", "N412"] if how == "ctrl-c" else ["E414", "E404"]), codes
    assert obj["diagnostics"][codes.index("E404")]["message"].startswith("at K=1: "), obj
    if how == "died":
        assert "1 of 3 points were evaluated" in obj["diagnostics"][0]["message"]
        assert json.loads(out.read_text())["points"] == obj["points"]
    assert [(pt["x"], {p["name"]: p["value"] for p in pt["properties"]})
            for pt in obj["points"]] == \
        [(1, {"nxt": None, "reach": exact.curve("reach", "value")[0]})], obj["points"]


@pytest.mark.storm
def test_api_takes_python_numbers_as_run_does(deadline: str) -> None:
    """The twin of run(consts={"CELLS": 5}): sweep's fixed constants raised a TypeError."""
    as_text = sweep(deadline, "D", [3, 4], consts={"P_FAIL": "0.3"}, properties=["by_deadline"],
                    jobs=1)
    as_number = sweep(deadline, "D", [3, 4], consts={"P_FAIL": 0.3}, properties=["by_deadline"],
                      jobs=1)
    assert as_number.curve("by_deadline", "max") == as_text.curve("by_deadline", "max")
    assert None not in as_text.curve("by_deadline", "max")


@pytest.mark.storm
@pytest.mark.parametrize(("option", "value"), [("kind", "zzz"), ("via", "smv"),
                                               ("engine", "fast")])
def test_api_refuses_an_unknown_choice(deadline: str, option: str, value: str) -> None:
    """sweep(kind="zzz") ran a bound sweep, and a misspelt engine or via ran as sparse/PRISM
   ; the same check guards run()."""
    from afsmc.verify import run

    with pytest.raises(ValueError, match=f"{option} must be one of .*; got '{value}'"):
        sweep(deadline, "D", [3], properties=["by_deadline"], jobs=1,
              **{option: value})  # type: ignore[arg-type]
    if option != "kind":
        with pytest.raises(ValueError, match=f"{option} must be one of .*; got '{value}'"):
            run(deadline, **{option: value})  # type: ignore[arg-type]


@pytest.mark.slow
@pytest.mark.storm
def test_an_error_at_every_point_is_reported_once() -> None:
    """An error that does not depend on the swept value is reported once, saying where, not
    once per point (3 copies of E209 for FOO=1:3, 10 of E203 for CELLS=0:9)."""
    patrol = str(EXAMPLES / "patrol.afsm")
    r = run_cli("sweep", patrol, "--const", "FOO=1:3", "-p", "finish")
    assert r.code == 1 and r.err.count("error[E209]") == 1, r.err
    assert "at every value of FOO: --const FOO: no open constant named 'FOO'" in r.err
    r = run_cli("sweep", patrol, "--const", "CELLS=2:4", "-f", 'P=? [ F "nolabel" ]')
    assert r.code == 1 and r.err.count("error[E203]") == 1, r.err
    assert 'at every value of CELLS: label "nolabel" is not declared' in r.err
    # errors that differ from value to value stay one per value, each naming it
    r = run_cli("sweep", patrol, "--const", "CELLS=-2:2", "-p", "finish")
    assert r.code == 1 and "every value" not in r.err, r.err
    assert "at CELLS=-2: range [0..-2] of 'cell' is empty" in r.err
    assert "at CELLS=-1: range [0..-1] of 'cell' is empty" in r.err


SW = ("machine sw;\nparam int K = 3;\nvar x : [0..4] init 0 clamp;\n"
      "mode A = 0 initial;\nmode B = 1 final;\n"
      "action Go in A when x < K { 0.3: x += 1; 0.7: goto B; }\n"
      "action Stop in A when x >= K { goto B; }\n"
      "property nxt = P=? [ X x == 1 ];\n"
      "property reach = P=? [ F x == 2 ];\n")


@pytest.mark.slow
@pytest.mark.storm
def test_a_sweep_with_a_failed_query_still_writes_what_it_answered(tmp_path: Path) -> None:
    """No data lost: one query that Storm cannot check (X from JANI on the hybrid engine)
    fails at every point, yet -o, --json and stdout get every other value, the failed
    query's cells empty (null in JSON); the errors follow and the exit code is 1. Here the
    model reads K, so each point is a task of its own."""
    path = tmp_path / "sw.afsm"
    path.write_text(SW, encoding="utf-8")
    exact = sweep(str(path), "K", [1, 2, 3], properties=["reach"], jobs=1)  # sparse, alone
    assert exact.curve("reach", "value") == pytest.approx([0.0, 0.09, 0.09])
    args = ["sweep", str(path), "--const", "K=1:3", "--via", "jani", "--engine", "hybrid",
            "-j", "1"]
    out = tmp_path / "sw.csv"
    r = run_cli(*args, "-o", str(out))
    assert r.code == 1 and r.err.count("error[E404]") == 1, r.err
    assert "at every value of K: Storm failed to check 'nxt'" in r.err and "Traceback" not in r.err
    assert "points were evaluated" not in r.err, r.err  # they are in the file instead
    rows = list(csv.DictReader(io.StringIO(out.read_text())))
    assert [(row["K"], row["property"]) for row in rows] == [
        (k, n) for k in ("1", "2", "3") for n in ("nxt", "reach")]
    assert [row["value"] for row in rows if row["property"] == "nxt"] == ["", "", ""]
    assert [float(row["value"]) for row in rows if row["property"] == "reach"] == \
        exact.curve("reach", "value")
    # stdout (no -o): the same CSV there, the errors on stderr
    r = run_cli(*args)
    assert r.code == 1 and r.out == out.read_text() and "error[E404]" in r.err, r.err
    # --json: the points and the diagnostics in one object
    r = run_cli(*args, "--json")
    assert r.code == 1, r.err
    obj = json.loads(r.out)
    assert [d["code"] for d in obj["diagnostics"]] == ["E404"], obj["diagnostics"]
    values = {(pt["x"], p["name"]): p["value"] for pt in obj["points"] for p in pt["properties"]}
    assert values == {(k, "nxt"): None for k in (1, 2, 3)} | {
        (k, "reach"): v for k, v in zip((1, 2, 3), exact.curve("reach", "value"), strict=True)}


@pytest.mark.slow
@pytest.mark.storm
def test_an_output_it_replaces_keeps_its_permissions(tmp_path: Path) -> None:
    """-o over a file made private (chmod 640) left it 644: the temporary file
    renamed over it had the default mode. Every command writes through write_atomic."""
    out = tmp_path / "perm.csv"
    out.write_text("old\n")
    out.chmod(0o640)
    r = run_cli("sweep", str(EXAMPLES / "patrol.afsm"), "--bound", "0:2", "-p", "finish_soon",
                "-o", str(out))
    assert r.code == 0, r.err
    assert out.read_text().startswith("bound,") and out.stat().st_mode & 0o7777 == 0o640


@pytest.mark.slow
@pytest.mark.storm
def test_a_failed_query_of_a_shared_model_is_named_as_the_user_wrote_it(tmp_path: Path) -> None:
    """A sweep over a constant that only the properties read checks every point on one model,
    as properties NAME__atI. An error there is the user's property at the points it covers,
    once, not one per internal name; the note of the values answered names each point."""
    from afsmc.diagnostics import CompileError

    path = tmp_path / "sw.afsm"
    path.write_text("machine sw;\nparam int K = 3;\nvar x : [0..4] init 0 clamp;\n"
                    "mode A = 0 initial;\nmode B = 1 final;\n"
                    "action Go in A when x < 3 { 0.3: x += 1; 0.7: goto B; }\n"
                    "action Stop in A when x >= 3 { goto B; }\n"
                    "property nxt = P=? [ X x == 1 ];\n"
                    "property reach = P=? [ F<=K x == 2 ];\n", encoding="utf-8")
    with pytest.raises(CompileError) as info:
        sweep(str(path), "K", [1, 2, 3], via="jani", engine="hybrid", jobs=1)
    d, note = info.value.diagnostics
    assert d.code == "E404" and d.message.startswith("at K=1..3: Storm failed to check 'nxt' "), d
    assert "__at" not in d.message and d.span is not None and d.span.line == 8
    # the values answered are kept in the points, each at its point (nxt's cells empty)
    lines = note.message.splitlines()
    assert note.code == "N412" and "__at" not in note.message, note.message
    assert lines[0].startswith("3 points were evaluated before this, some in part"), lines
    rows = [row.split(",")[:6] for row in lines[2:]]
    assert [(k, name) for k, name, *_ in rows] == [
        (str(k), n) for k in (1, 2, 3) for n in ("nxt", "reach")], rows
    assert [value == "" for _, name, *_, value in rows] == [True, False] * 3, rows
    exact = sweep(str(path), "K", [1, 2, 3], properties=["reach"], jobs=1)  # sparse, alone
    part = info.value.partial
    assert part.curve("reach", "value") == exact.curve("reach", "value"), part.points
    assert part.curve("nxt", "value") == [None, None, None]


@pytest.mark.storm
def test_a_bool_constant_is_swept_over_false_and_true(tmp_path: Path) -> None:
    """`--const FLAG=false,true` sweeps a bool param; each point equals a verify run at that
    value (the oracle), and the CSV, the JSON and verify's footer write the values as the
    language does. --bound and mixed lists are refused as usage errors."""
    p = tmp_path / "flag.afsm"
    p.write_text("machine flag;\nparam bool FAST;\nvar c : [0..4] init 0;\nmode A initial;\n"
                 "mode B final;\naction Go in A when c < 3 { 0.5 : c += (FAST ? 2 : 1); "
                 "0.5 : c += 1; }\naction Stop in A when c >= 3 { goto B; }\n"
                 "rewards steps { true : 1; }\n"
                 "property n = R{\"steps\"}=? [ F mode == B ];\n")
    out = tmp_path / "flag.csv"
    r = run_cli("sweep", str(p), "--const", "FAST=true,false", "-p", "n", "-o", str(out),
                "--jobs", "1")
    assert r.code == 0, r.err
    rows = list(csv.DictReader(out.open()))
    assert [row["FAST"] for row in rows] == ["false", "true"]
    for row in rows:
        v = run_cli("verify", str(p), "--const", f"FAST={row['FAST']}", "-p", "n")
        assert v.code == 0 and f"constants FAST={row['FAST']};" in v.out, v.out
        one = json.loads(run_cli("verify", str(p), "--const", f"FAST={row['FAST']}", "-p", "n",
                                 "--json").out)
        assert float(row["value"]) == pytest.approx(one["properties"][0]["value"], abs=1e-12)
    assert float(rows[0]["value"]) > float(rows[1]["value"])  # faster with FAST
    js = json.loads(run_cli("sweep", str(p), "--const", "FAST=false,true", "-p", "n",
                            "--json", "--jobs", "1").out)
    assert [pt["x"] for pt in js["points"]] == [False, True]
    bad = run_cli("sweep", str(p), "--const", "FAST=true,1", "-p", "n")
    assert bad.code == 2 and "mixes true/false with numbers" in bad.err
    assert run_cli("sweep", str(p), "-c", "FAST=true", "--bound", "false,true",
                   "-p", "n").code == 2


@pytest.mark.slow
@pytest.mark.storm
def test_sweeping_a_bool_over_numbers_fails_once_before_any_point(tmp_path: Path) -> None:
    path = tmp_path / "windy.afsm"
    path.write_text(BOOL_PARAM)
    r = run_cli("sweep", str(path), "--const", "WINDY=0:1")
    assert r.code == 1
    assert r.err.count("error[E208]") == 1 and "0, 1 are not bools" in r.err, r.err
    assert "sweep it as 'false,true'" in r.err and "points in" not in r.err, r.err
    ok = run_cli("sweep", str(path), "--const", "WINDY=false,true", "--json")
    assert ok.code == 0, ok.err
    # and an int swept over true/false
    path.write_text(BOOL_PARAM.replace("param bool WINDY = false", "param int WINDY = 0")
                    .replace("(WINDY ? 0.1 : 0)", "(WINDY > 0 ? 0.1 : 0)"))
    r = run_cli("sweep", str(path), "--const", "WINDY=false,true")
    assert r.code == 1 and r.err.count("error[E208]") == 1, r.err
    assert "true and false are not numbers" in r.err, r.err


def test_sweep_a_range_replaces_a_preset_value_but_not_a_second_value() -> None:
    fixed, swept = split_consts(["OBJECTS=2", "DEADLINE=500", "DEADLINE=150:500:50"])
    assert fixed == {"OBJECTS": "2"} and swept == {"DEADLINE": [150, 200, 250, 300, 350, 400, 450, 500]}
    assert split_consts(["N=2,T=0:10:5", "M=1"]) == ({"N": "2", "M": "1"}, {"T": [0, 5, 10]})
    for items in (["N=1", "N=2"], ["N=1,N=2"], ["T=1:3", "T=4,5"]):
        with pytest.raises(SystemExit) as exc:
            split_consts(items)
        assert exc.value.code == 2


def test_sweep_values_must_be_finite() -> None:
    for text in ("inf,1", "nan", "0:inf:1", "0:1:nan"):
        with pytest.raises(ValueError, match="finite"):
            parse_values(text)
