"""The checks' shortcuts (sampling before the exhaustive search, interval arithmetic before
a search) must give exactly the answers of the exhaustive search they skip."""

from __future__ import annotations

from pathlib import Path

import pytest

from afsmc.compiler import load
from afsmc.model import expr as E
from afsmc.model import ir
from afsmc.model.bounds import bounds
from afsmc.model.search import exists, find
from afsmc.model.semantics import enabled, fire_condition

ROOT = Path(__file__).resolve().parents[3]
EXAMPLES = sorted((ROOT / "examples").glob("*.afsm"))
SMALL = {"uav.afsm": {"WIDTH": "3", "HEIGHT": "3", "T_LIMIT": "120"}}


def machines(path: Path) -> list[ir.Model]:
    """The example's machine, or each agent's machine of a composed mission (the checks run
    per agent)."""
    model = load(str(path), SMALL.get(path.name)).model
    if model.composition is None:
        return [model]
    return [agent.model for agent in model.composition.agents]


@pytest.mark.parametrize("path", EXAMPLES, ids=lambda p: p.name)
def test_exists_agrees_with_the_exhaustive_search(path: Path) -> None:
    asked = 0
    for model in machines(path):
        asked += _ask_every_condition(model)
    assert asked > 0


def _ask_every_condition(model: ir.Model) -> int:
    asked = 0
    for a in model.actions:
        for mode in a.modes:
            for pred in (fire_condition(model, a, mode),
                         fire_condition(model, a, mode, ties=True), enabled(model, a, mode),
                         E.neg(enabled(model, a, mode))):
                assert exists(model, mode, pred) == (find(model, mode, pred) is not None)
                asked += 1
    return asked


@pytest.mark.parametrize("path", EXAMPLES, ids=lambda p: p.name)
def test_update_ranges_shortcut_is_conservative(path: Path) -> None:
    # Where interval arithmetic says an update stays in range, no state may take it out.
    for model in machines(path):
        _check_update_ranges(model)


def _check_update_ranges(model: ir.Model) -> None:
    for a in model.actions:
        for o in a.outcomes:
            for u in o.updates:
                if u.var == "mode" or model.variable(u.var).type is not E.Type.INT:
                    continue
                var = model.variable(u.var)
                lo, hi = bounds(u.value, model)
                if var.lo <= lo and hi <= var.hi:
                    out = E.disj(E.Binary("<", u.value, E.lit(var.lo), E.Type.BOOL),
                                 E.Binary(">", u.value, E.lit(var.hi), E.Type.BOOL))
                    assert all(find(model, m, out, c) is None for m in a.modes
                               for c in _ends(model, u.value))


def _ends(model: ir.Model, e: E.Expr) -> list[dict[str, int]]:
    """Every floor/ceil choice of the interval constants that `e` reads."""
    used = [c for c in model.interval_constants if c.name in E.consts_read(e)]
    out: list[dict[str, int]] = [{}]
    for c in used:
        out = [d | {c.name: end} for d in out for end in (c.interval or ())]
    return out


@pytest.mark.parametrize("case", ["err_weight_tie", "err_weight_tie_rounding",
                                  "err_weight_tie_no_order_warnings", "warn_deadlock"])
def test_the_smt_solver_decides_ties_as_enumeration_does(
        case: str, monkeypatch: pytest.MonkeyPatch) -> None:
    """A tie (weights within 1e-12, E301) and the mode graph's view of it are the same
    whether the states are enumerated or left to Z3."""
    from afsmc import check
    from afsmc.model import search

    path = str(ROOT / "tests" / "golden" / "cases" / case / "input.afsm")

    def run() -> list[tuple[str, str]]:
        loaded = load(path, run_checks=False)
        return [(d.code, d.message)
                for d in check.run(loaded.model, used_names=loaded.used_names)]

    enumerated = run()
    monkeypatch.setattr(search, "ENUMERATION_LIMIT", 0)
    monkeypatch.setattr(search, "SAMPLE_LIMIT", 0)
    assert run() == enumerated


def test_a_checked_model_pickles_without_its_caches() -> None:
    # A verify job sends the lowered model to a Storm child by pickling it: the checks'
    # shared sites (closures among them) must stay behind, and the child derive its own.
    import pickle

    from afsmc.compiler import lowered

    model = load(str(Path(__file__).parents[3] / "examples" / "patrol.afsm"), {}).model
    assert "check.sites" in model.memo.lookups
    low = lowered(model, "nondet")
    back = pickle.loads(pickle.dumps(low))
    assert back.model.memo.lookups == {}
    assert back.model.properties == model.properties
