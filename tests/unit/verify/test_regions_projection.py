"""The projection `afsmc regions --plot` draws over more than two parameters: each cell of
the axes' grid carries the share of its slice of the other parameters that holds, fails
or is unknown, checked against a brute-force count over the finest grid of every region
edge; and the picture (`fills`) shows a verdict wherever a region of it lies over a cell,
so a decided region is never hidden under an undecided one."""

from __future__ import annotations

import itertools
import math
import random

import pytest

from afsmc.commands.render.regions_plot import Fill, fills
from afsmc.compiler import load, lowered
from afsmc.verify.reports import regions as R
from tests.conftest import EXAMPLES

BOX: R.Bounds = {"A": (0.0, 1.0), "B": (0.2, 0.6), "C": (0.001, 0.01)}


def random_regions(seed: int, splits: int, box: R.Bounds = BOX) -> list[R.Region]:
    """A partition of `box` by random halvings (as `refine` halves), random verdicts."""
    rng = random.Random(seed)
    boxes = [dict(box)]
    for _ in range(splits):
        b = boxes.pop(rng.randrange(len(boxes)))
        boxes += R.split(b, box)
    return [R.Region(b, rng.choice(["holds", "fails", "unknown"])) for b in boxes]


def result(regions: list[R.Region], box: R.Bounds = BOX) -> R.RegionResult:
    return R.RegionResult("P>=0.5 [ F \"done\" ]", box, regions, 0.0, 0.95, 1)


def brute_force(res: R.RegionResult, axes: list[str]
                ) -> dict[tuple[tuple[float, float], tuple[float, float]], dict[str, float]]:
    """Per cell of the axes' grid, the verdicts' shares of its slice: the finest grid of
    every edge of every region, each elementary box given to the region holding its
    centre, its volume counted in the axes' cell holding that centre."""
    names = list(res.box)
    edges = {n: sorted({e for r in res.regions for e in r.bounds[n]}) for n in names}
    out: dict[tuple[tuple[float, float], tuple[float, float]], dict[str, float]] = {}
    for sides in itertools.product(*(list(itertools.pairwise(edges[n])) for n in names)):
        cell = dict(zip(names, sides, strict=True))
        centre = {n: (lo + hi) / 2 for n, (lo, hi) in cell.items()}
        (owner,) = [r for r in res.regions
                    if all(r.bounds[n][0] <= centre[n] <= r.bounds[n][1] for n in names)]
        rest = math.prod((cell[n][1] - cell[n][0]) / (res.box[n][1] - res.box[n][0])
                         for n in names if n not in axes)
        key = (cell[axes[0]], cell[axes[1]])
        shares = out.setdefault(key, dict.fromkeys(("holds", "fails", "unknown"), 0.0))
        shares[owner.verdict] += rest
    return out


@pytest.mark.parametrize("seed", range(6))
@pytest.mark.parametrize("axes", [["A", "B"], ["C", "A"], ["B", "C"]])
def test_each_cell_holds_the_shares_of_its_slice(seed: int, axes: list[str]) -> None:
    res = result(random_regions(seed, 25))
    cells = R.projection(res, axes)
    expected = brute_force(res, axes)
    assert len(cells) == len(expected)
    for c in cells:
        assert c.y is not None
        want = expected[(c.x, c.y)]
        assert c.share == pytest.approx(want, abs=1e-12)
        assert sum(c.share.values()) == pytest.approx(1.0, abs=1e-12)
    # weighted by the cells' areas, the shares are the fractions of the whole volume
    (xlo, xhi), (ylo, yhi) = res.box[axes[0]], res.box[axes[1]]
    for verdict in ("holds", "fails", "unknown"):
        total = sum(c.share[verdict] * (c.x[1] - c.x[0]) / (xhi - xlo)
                    * (c.y[1] - c.y[0]) / (yhi - ylo) for c in cells if c.y is not None)
        assert total == pytest.approx(res.fraction(verdict), abs=1e-12)


def test_over_the_plotted_parameters_alone_each_cell_is_one_region() -> None:
    box = {"A": BOX["A"], "B": BOX["B"]}
    res = result(random_regions(3, 12, box), box)
    for c in R.projection(res, ["A", "B"]):
        assert sorted(c.share.values()) == [0.0, 0.0, 1.0]
    # and the picture draws the regions themselves
    assert sorted(fills(res, ["A", "B"]), key=repr) == sorted(
        (Fill(r.bounds["A"], r.bounds["B"], r.verdict) for r in res.regions), key=repr)


def test_the_picture_shows_every_verdict_lying_over_a_cell() -> None:
    res = result(random_regions(11, 40))
    axes = ["A", "C"]
    drawn = fills(res, axes)
    assert len(drawn) == len(R.projection(res, axes))
    for f in drawn:
        over = {r.verdict for r in res.regions
                if min(r.bounds["A"][1], f.x[1]) > max(r.bounds["A"][0], f.x[0])
                and min(r.bounds["C"][1], f.y[1]) > max(r.bounds["C"][0], f.y[0])}
        want = ("depends" if {"holds", "fails"} <= over
                else "unknown" if over == {"unknown"}
                else f"{next(iter(over - {'unknown'}))}, rest unknown" if "unknown" in over
                else next(iter(over)))
        assert f.shows == want, (f, over)


@pytest.mark.storm
def test_a_three_parameter_run_draws_its_decided_volume() -> None:
    """The reproducer of issue 44: warehouse.afsm with an interval probability and two
    --param. Whatever the axes, a cell shows holds (or depends) wherever a region that
    holds projects onto it; the plot of two of three parameters hid them all under
    unknown slices."""
    text = (EXAMPLES / "warehouse.afsm").read_text(encoding="utf-8").replace(
        "const prob P_FAULT = 0.002;", "const prob P_FAULT = [0.001, 0.01];")
    model = load("warehouse.afsm", text=text).model
    low = lowered(model, "nondet")
    box = {"P_GRASP": (0.8, 0.99), "P_SLIP": (0.01, 0.1), "P_FAULT": (0.001, 0.01)}
    req = R.parse_requirement('P>=0.93 [ F "done" ]')
    src, formulas, built = R.prepare(low, list(box), req, 'P=? [ F "done" ]', "prism")
    regions, _ = R.refine(low, src, formulas, built, box, coverage=0.8, max_rounds=8)
    res = result(regions, box)
    assert res.fraction("holds") > 0.1 and res.fraction("fails") > 0.1
    for axes in (["P_GRASP", "P_SLIP"], ["P_SLIP", "P_FAULT"]):
        drawn = fills(res, axes)
        for r in regions:
            if r.verdict == "unknown":
                continue
            under = [f for f in drawn
                     if r.bounds[axes[0]][0] <= f.x[0] < r.bounds[axes[0]][1]
                     and r.bounds[axes[1]][0] <= f.y[0] < r.bounds[axes[1]][1]]
            assert under and all(r.verdict in f.shows or f.shows == "depends"
                                 for f in under), (axes, r)
