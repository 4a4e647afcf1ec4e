"""Parameter regions: every region called holds or fails is confirmed at its corners and
its centre by an ordinary Storm model at those values; the coverage is the decided volume."""

from __future__ import annotations

import itertools
from fractions import Fraction
from pathlib import Path

import pytest

from afsmc.compiler import load, lowered
from afsmc.diagnostics import CompileError
from afsmc.model.ir import Threshold
from afsmc.verify.outcome.verdicts import Verdict, judge
from afsmc.verify.reports import regions as R
from tests.conftest import EXAMPLES
from tests.unit.verify.points import value

pytestmark = pytest.mark.storm

BOUND = 0.81


@pytest.fixture(scope="module")
def patrol(tmp_path_factory: pytest.TempPathFactory) -> object:
    text = (EXAMPLES / "patrol.afsm").read_text(encoding="utf-8")
    path = tmp_path_factory.mktemp("patrol") / "patrol.afsm"
    path.write_text(text.replace("const prob P_SLIP   = 0.1;",
                                 "const prob P_SLIP   = [0.05, 0.15];"), encoding="utf-8")
    return load(str(path)).model


@pytest.mark.slow
def test_regions_are_confirmed_at_their_corners_and_centre(patrol: object) -> None:
    model = patrol
    low = lowered(model, "nondet")  # type: ignore[arg-type]
    req = R.parse_requirement(f'P>={BOUND} [ F "done" ]')
    box = {"P_FAULT": (0.005, 0.02), "P_SLIP": (0.05, 0.15)}
    src, formulas, built = R.prepare(low, list(box), req, 'P=? [ F "done" ]', "prism")
    # the requirement with its margin against it, and for it (R.with_margin)
    m = R.margin(req)
    assert formulas == (f'Pmin>={BOUND + m!r} [ F "done" ]', f'Pmin>={BOUND - m!r} [ F "done" ]')
    regions, rounds = R.refine(low, src, formulas, built, box, coverage=0.8, max_rounds=8)
    decided = [r for r in regions if r.verdict != "unknown"]
    assert {r.verdict for r in decided} == {"holds", "fails"}
    covered = sum(r.volume(box) for r in decided)
    assert covered >= 0.8 or rounds == 8
    assert sum(r.volume(box) for r in regions) == pytest.approx(1.0)
    for r in decided:
        names = sorted(r.bounds)
        points = [dict(zip(names, c, strict=True))
                  for c in itertools.product(*(r.bounds[n] for n in names))]
        points.append({n: (lo + hi) / 2 for n, (lo, hi) in r.bounds.items()})
        for pt in points:
            v = value(model, pt, 'Pmin=? [ F "done" ]')  # type: ignore[arg-type]
            assert (v >= BOUND) == (r.verdict == "holds"), (r, pt, v)


@pytest.mark.parametrize("text", ['P=? [ F "done" ]', "P>=x [ F \"done\" ]", "F done"])
def test_a_requirement_without_a_bound_is_e442(text: str) -> None:
    with pytest.raises(CompileError) as info:
        R.parse_requirement(text)
    assert info.value.diagnostics[0].code == "E442"


@pytest.mark.parametrize(("text", "mdp", "holds", "fails"), [
    ("P>=0.6 [ F \"s\" ]", True, "Pmin>=0.6", "Pmin<0.6"),
    ("P<0.1 [ F \"s\" ]", True, "Pmax<0.1", "Pmax>=0.1"),
    ("Pmax>0.5 [ F \"s\" ]", True, "Pmax>0.5", "Pmax<=0.5"),
    ("P>=0.6 [ F \"s\" ]", False, "P>=0.6", "P<0.6"),
])
def test_the_requirement_and_its_negation_for_storm(text: str, mdp: bool, holds: str,
                                                     fails: str) -> None:
    req = R.parse_requirement(text)
    got = R.storm_formulas(req, f"P{req.opt}=? [ F \"s\" ]", mdp)
    assert got == (f'{holds} [ F "s" ]', f'{fails} [ F "s" ]')


def test_a_box_is_halved_along_its_widest_side_relative_to_the_whole() -> None:
    whole = {"A": (0.0, 1.0), "B": (0.0, 0.01)}
    halves = R.split({"A": (0.0, 0.5), "B": (0.0, 0.01)}, whole)
    assert halves == [{"A": (0.0, 0.5), "B": (0.0, 0.005)}, {"A": (0.0, 0.5), "B": (0.005, 0.01)}]


@pytest.mark.slow
def test_local_processes_and_dask_give_the_regions_of_one_process(patrol: object) -> None:
    distributed = pytest.importorskip("distributed")
    low = lowered(patrol, "nondet")  # type: ignore[arg-type]
    req = R.parse_requirement(f'P>={BOUND} [ F "done" ]')
    box = {"P_FAULT": (0.005, 0.02), "P_SLIP": (0.05, 0.15)}
    src, formulas, built = R.prepare(low, list(box), req, 'P=? [ F "done" ]', "prism")

    def run(**kw: object) -> list[R.Region]:
        return R.refine(low, src, formulas, built, box, coverage=0.7, max_rounds=5,
                        **kw)[0]  # type: ignore[arg-type]

    one = run(jobs=1)
    assert run(jobs=2) == one
    with distributed.LocalCluster(n_workers=1, threads_per_worker=1, processes=False,
                                  dashboard_address=None) as cluster:
        assert run(dask=cluster.scheduler_address) == one


def _whole(verdicts: list[str], judged: Verdict | None = None) -> tuple[str, str]:
    """The verdict over [0, 1] cut into equal regions with these verdicts."""
    n = len(verdicts)
    regions = [R.Region({"P": (i / n, (i + 1) / n)}, v) for i, v in enumerate(verdicts)]
    res = R.RegionResult("P>=0.5 [ F \"done\" ]", {"P": (0.0, 1.0)}, regions, 0.0, 0.95, 1,
                         judged=judged)
    return res.verdict()


@pytest.mark.parametrize(("verdicts", "kind"), [
    (["holds", "holds"], "holds"),
    (["holds", "fails"], "depends"),
    (["holds", "fails", "unknown"], "depends"),
    (["fails", "fails"], "undecided"),   # an MDP's region fails for some choice only
    (["fails", "unknown"], "undecided"),
    (["unknown"], "undecided"),
])
def test_before_the_bounds_the_regions_decide_only_what_they_prove(verdicts: list[str],
                                                                   kind: str) -> None:
    got, reason = _whole(verdicts)
    assert got == kind, reason


def test_the_verdict_over_the_box_is_verifys_judgement_of_the_bounds() -> None:
    judged = judge(Threshold(">=", 0.5, "0.5"), 0.3, 0.7, 1e-4)
    assert _whole(["holds", "fails"], judged) == (judged.kind, judged.reason)
    assert judged.kind == "depends" and judged.decided_by == "min"


FLAT = """machine flat;
const prob P_X = [0.1, 0.2];
mode A = 0 initial;
mode B = 1;
mode Done = 2 final;
mode Fail = 3 final;
action Go in A {
    P_X: goto B;
    1 - P_X: goto B;
}
action Fin in B {
    0.3: goto Done;
    0.7: goto Fail;
}
"""


@pytest.mark.parametrize("threshold", ["0.3", "0.29999999", "0.30000001", "0.2999999999",
                                       "0.3000000001"])
def test_a_flat_value_at_the_threshold_is_never_labelled_wrongly(tmp_path: Path,
                                                                 threshold: str) -> None:
    # P(F Done) is exactly 3/10 whatever P_X is; 0.3 is no double, and the parametric
    # engine's numbers are within its precision of it: only a margin keeps a label honest
    path = tmp_path / "flat.afsm"
    path.write_text(FLAT, encoding="utf-8")
    low = lowered(load(str(path)).model, "nondet")
    req = R.parse_requirement(f"P>={threshold} [ F mode == Done ]")
    box = {"P_X": (0.1, 0.2)}
    src, formulas, built = R.prepare(low, list(box), req, "P=? [ F mode=2 ]", "prism")
    regions, _ = R.refine(low, src, formulas, built, box, coverage=0.95, max_rounds=3)
    truth = "holds" if Fraction(3, 10) >= Fraction(threshold) else "fails"
    assert {r.verdict for r in regions} <= {truth, "unknown"}
    # within the margin of the value nothing is labelled: the engine's error could be
    # on either side of the threshold
    assert abs(Fraction(threshold) - Fraction(3, 10)) < Fraction(R.margin(req))
    assert {r.verdict for r in regions} == {"unknown"}
