"""Bounds over interval probabilities by parameter lifting on afsmc's explorer
(afsmc.verify.lifting), held to independent oracles: closed forms on a two-step mission
whose value is not monotone in its parameter, Storm's numeric models at random points
of the box (every point value lies inside the outer bounds), and Storm's parametric
route (the same extremes within the precision)."""

from __future__ import annotations

import dataclasses
import itertools
import random
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from afsmc.compiler import load, lowered
from afsmc.model import expr as E
from afsmc.model import ir
from afsmc.verify import run
from afsmc.verify.core.uncertainty import LIFTING, PARAMETRIC
from afsmc.verify.engines.parametric import Extreme, extremes, interval_box
from afsmc.verify.explorer import explore, explore_graph
from afsmc.verify.lifting import bounds, passes, route
from afsmc.verify.lifting.model import NotLiftable, build, queries
from afsmc.verify.lifting.symbolic import multilinear
from afsmc.verify.plan.precision import PARAMETER_PRECISION, PARAMETER_SOLVER_ERROR
from afsmc.verify.reports import regions as R
from tests.conftest import EXAMPLES
from tests.unit.verify.points import value

# PA(1 - PA)(1 - QB) reaches "done": not monotone in PA (largest at PA = 0.5)
TWO_STEPS = """machine twostep;

const prob PA = [0.2, 0.8];
const prob QB = [0.1, 0.3];

var n : [0..2] init 0 clamp;

mode A    = 0 initial;
mode B    = 1;
mode Done = 2 final;
mode Fail = 3 final;

action First in A {
    PA:     goto B, n += 1;
    1 - PA: goto Fail;
}
action Second in B {
    (1 - PA) * (1 - QB): goto Done, n += 1;
    PA + QB - PA * QB:   goto Fail;
}

label done = mode == Done;
label over = mode in {Done, Fail};

rewards firsts {
    [First] true : 1;
}
rewards never {
    [Second] n > 5 : 1;
}

property reach_b = P=? [ F mode == B ];
property done    = P=? [ F "done" ];
property firsts  = R{"firsts"}=? [ F "over" ];
property never   = R{"never"}=? [ F "over" ];
"""


def _bounds(path: Path, consts: dict[str, str] | None = None
            ) -> tuple[dict[str, Extreme], dict[str, float], ir.Model]:
    model = load(str(path), consts).model
    found, gaps, left = route.extremes(lowered(model, "nondet"), model.properties,
                                       interval_box(model), PARAMETER_PRECISION)
    assert not left
    return {e.name: e for e in found}, gaps, model


@pytest.fixture(scope="module")
def two_steps(tmp_path_factory: pytest.TempPathFactory) -> Path:
    path = tmp_path_factory.mktemp("lifting") / "twostep.afsm"
    path.write_text(TWO_STEPS, encoding="utf-8")
    return path


def test_a_value_not_monotone_is_refined_to_its_closed_form(two_steps: Path) -> None:
    got, gaps, _ = _bounds(two_steps)
    done = got["done"]
    # the minimum at a corner (PA = 0.2 or 0.8, QB = 0.3), the maximum inside (PA = 0.5)
    true_min = 0.2 * 0.8 * 0.7
    assert done.min_attained == pytest.approx(true_min, abs=1e-12)
    assert true_min - PARAMETER_PRECISION <= done.min <= true_min + 1e-12
    true_max = 0.25 * 0.9
    assert done.max_attained <= true_max + 1e-12 <= done.max + 2e-12
    assert done.max - done.max_attained <= PARAMETER_PRECISION
    assert gaps["done"] <= PARAMETER_PRECISION
    assert done.max_at["PA"] == pytest.approx(0.5, abs=0.01)


def test_a_monotone_value_is_exact_at_a_corner(two_steps: Path) -> None:
    got, gaps, _ = _bounds(two_steps)
    reach = got["reach_b"]
    assert (reach.min, reach.min_attained, reach.max, reach.max_attained) == pytest.approx(
        (0.2, 0.2, 0.8, 0.8), abs=1e-12)
    assert reach.min_at["PA"] == 0.2 and reach.max_at["PA"] == 0.8
    assert gaps["reach_b"] == 0.0


def test_counts_stay_in_range(two_steps: Path) -> None:
    got, _, _ = _bounds(two_steps)
    assert (got["firsts"].min, got["firsts"].max) == pytest.approx((1.0, 1.0), abs=1e-12)
    never = got["never"]
    assert (never.min, never.min_attained, never.max_attained, never.max) == (0.0,) * 4


def test_verify_reports_the_lifted_bounds_and_judges_them_once(two_steps: Path) -> None:
    res = run(str(two_steps), properties=["done"],
              formulas=['P>=0.1 [ F "done" ]', 'P>=0.2 [ F "done" ]'])
    assert res.probability is not None and res.probability.engine == LIFTING
    intervals: Any = res.to_json()["probability_intervals"]
    assert {e["engine"] for e in intervals["properties"]} == {"lifting"}
    by = {p.name: p for p in res.properties}
    assert by["done"].min == pytest.approx(0.112, abs=1e-12)
    assert by["done"].reference is not None  # the midpoint kept as a reference
    verdicts = [p.verdict.kind for p in res.properties if p.verdict is not None]
    # min 0.112 > 0.1 by more than the error; 0.2 lies between min and max
    assert verdicts == ["holds", "depends"]


def test_multilinear_probabilities_only() -> None:
    pa = E.ConstRef("PA", E.Type.DOUBLE)
    qb = E.ConstRef("QB", E.Type.DOUBLE)
    one = E.lit(1.0)
    x = E.VarRef("x", E.Type.INT)
    params = {"PA", "QB"}
    assert multilinear(E.mul(pa, E.sub(one, qb)), params)
    assert multilinear(E.Binary("/", E.mul(pa, x), E.lit(2.0), E.Type.DOUBLE), params)
    assert multilinear(E.Ite(E.Binary(">", x, E.lit(1), E.Type.BOOL), pa, qb, E.Type.DOUBLE),
                       params)
    assert not multilinear(E.mul(pa, pa), params)
    assert not multilinear(E.Binary("/", x, pa, E.Type.DOUBLE), params)
    assert not multilinear(E.Call("min", (pa, E.lit(0.5)), E.Type.DOUBLE), params)


@pytest.mark.storm
def test_a_probability_not_multilinear_goes_to_storm(tmp_path: Path) -> None:
    path = tmp_path / "square.afsm"
    path.write_text(TWO_STEPS.replace("PA:     goto B", "PA * PA: goto B")
                    .replace("1 - PA: goto Fail;", "1 - PA * PA: goto Fail;"), encoding="utf-8")
    model = load(str(path)).model
    with pytest.raises(NotLiftable):
        route.extremes(lowered(model, "nondet"), model.properties, interval_box(model),
                       PARAMETER_PRECISION)
    res = run(str(path), properties=["reach_b"])
    assert res.probability is not None and res.probability.engine == PARAMETRIC
    intervals: Any = res.to_json()["probability_intervals"]
    assert [e["engine"] for e in intervals["properties"]] == ["parametric"]
    assert res.properties[0].min == pytest.approx(0.04, abs=2 * PARAMETER_PRECISION)


# examples/uav.afsm on a 2x2 arena (1,511 states), the three probabilities the simulators
# measure as their 95% intervals (docs/uncertainty.md, "Worked on the UAV")
UAV_BOX = {"P_INIT_FAIL": (0.0202, 0.0262), "P_DROP_LIFT": (0.0452, 0.0538),
           "P_DROP": (0.0101, 0.0145)}
SMALL = {"WIDTH": "2", "HEIGHT": "2", "T_LIMIT": "80", "DEADLINE": "80"}


@pytest.fixture(scope="module")
def uav(tmp_path_factory: pytest.TempPathFactory) -> Path:
    text = (EXAMPLES / "uav.afsm").read_text(encoding="utf-8")
    for name, (lo, hi) in UAV_BOX.items():
        old = next(line for line in text.splitlines() if line.startswith(f"const prob {name} "))
        text = text.replace(old, f"const prob {name} = [{lo}, {hi}];")
    path = tmp_path_factory.mktemp("uav") / "uav_iv.afsm"
    path.write_text(text, encoding="utf-8")
    return path


@pytest.mark.storm
def test_outer_bounds_contain_the_value_at_random_points(uav: Path) -> None:
    got, _, model = _bounds(uav, SMALL)
    rng = random.Random(49)
    for _ in range(3):
        at = {n: rng.uniform(lo, hi) for n, (lo, hi) in UAV_BOX.items()}
        for name, formula in (("success", 'Pmin=? [ F "success" ]'),
                              ("success", 'Pmax=? [ F "success" ]'),
                              ("drops", 'R{"drops"}min=? [ F "finished" ]'),
                              ("drops", 'R{"drops"}max=? [ F "finished" ]')):
            v = value(model, at, formula)
            assert got[name].min - 1e-9 <= v <= got[name].max + 1e-9, (name, at, v)


@pytest.mark.storm
def test_agrees_with_storm_parametric_route(uav: Path) -> None:
    got, gaps, model = _bounds(uav, SMALL)
    names = ["success", "timeout", "recharges"]
    props = [p for p in model.properties if p.name in names]
    storm = {e.name: e for e in extremes(lowered(model, "nondet"), props)}
    error = PARAMETER_PRECISION + PARAMETER_SOLVER_ERROR
    for name in names:
        ours, theirs = got[name], storm[name]
        assert gaps[name] <= PARAMETER_PRECISION
        # both attain their values, and each is within the other's error of the extreme
        assert abs(ours.min_attained - theirs.min_attained) <= error + PARAMETER_PRECISION
        assert abs(ours.max_attained - theirs.max_attained) <= error + PARAMETER_PRECISION
        # sound: our outer bounds contain what Storm attained
        assert ours.min <= theirs.min_attained + 1e-9
        assert ours.max >= theirs.max_attained - 1e-9


@pytest.mark.storm
def test_regions_by_lifting_are_confirmed_at_their_corners_and_centre(uav: Path) -> None:
    model = load(str(uav), SMALL).model
    low = lowered(model, "nondet")
    prop = next(p for p in model.properties if p.name == "success")
    box = {"P_INIT_FAIL": UAV_BOX["P_INIT_FAIL"], "P_DROP": (0.005, 0.2)}
    lifted = build(low, box, [prop.path.target], [])  # type: ignore[list-item]
    bound = 0.17
    req = R.parse_requirement(f'P>={bound} [ F "success" ]')
    qs, _, _, _ = queries(low, [prop])
    q = R.lifted_query(req, qs[0], mdp=True)
    assert (q.end, q.sched) == ("min", "min")
    regions, rounds = R.refine_lifted(lifted, q, req, box, coverage=0.9, max_rounds=8)
    assert sum(r.volume(box) for r in regions) == pytest.approx(1.0)
    decided = [r for r in regions if r.verdict != "unknown"]
    assert {r.verdict for r in decided} == {"holds", "fails"}
    assert sum(r.volume(box) for r in decided) >= 0.9 or rounds == 8
    # a sample of the regions, each of both verdicts among them (each point a Storm model)
    sample = [next(r for r in decided if r.verdict == v) for v in ("holds", "fails")]
    sample += random.Random(49).sample(decided, min(4, len(decided)))
    for r in sample:
        names = sorted(r.bounds)
        pts = [dict(zip(names, c, strict=True))
               for c in itertools.product(*(r.bounds[n] for n in names))]
        pts.append({n: (lo + hi) / 2 for n, (lo, hi) in r.bounds.items()})
        for pt in pts:
            v = value(model, {**pt, "P_DROP_LIFT": 0.0495}, 'Pmin=? [ F "success" ]')
            assert (v >= bound) == (r.verdict == "holds"), (r, pt, v)


def test_regions_decided_a_box_at_a_time_as_all_at_once(two_steps: Path,
                                                          monkeypatch: pytest.MonkeyPatch) -> None:
    model = load(str(two_steps)).model
    low = lowered(model, "nondet")
    box = interval_box(model)
    prop = next(p for p in model.properties if p.name == "done")
    lifted = build(low, box, [prop.path.target], [])  # type: ignore[list-item]
    req = R.parse_requirement('P>=0.2 [ F "done" ]')
    q = R.lifted_query(req, queries(low, [prop])[0][0], mdp=False)
    boxes = [{"PA": pa, "QB": (0.1, 0.12)} for pa in ((0.2, 0.25), (0.48, 0.52), (0.3, 0.5))]
    together = bounds.decide(lifted, q, boxes, req.cmp, req.bound, R.margin(req))
    monkeypatch.setattr(bounds, "VALUE_BYTES", 1)
    assert bounds.decide(lifted, q, boxes, req.cmp, req.bound, R.margin(req)) == together
    # PA(1 - PA)(1 - QB): at most 0.25 * 0.8 * 0.9 = 0.18 on the first box; at least
    # 0.48 * 0.48 * 0.88 = 0.2028 by lifting on the second; the third straddles 0.2
    assert together == ["fails", "holds", "unknown"]


def test_votes_compare_each_parameters_best_corner_on_either_side() -> None:
    # few distinct values, so that ties (no vote) occur; checked against the definition
    # corner by corner, the first parameter's bit the most significant
    rng = np.random.default_rng(49)
    for k in (1, 2, 3):
        signed = rng.integers(0, 4, size=(40, 1 << k, 2)).astype(float)
        want = np.zeros((2, k, 2))
        for c, q, i in itertools.product(range(40), range(2), range(k)):
            ends = [min(signed[c, x, q] for x in range(1 << k) if (x >> (k - 1 - i)) & 1 == b)
                    for b in (0, 1)]
            want[0, i, q] += ends[1] > ends[0]
            want[1, i, q] += ends[1] < ends[0]
        assert (passes._votes(signed, k) == want).all()


HALF = """machine half;

const prob PX = [0.4, 0.6];

mode A    = 0 initial;
mode Done = 1 final;
mode Fail = 2 final;

action Go in A {
    OUTCOMES
}

property done = P=? [ F mode == Done ];
"""


@pytest.mark.parametrize("outcomes", [
    "PX: goto Done; 0.5: goto Fail;",  # sums to 1 at PX = 0.5 only
    "1.5 - PX: goto Done; PX - 0.5: goto Fail;",  # 0 at PX = 0.5, dropped there
])
def test_a_distribution_off_one_at_a_further_point_is_refused_while_exploring(
        tmp_path: Path, outcomes: str) -> None:
    path = tmp_path / "half.afsm"
    path.write_text(HALF.replace("OUTCOMES", outcomes), encoding="utf-8")
    model = load(str(path)).model
    low = lowered(model, "nondet")
    targets = [model.properties[0].path.target]
    for further, fine in ((0.5, True), (0.6, False)):
        compiled = explore.compile_model(low, targets, [], points=[{"PX": 0.5}, {"PX": further}])
        if fine:
            # Fail is not reached where its probability is 0 at the point explored
            states = 2 if "PX - 0.5" in outcomes else 3
            assert explore_graph.explore(compiled, None, None, None).states == states
        else:
            with pytest.raises(explore.GiveUp, match="further valuation"):
                explore_graph.explore(compiled, None, None, None)


def test_regions_second_side_only_where_the_first_does_not_hold(
        two_steps: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    model = load(str(two_steps)).model
    low = lowered(model, "nondet")
    prop = next(p for p in model.properties if p.name == "done")
    lifted = build(low, interval_box(model), [prop.path.target], [])  # type: ignore[list-item]
    req = R.parse_requirement('P>=0.2 [ F "done" ]')
    q = R.lifted_query(req, queries(low, [prop])[0][0], mdp=False)
    boxes = [{"PA": pa, "QB": (0.1, 0.12)} for pa in ((0.2, 0.25), (0.48, 0.52), (0.3, 0.5))]
    asked: list[tuple[str, int]] = []
    real = bounds._lifted_values

    def counted(lf: Any, qq: Any, bs: Any) -> list[float]:
        asked.append((qq.end, len(bs)))
        return real(lf, qq, bs)

    monkeypatch.setattr(bounds, "_lifted_values", counted)
    verdicts = bounds.decide(lifted, q, boxes, req.cmp, req.bound, R.margin(req))
    assert verdicts == ["fails", "holds", "unknown"]
    assert asked == [("min", 3), ("max", 2)]  # the box that holds is not lifted again
    # each verdict as each box's own lifted bounds on either side say
    for b, v in zip(boxes, verdicts, strict=True):
        worst = bounds._lift(lifted, q, b)[0]
        best = bounds._lift(lifted, dataclasses.replace(q, end="max"), b)[0]
        assert v == ("holds" if worst >= 0.2 + R.margin(req) else
                     "fails" if best <= 0.2 - R.margin(req) else "unknown")
