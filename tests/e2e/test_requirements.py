"""Requirements end to end on examples/patrol.afsm (finish: min 0.8102, max 0.8316):
verdicts and exit codes, the JUnit report (read back with junitparser), exact values
against sound ones, and every bad input as a diagnostic."""

from __future__ import annotations

import json
import re
from fractions import Fraction
from pathlib import Path

import pytest
from junitparser import Error, Failure, JUnitXml

from afsmc import verify
from tests.conftest import EXAMPLES, run_cli

pytestmark = pytest.mark.storm

PATROL = str(EXAMPLES / "patrol.afsm")


@pytest.mark.parametrize(("formula", "verdict", "code"), [
    ('P>=0.8 [ F "done" ]', "holds", 0),
    ('P>=0.82 [ F "done" ]', "depends", 1),
    ('P>=0.9 [ F "done" ]', "fails", 1),
    ('P<0.2 [ F "halted" ]', "holds", 0),
    ('R{"steps"}<=18 [ F "done" || "halted" ]', "depends", 1),
])
def test_patrol_verdicts_and_exit_codes(formula: str, verdict: str, code: int) -> None:
    r = run_cli("verify", PATROL, "-f", formula, "--json", "--no-uniform")
    assert r.code == code, r.err
    (p,) = json.loads(r.out)["properties"]
    # the precision asked, plus the bound on the built model's rounding over patrol's few
    # expected steps (afsmc.verify.core.conditioning): far below the precision here
    assert p["verdict"] == verdict and 1e-6 <= p["error"] < 1.001e-6
    op = re.match(r'[PR](?:\{"\w+"\})?(<=|>=|<|>)([\d.]+)', formula)
    assert op is not None
    assert p["threshold"] == {"op": op.group(1), "bound": float(op.group(2))}
    if verdict == "depends":  # the bound that counts is the one that breaks it
        assert p["broken_by"] == ("min" if ">" in formula else "max")


def test_the_table_has_a_verdict_column_and_a_reason() -> None:
    r = run_cli("verify", PATROL, "-p", "finish", "-f", 'P>=0.82 [ F "done" ]')
    assert r.code == 1
    head = next(line for line in r.out.splitlines() if line.startswith("property"))
    assert head.split()[-1] == "verdict"
    assert "adhoc: depends: the min 0.810218 ± 1e-06 is not >= 0.82" in r.out
    assert "within 1e-06 of the true one" in r.out
    # a run without requirements prints the table it always did
    plain = run_cli("verify", PATROL, "-p", "finish")
    head = next(line for line in plain.out.splitlines() if line.startswith("property"))
    assert plain.code == 0 and head.split()[-1] == "uniform" and "within" not in plain.out


def test_junit_has_one_testcase_per_requirement(tmp_path: Path) -> None:
    out = tmp_path / "reports" / "patrol.xml"
    r = run_cli("verify", PATROL, "-p", "finish", "-f", 'P>=0.8 [ F "done" ]',
                "-f", 'P>=0.82 [ F "done" ]', "-f", 'P>=0.9 [ F "done" ]',
                "--junit", str(out), "--no-uniform")
    assert r.code == 1
    xml = JUnitXml.fromfile(str(out))
    cases = [c for suite in xml for c in suite]
    assert [c.name.split(":")[0] for c in cases] == ["adhoc", "adhoc2", "adhoc3"]
    results = [c.result for c in cases]
    assert results[0] == []  # holds: passed
    assert all(isinstance(res[0], Failure) for res in results[1:])
    assert "depends" in results[1][0].message and "min 0.810218" in results[1][0].message
    assert "fails" in results[2][0].message and "max 0.831584" in results[2][0].message
    again = tmp_path / "again.xml"
    run_cli("verify", PATROL, "-p", "finish", "-f", 'P>=0.8 [ F "done" ]',
            "-f", 'P>=0.82 [ F "done" ]', "-f", 'P>=0.9 [ F "done" ]',
            "--junit", str(again), "--no-uniform")
    strip = [line for line in out.read_text().splitlines() if "time=" not in line]
    assert strip == [line for line in again.read_text().splitlines() if "time=" not in line]


def test_undecided_is_an_error_in_junit(tmp_path: Path) -> None:
    exact = verify.run(PATROL, properties=["finish"], exact=True, uniform=False)
    lo = exact.property("finish").min
    assert lo is not None
    near = f"{lo + 3e-7:.9f}"  # within 1e-6 of the min, far from the max
    out = tmp_path / "u.xml"
    r = run_cli("verify", PATROL, "-f", f'P>={near} [ F "done" ]', "--junit", str(out))
    assert r.code == 1 and "undecided" in r.out
    (case,) = [c for s in JUnitXml.fromfile(str(out)) for c in s]
    assert isinstance(case.result[0], Error) and "--exact" in case.result[0].message
    # a finer precision decides it
    fine = verify.run(PATROL, formulas=[f'P>={near} [ F "done" ]'], precision=1e-9,
                      uniform=False)
    assert fine.properties[0].verdict is not None
    assert fine.properties[0].verdict.kind == "depends"


def test_exact_values_are_rationals_and_sound_ones_lie_within_their_bound() -> None:
    exact = verify.run(PATROL, exact=True, uniform=False)
    sound = verify.run(PATROL, precision=1e-9, uniform=False)
    for e, s in zip(exact.properties, sound.properties, strict=True):
        # the precision, plus the bound on the built model's rounding (a little more for
        # the expected rewards, which it scales)
        assert e.error == 0 and s.error is not None and 1e-9 <= s.error < 1.1e-9
        for key in ("min", "max"):
            q = Fraction(e.exact[key])
            assert float(q) == getattr(e, key)
            assert abs(getattr(s, key) - q) <= Fraction(1, 10**9), (e.name, key)
    # PRISM's exact engine: finish min 0.810218096815..., fault max 0.189781903185...
    finish, fault = exact.property("finish"), exact.property("fault")
    assert f"{float(Fraction(finish.exact['min'])):.12f}" == "0.810218096815"
    assert f"{float(Fraction(fault.exact['max'])):.12f}" == "0.189781903185"
    # equal as rationals: reaching "done" and never halting are the same event here
    assert exact.property("safe_soon").exact["min"] == finish.exact["min"]
    assert Fraction(fault.exact["max"]) == 1 - Fraction(finish.exact["min"])
    assert exact.model.solver == "exact" and sound.model.solver == "sound-value-iteration"


def test_a_requirement_in_the_file_round_trips_through_fmt(tmp_path: Path) -> None:
    path = tmp_path / "p.afsm"
    path.write_text(Path(PATROL).read_text() + 'property need = P >=0.8[F "done"];\n'
                    'property few = R{"charges"}<(LOW/6) [ F "done" || "halted" ];\n')
    assert run_cli("fmt", str(path)).code == 0
    text = path.read_text()
    assert 'property need        = P>=0.8 [ F "done" ];' in text
    assert 'R{"charges"}<(LOW / 6) [ F "done" || "halted" ];' in text
    assert run_cli("fmt", "--check", str(path)).code == 0
    r = run_cli("verify", str(path), "-p", "need", "-p", "few", "--json", "--no-uniform")
    props = {p["name"]: p for p in json.loads(r.out)["properties"]}
    assert props["need"]["verdict"] == "holds"
    assert props["few"]["threshold"] == {"op": "<", "bound": 0.5}
    assert props["few"]["verdict"] == "depends" and r.code == 1


@pytest.mark.parametrize(("argv", "code", "text"), [
    (["-f", 'P>=1.2 [ F "done" ]'], 1, "E252"),
    (["-f", 'P>=(1/0) [ F "done" ]'], 1, "E252"),
    (["-f", 'P>=(CELLS) [ F "done" ]'], 1, "not 4"),
    (["-f", 'P=>0.5 [ F "done" ]'], 1, "error[E1"),
    (["-f", 'P==0.5 [ F "done" ]'], 1, "E123"),
    (["-f", 'Pmax>=0.5 [ F "done" ]'], 1, "E251"),
    (["-p", "finish", "--precision", "0"], 2, "strictly between 0 and 1"),
    (["-p", "finish", "--precision", "-1e-6"], 2, "strictly between 0 and 1"),
    (["-p", "finish", "--precision", "abc"], 2, "expected a number"),
    (["-p", "finish", "--exact", "--engine", "hybrid"], 2, "--exact needs the sparse engine"),
    (["-p", "finish", "--exact", "--precision", "1e-9"], 2, "exclude each other"),
    (["-p", "finish", "--engine", "dd", "--precision", "1e-9"], 2, "no sound method"),
    (["-f", 'P>=0.5 [ F "done" ]', "--engine", "dd"], 1, "E404"),
])
def test_bad_input_is_a_diagnostic(argv: list[str], code: int, text: str) -> None:
    r = run_cli("verify", PATROL, *argv)
    assert r.code == code and text in r.out + r.err
    assert "Traceback" not in r.out + r.err


def test_the_api_refuses_a_bad_precision() -> None:
    with pytest.raises(ValueError, match="strictly between 0 and 1"):
        verify.run(PATROL, properties=["finish"], precision=0.0)


@pytest.mark.slow
def test_sweep_reports_where_a_requirement_holds_fails_and_depends(tmp_path: Path) -> None:
    out, plot = tmp_path / "s.json", tmp_path / "s.svg"
    r = run_cli("sweep", PATROL, "-c", "CELLS=3:6:1", "-f", 'P>=0.8 [ F "done" ]',
                "--jobs", "1", "--no-uniform", "-o", str(out), "--plot", str(plot))
    assert r.code == 0, r.err
    data = json.loads(out.read_text())
    (req,) = data["requirements"]
    # each point judged by the definition from its own min and max (margins >> 1e-6)
    want = []
    for pt in data["points"]:
        (p,) = pt["properties"]
        kind = ("holds" if p["min"] >= 0.8 else "fails" if p["max"] < 0.8 else "depends")
        assert p["verdict"] == kind
        if want and want[-1]["verdict"] == kind:
            want[-1]["to"] = pt["x"]
        else:
            want.append({"verdict": kind, "from": pt["x"], "to": pt["x"]})
    assert req == {"name": "adhoc", "ranges": want} and len(want) >= 2
    line = next(s for s in r.err.splitlines() if s.startswith("afsmc: adhoc (CELLS):"))
    assert all(f"{w['verdict']} for {w['from']}" in line for w in want)
    assert "requirement &gt;= 0.8" in plot.read_text()


@pytest.mark.slow
def test_the_hybrid_engine_is_sound_too() -> None:
    """Every value of the hybrid engine's sound mode, the uniform DTMC's included, lies
    within its bound of the exact one."""
    exact = verify.run(PATROL, exact=True)
    hybrid = verify.run(PATROL, precision=1e-9, engine="hybrid")
    assert hybrid.model.engine == "hybrid" and hybrid.model.solver == "sound-value-iteration"
    for e, h in zip(exact.properties, hybrid.properties, strict=True):
        for key in ("min", "max", "uniform"):
            assert abs(getattr(h, key) - Fraction(e.exact[key])) <= Fraction(1, 10**9), (
                e.name, key)


def test_a_requirement_is_judged_over_every_fixed_interval_probability(tmp_path: Path) -> None:
    """At P_FAULT's midpoint the min meets 0.6; over P_FAULT in [0.005, 0.03] it does not
    (a higher fault rate lowers it), so the verdict is `depends`, not `holds`."""
    spec = tmp_path / "patrol.afsm"
    spec.write_text((EXAMPLES / "patrol.afsm").read_text(encoding="utf-8").replace(
        "const prob P_FAULT  = 0.01;", "const prob P_FAULT  = [0.005, 0.03];"), encoding="utf-8")
    r = run_cli("verify", str(spec), "-f", 'P>=0.6 [ F "done" ]', "--json")
    assert r.code == 1, r.err
    out = json.loads(r.out)
    prop = out["properties"][0]
    assert prop["reference"]["point"] == "midpoint"
    assert prop["reference"]["min"] >= 0.6  # the floor/ceil MDP at the midpoint would hold
    low = out["probability_intervals"]["properties"][0]
    # the headline min and max are the bounds over the whole box, and they decide
    assert (prop["min"], prop["max"]) == (low["min_attained"], low["max_attained"])
    assert prop["min"] < 0.6 < prop["max"]
    assert prop["verdict"] == "depends" and prop["broken_by"] == prop["decided_by"] == "min"
    assert prop["attained_at"]["min"]["P_FAULT"] > prop["attained_at"]["max"]["P_FAULT"]
    assert out["uncertainty"] == ["interval constants", "interval probabilities"]
