"""Monotonicity proven from an interval bound on the slopes carried along the backward
pass (afsmc.verify.lifting.monotone), and the regions it decides by exact corner values
(afsmc.verify.lifting.regions), held to independent oracles: closed forms and their
derivatives on a grid, Storm's numeric models at grid points and corners, and a value
that is not monotone (never claimed monotone)."""

from __future__ import annotations

import itertools
import json
from collections.abc import Callable
from pathlib import Path

import numpy as np
import pytest

from afsmc.compiler import load, lowered
from afsmc.model import ir
from afsmc.verify.engines.parametric import interval_box
from afsmc.verify.lifting import monotone
from afsmc.verify.lifting.model import Lifted, Query, build, queries
from afsmc.verify.lifting.regions import Decider
from afsmc.verify.reports import regions as R
from tests.conftest import run_cli
from tests.unit.verify.points import value
from tests.unit.verify.test_lifting import SMALL, TWO_STEPS, UAV_BOX

# PA / (1 - (1 - PA) QB): retried while QB holds, a self-loop whose probability reads both
RETRY = """machine retry;

const prob PA = [0.2, 0.8];
const prob QB = [0.1, 0.6];

mode A    = 0 initial;
mode Done = 1 final;
mode Fail = 2 final;

action Try in A {
    PA:                   goto Done;
    (1 - PA) * QB:        goto A;
    (1 - PA) * (1 - QB):  goto Fail;
}

rewards tries {
    [Try] true : 1;
}

property done  = P=? [ F mode == Done ];
property tries = R{"tries"}=? [ F mode != A ];
"""


def _lifted(text: str, tmp: Path, prop: str) -> tuple[Lifted, Query, ir.Model]:
    path = tmp / "m.afsm"
    path.write_text(text, encoding="utf-8")
    model = load(str(path)).model
    low = lowered(model, "nondet")
    p = next(x for x in model.properties if x.name == prop)
    qs, targets, rewards, _ = queries(low, [p])
    return build(low, interval_box(model), targets, rewards), qs[0], model


def _grid_quotients(f: Callable[[float, float], float], box: dict[str, tuple[float, float]],
                    steps: int = 6) -> tuple[list[float], list[float]]:
    """Every difference quotient of f(PA, QB) along PA and along QB between neighbours of
    a grid over `box` (a brute-force oracle of the slopes)."""
    pa = np.linspace(*box["PA"], steps)
    qb = np.linspace(*box["QB"], steps)
    along_pa = [(f(pa[i + 1], q) - f(pa[i], q)) / (pa[i + 1] - pa[i])
                for i in range(steps - 1) for q in qb]
    along_qb = [(f(p, qb[j + 1]) - f(p, qb[j])) / (qb[j + 1] - qb[j])
                for j in range(steps - 1) for p in pa]
    return along_pa, along_qb


def _done(pa: float, qb: float) -> float:
    return pa * (1 - pa) * (1 - qb)


def _retry(pa: float, qb: float) -> float:
    return pa / (1 - (1 - pa) * qb)


def _tries(pa: float, qb: float) -> float:
    return 1 / (1 - (1 - pa) * qb)  # the expected number of tries


@pytest.mark.parametrize(("text", "prop", "f", "boxes"), [
    (TWO_STEPS, "done", _done, [{"PA": (0.2, 0.8), "QB": (0.1, 0.3)}, {"PA": (0.2, 0.4), "QB": (0.1, 0.3)},
                        {"PA": (0.6, 0.8), "QB": (0.2, 0.3)}, {"PA": (0.45, 0.55), "QB": (0.1, 0.3)}]),
    (RETRY, "done", _retry, [{"PA": (0.2, 0.8), "QB": (0.1, 0.6)},
                             {"PA": (0.5, 0.6), "QB": (0.3, 0.4)}]),
    (RETRY, "tries", _tries, [{"PA": (0.2, 0.8), "QB": (0.1, 0.6)},
                              {"PA": (0.5, 0.6), "QB": (0.3, 0.4)}]),
])
def test_slopes_contain_every_difference_quotient_of_the_closed_form(
        tmp_path: Path, text: str, prop: str, f: Callable[[float, float], float],
        boxes: list[dict[str, tuple[float, float]]]) -> None:
    lifted, q, _ = _lifted(text, tmp_path, prop)
    assert lifted.names == ("PA", "QB")
    for box in boxes:
        s = monotone.slopes(lifted, q, box)
        values = [f(pa, qb) for pa, qb in itertools.product(np.linspace(*box["PA"], 6),
                                                             np.linspace(*box["QB"], 6))]
        assert s.low <= min(values) + 1e-12 and max(values) <= s.high + 1e-12
        for quotients, (lo, hi) in zip(_grid_quotients(f, box), s.slopes, strict=True):
            assert lo <= min(quotients) + 1e-12 and max(quotients) <= hi + 1e-12, (box, lo, hi)


def test_a_value_not_monotone_is_not_claimed_monotone(tmp_path: Path) -> None:
    # PA(1 - PA)(1 - QB) rises in PA below 0.5 and falls above it
    lifted, q, _ = _lifted(TWO_STEPS, tmp_path, "done")
    for box in ({"PA": (0.2, 0.8), "QB": (0.1, 0.3)}, {"PA": (0.45, 0.55), "QB": (0.1, 0.3)},
                {"PA": (0.49, 0.51), "QB": (0.1, 0.11)}):
        s = monotone.slopes(lifted, q, box)
        assert s.signs() is None
        lo, hi = s.slopes[0]
        assert lo < 0.0 < hi  # both signs occur along PA: the grid shows it
        along_pa, _ = _grid_quotients(_done, box)
        assert min(along_pa) < 0.0 < max(along_pa)
    # on either side of 0.5 it is monotone, and the signs say which way
    assert monotone.slopes(lifted, q, {"PA": (0.2, 0.4), "QB": (0.1, 0.3)}).signs() == (1, -1)
    assert monotone.slopes(lifted, q, {"PA": (0.6, 0.8), "QB": (0.1, 0.3)}).signs() == (-1, -1)


def test_a_parameter_no_probability_reads_has_slope_exactly_zero(tmp_path: Path) -> None:
    lifted, q, _ = _lifted(TWO_STEPS, tmp_path, "reach_b")  # PA alone reaches B
    s = monotone.slopes(lifted, q, {"PA": (0.2, 0.8), "QB": (0.1, 0.3)})
    assert s.slopes[1] == (0.0, 0.0) and s.signs() == (1, 0)
    assert s.slopes[0][0] <= 1.0 <= s.slopes[0][1]
    assert s.slopes[0][1] - s.slopes[0][0] < 1e-9


@pytest.mark.storm
def test_monotone_uav_corners_are_point_verifications(tmp_path: Path) -> None:
    # examples/uav.afsm on a 2x2 arena, the MDP's Pmin of success over P_INIT_FAIL and
    # P_DROP (P_DROP_LIFT fixed): proven monotone over the whole box; on a 3 x 3 grid
    # of point-valued Storm models the values fall along both, and the two extreme
    # corners' exact values are the point verifications there
    from tests.conftest import EXAMPLES

    text = (EXAMPLES / "uav.afsm").read_text(encoding="utf-8")
    box = {"P_INIT_FAIL": UAV_BOX["P_INIT_FAIL"], "P_DROP": (0.005, 0.2)}
    for name, (lo, hi) in box.items():
        old = next(line for line in text.splitlines() if line.startswith(f"const prob {name} "))
        text = text.replace(old, f"const prob {name} = [{lo}, {hi}];")
    path = tmp_path / "uav.afsm"
    path.write_text(text, encoding="utf-8")
    model = load(str(path), SMALL).model
    low = lowered(model, "nondet")
    prop = next(p for p in model.properties if p.name == "success")
    lifted = build(low, box, [prop.path.target], [])  # type: ignore[list-item]
    req = R.parse_requirement('P>=0.17 [ F "success" ]')
    q = R.lifted_query(req, queries(low, [prop])[0][0], mdp=True)
    s = monotone.slopes(lifted, q, box)
    signs = s.signs()
    assert signs == (-1, -1)  # lifted.names: P_DROP, P_INIT_FAIL
    formula = 'Pmin=? [ F "success" ]'
    grid = {n: np.linspace(lo, hi, 3).tolist() for n, (lo, hi) in box.items()}
    at = {pt: value(model, dict(zip(lifted.names, pt, strict=True)), formula)
          for pt in itertools.product(grid["P_DROP"], grid["P_INIT_FAIL"])}
    for (d, f), v in at.items():
        for (d2, f2), v2 in at.items():
            if d <= d2 and f <= f2:
                assert v2 <= v + 1e-9  # non-increasing in both
    for end in ("min", "max"):
        corner = monotone.extreme_corner(lifted.names, box, signs, end)
        exact = monotone.exact_values(lifted, q, [corner], 1 << 20)[0]
        assert exact == pytest.approx(value(model, corner, formula), abs=1e-9)
        assert exact == pytest.approx((min if end == "min" else max)(at.values()), abs=1e-9)
        assert s.low - 1e-12 <= exact <= s.high + 1e-12
    # the regions: every box inside the proven one, decided by its corners
    decider = Decider(lifted, q, req.cmp, req.bound, R.margin(req))
    regions, _ = R.refine_lifted(lifted, q, req, box, coverage=0.9, max_rounds=8)
    assert decider.decide([box]) == ["unknown"] and decider.slope_passes == 1
    decided = [r for r in regions if r.verdict != "unknown"]
    assert {r.verdict for r in decided} == {"holds", "fails"}
    assert decider.decide([dict(r.bounds) for r in decided]) == [r.verdict for r in decided]
    assert decider.slope_passes == 1  # every region lies inside the box proven monotone
    for r in decided:
        names = sorted(r.bounds)
        for c in itertools.product(*(r.bounds[n] for n in names)):
            v = decider.values.get(tuple(dict(zip(names, c, strict=True))[n]
                                         for n in lifted.names))
            if v is not None:
                assert (v >= req.bound) == (r.verdict == "holds")


def test_regions_json_names_lifting_and_each_decided_corner_agrees(tmp_path: Path) -> None:
    # RETRY's value PA / (1 - (1 - PA) QB) rises in both: every region decided by its
    # corners (one slope pass for the whole box); the closed form at each corner of each
    # decided region agrees with its verdict
    path = tmp_path / "retry.afsm"
    path.write_text(RETRY, encoding="utf-8")
    r = run_cli("regions", str(path), "--require", 'P>=0.6 [ F mode == Done ]', "--json",
                "--coverage", "0.9")
    assert r.code == 0, r.err
    out = json.loads(r.out)
    assert out["engine"] == "lifting" and out["coverage"] >= 0.9
    decided = [g for g in out["regions"] if g["verdict"] != "unknown"]
    assert {g["verdict"] for g in decided} == {"holds", "fails"}
    for g in decided:
        for pa, qb in itertools.product(g["bounds"]["PA"], g["bounds"]["QB"]):
            assert (_retry(pa, qb) >= 0.6) == (g["verdict"] == "holds"), (g, pa, qb)


@pytest.mark.storm
def test_diagram_reach_with_interval_probabilities_by_lifting(tmp_path: Path) -> None:
    # the diagram's --reach over TWO_STEPS' box: Done's bounds are PA(1 - PA)(1 - QB)'s
    # extremes (0.2 * 0.8 * 0.7 at a corner, 0.25 * 0.9 at PA = 0.5), by parameter lifting
    from afsmc.api.diagram import mode_reachability

    path = tmp_path / "twostep.afsm"
    path.write_text(TWO_STEPS, encoding="utf-8")
    model = load(str(path)).model
    said: list[str] = []
    got, mdp = mode_reachability(model, "nondet", progress=said.append)
    assert mdp
    assert any("bounds over the interval probabilities (afsmc's explorer, parameter lifting)"
               in s for s in said), said
    done = next(m.number for m in model.modes if m.name == "Done")
    b = next(m.number for m in model.modes if m.name == "B")
    assert got[b] == pytest.approx((0.2, 0.8), abs=1e-12)
    assert got[done][0] == pytest.approx(0.2 * 0.8 * 0.7, abs=1e-12)
    assert got[done][1] == pytest.approx(0.25 * 0.9, abs=1e-4)


# 0.9 PA + (1 - PA)(0.6 - 0.5 PA) = 0.6 - 0.2 PA + 0.5 PA^2, rising on [0.3, 0.8] (its
# derivative PA - 0.2 > 0) while C's own value falls in PA: the lifted states disagree
DISAGREE = """machine disagree;

const prob PA = [0.3, 0.8];

mode A    = 0 initial;
mode B    = 1;
mode C    = 2;
mode Done = 3 final;
mode Fail = 4 final;

action First in A {
    PA:     goto B;
    1 - PA: goto C;
}
action FromB in B {
    0.9: goto Done;
    0.1: goto Fail;
}
action FromC in C {
    0.6 - 0.5 * PA: goto Done;
    0.4 + 0.5 * PA: goto Fail;
}

property done = P=? [ F mode == Done ];
"""


def test_a_monotone_value_whose_states_disagree_is_exact_at_its_corners(tmp_path: Path) -> None:
    from afsmc.verify.lifting import bounds, passes
    from afsmc.verify.plan.precision import PARAMETER_PRECISION

    lifted, q, _ = _lifted(DISAGREE, tmp_path, "done")
    # the lifted bound alone is far from the minimum (C at PA = 0.8, A at PA = 0.3)
    corners = lifted.values_at([{"PA": 0.3}, {"PA": 0.8}])
    outer = float(passes.lifted_bounds(lifted, [q], corners)[0][0])
    assert outer == pytest.approx(0.3 * 0.9 + 0.7 * 0.2, abs=1e-12)
    assert monotone.slopes(lifted, q, lifted.box).signs() == (1,)
    # the bounds: exact at the corners the signs name, no refinement (gap 0); by splitting
    # the outer bound would only come within the precision of them
    path = tmp_path / "m.afsm"
    model = load(str(path)).model
    (e,), gaps = bounds.extremes(lifted, queries(lowered(model, "nondet"), model.properties)[0],
                                 PARAMETER_PRECISION)
    lo, hi = (0.6 - 0.2 * pa + 0.5 * pa * pa for pa in (0.3, 0.8))
    assert (e.min, e.min_attained, e.max, e.max_attained) == pytest.approx((lo, lo, hi, hi),
                                                                           abs=1e-12)
    assert (e.min_at, e.max_at, e.engine) == ({"PA": 0.3}, {"PA": 0.8}, "lifting")
    assert gaps["done"] == 0.0


def test_states_renumbered_dependent_first_give_the_same_values(
        monkeypatch: pytest.MonkeyPatch) -> None:
    # the small UAV over P_INIT_FAIL x P_DROP: the states that do not depend on them have
    # one value at every corner (a full pass at each, compared state by state); a point
    # pass over the dependent states only, the others taken from one pass at the centre,
    # gives the values of a pass over every state
    from afsmc.verify.lifting import order, passes
    from tests.conftest import EXAMPLES

    model = load(str(EXAMPLES / "uav.afsm"), SMALL).model
    low = lowered(model, "nondet")
    box = {"P_INIT_FAIL": UAV_BOX["P_INIT_FAIL"], "P_DROP": (0.005, 0.2)}
    prop = next(p for p in model.properties if p.name == "success")
    lifted = build(low, box, [prop.path.target], [])  # type: ignore[list-item]
    q = R.lifted_query(R.parse_requirement('P>=0.5 [ F "success" ]'),
                       queries(low, [prop])[0][0], mdp=True)
    dep = order.dependent(lifted)
    assert 0 < dep.sum() < len(dep)
    corners = [dict(zip(lifted.names, c, strict=True))
               for c in itertools.product(*(box[n] for n in lifted.names))]
    every = passes.sweep(lifted, [q] * 4, lifted.values_at(corners), lift=False,
                         every=True)[0][:, 0, :]
    assert (every[~dep] == every[~dep][:, :1]).all()
    assert (every[dep] != every[dep][:, :1]).any(axis=1).sum() > 0
    # a few layers at a time, as on a model of millions of states
    monkeypatch.setattr(order, "CHUNK_STATES", 50)
    assert len(order._chunks(lifted.arrays.layers)) > 3
    renumbered = order.dependent_first(lifted)
    assert renumbered.leading is not None and renumbered.leading.sum() == dep.sum()
    base = monotone.base_values(renumbered, q)
    points = [{"P_INIT_FAIL": 0.021, "P_DROP": 0.05}, {"P_INIT_FAIL": 0.025, "P_DROP": 0.17},
              *corners]
    want = passes.attained(lifted, [q] * len(points), lifted.values_at(points))
    got = monotone.exact_values(renumbered, q, points, 1 << 20, base)
    assert got == pytest.approx(want.tolist(), abs=1e-12)


def test_expected_rewards_get_slopes_too(tmp_path: Path) -> None:
    # 1 / (1 - (1 - PA) QB) tries: fewer as PA rises, more as QB does
    lifted, q, _ = _lifted(RETRY, tmp_path, "tries")
    assert monotone.slopes(lifted, q, lifted.box).signs() == (-1, 1)
    # one First whatever PA and QB: a count that does not depend on them, slopes exactly 0
    lifted, q, _ = _lifted(TWO_STEPS, tmp_path, "firsts")
    s = monotone.slopes(lifted, q, lifted.box)
    assert (s.low, s.high, s.slopes) == (1.0, 1.0, ((0.0, 0.0), (0.0, 0.0)))


def test_regions_of_a_value_not_monotone_split_until_the_halves_are(tmp_path: Path) -> None:
    # PA(1 - PA)(1 - QB) >= 0.2: not monotone over the whole box (no corner rule there),
    # monotone on boxes on either side of PA = 0.5, which are then decided by corners;
    # every decided region agrees with the closed form at its corners and at its point
    # nearest PA = 0.5 (where the value is greatest along PA)
    lifted, q, _ = _lifted(TWO_STEPS, tmp_path, "done")
    req = R.parse_requirement('P>=0.2 [ F "done" ]')
    q = R.lifted_query(req, q, mdp=False)
    decider = Decider(lifted, q, req.cmp, req.bound, R.margin(req))
    box = dict(lifted.box)
    assert decider.decide([box]) == ["unknown"] and not decider.proven
    decider.decide([{"PA": (0.2, 0.4), "QB": box["QB"]}])
    assert [signs for _, signs in decider.proven] == [(1, -1)]
    regions, _ = R.refine_lifted(lifted, q, req, box, coverage=0.8, max_rounds=10)
    decided = [r for r in regions if r.verdict != "unknown"]
    assert {r.verdict for r in decided} == {"holds", "fails"}
    assert sum(r.volume(box) for r in decided) >= 0.8
    for r in decided:
        (pa_lo, pa_hi), (qb_lo, qb_hi) = r.bounds["PA"], r.bounds["QB"]
        top = min(max(0.5, pa_lo), pa_hi)
        values = [_done(pa, qb) for pa in (pa_lo, pa_hi, top) for qb in (qb_lo, qb_hi)]
        if r.verdict == "holds":
            assert min(values) >= 0.2
        else:
            assert max(values) <= 0.2
