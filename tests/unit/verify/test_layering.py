"""afsmc.verify.arrays.layering: a model whose clock buckets each hold a long chain (one
state per layer) is laid out again in its shallowest layering before the backward pass.
Oracles: the same model without it (every value to the bit, every strategy, policy and
witness path equal), and a closed form (a negative binomial sum, in exact rationals)."""

from __future__ import annotations

from fractions import Fraction
from math import comb
from pathlib import Path
from typing import Any

import pytest

from afsmc.verify.arrays import layering
from afsmc.verify.engines import explicit
from tests.unit.verify.test_streaming import CASES, _loops
from tests.unit.verify.test_streaming_extract import _same

pytestmark = pytest.mark.storm


def _grid(tmp: Path, n: int) -> str:
    """A counts up once per step of the clock-like `a`, 0.5 each: c is a chain within
    each value of a. q: c is still below n/2 when a reaches n."""
    path = tmp / "grid.afsm"
    path.write_text(f"""machine grid;
param int N = {n};
var a : [0..N] init 0;
var c : [0..N] init 0;
mode A = 0 initial;
mode B = 1 final;
action Inc in A when a < N {{ 0.5: a := a + 1; 0.5: c := min(c + 1, N); }}
action Stop in A when a >= N {{ goto B; }}
property q = P=? [ F mode == B & 2 * c < N ];
""", encoding="utf-8")
    return str(path)


def _closed_form(n: int) -> Fraction:
    # the number of c steps before the n-th a step is negative binomial (n, 1/2)
    return sum((Fraction(comb(n - 1 + k, k), 2 ** (n + k)) for k in range((n + 1) // 2)),
               Fraction(0))


def test_a_grid_of_chains_is_laid_out_again_and_gives_the_closed_form(tmp_path: Path) -> None:
    n = 150  # 22,801 states in about 22,650 layers of one state: past MIN_LAYERS
    low, names, _ = _low(_grid(tmp_path, n))
    said: list[str] = []
    got = explicit.answer(low, names, "DTMC", lambda e, d: said.append(str(d)))
    assert got is not None
    assert any("layers laid out again as" in s for s in said), said
    assert got.values["q"] == pytest.approx(float(_closed_form(n)), rel=1e-12)


def _low(path: str, consts: dict[str, str] | None = None) -> tuple[Any, tuple[str, ...], Any]:
    from afsmc.backends.prism import property_variants
    from afsmc.compiler import load, lowered

    low = lowered(load(path, consts or {}).model, "nondet")
    names = tuple(n for p in low.model.properties for n, _ in property_variants(low, p))
    return low, names, explicit.plan(low, names)


@pytest.mark.parametrize("case", [*CASES, "loops", "grid"])
def test_laid_out_again_every_value_strategy_and_path_is_the_same(
        case: str, tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    from afsmc.verify.engines.strategy_storm import WitnessRequest
    from afsmc.verify.outcome.strategy import extract_for

    path, consts = (_loops(tmp_path), {}) if case == "loops" else \
        (_grid(tmp_path, 30), {}) if case == "grid" else CASES[case]
    low, names, p = _low(path, consts)
    asked = [q for q in p.queries if q.kind in ("P", "R") and q.opt in ("min", "max")]
    probs = [q for q in asked if q.kind == "P"] or [q for q in p.queries if q.kind == "P"]
    ex = extract_for(low, tuple(q.name for q in asked), asked[0].name if asked else None,
                     WitnessRequest(probs[-1].name, 5))
    monkeypatch.setattr(layering, "MIN_LAYERS", 10**12)  # never
    want = explicit.answer(low, names, "MDP", lambda *_: None, extract=ex)
    monkeypatch.setattr(layering, "MIN_LAYERS", 0)  # always, where it gives fewer layers
    monkeypatch.setattr(layering, "MEAN_STATES", 10**12)
    said: list[str] = []
    got = explicit.answer(low, names, "MDP", lambda e, d: said.append(str(d)), extract=ex)
    assert want is not None and got is not None
    assert got.values == want.values  # to the bit
    _same(want.extracted, got.extracted)
    assert case not in ("uav", "rover", "grid") or any("laid out again" in s for s in said), said
