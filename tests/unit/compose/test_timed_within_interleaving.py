"""The timed composition only restricts which agent moves next, so its values lie within
the interleaving composition's min and max, on every reachability property (the two-UAV
mission of examples/, small)."""

from __future__ import annotations

import os

import pytest

from afsmc.verify.core.api import run
from tests.conftest import ROOT

PATH = os.path.join(ROOT, "examples", "two_uav.afsm")
SMALL = {"OBJECTS": 1, "T_LIMIT": 25}


def _values(compose: str) -> dict[str, tuple[float, float]]:
    with open(PATH, encoding="utf-8") as f:
        text = f.read().replace("compose timed ties order;", compose)
    result = run(PATH, text=text, consts=SMALL, uniform=False)
    out = {}
    for r in result.properties:
        if r.kind == "P":
            lo = r.min if r.min is not None else r.value
            hi = r.max if r.max is not None else r.value
            assert lo is not None and hi is not None
            out[r.name] = (lo, hi)
    return out


@pytest.mark.storm
@pytest.mark.slow
def test_timed_values_lie_between_the_interleaving_min_and_max() -> None:
    pytest.importorskip("stormpy")
    loose = _values("compose interleaving;")
    assert set(loose) == {"success", "all_home", "lost"}
    for timed in ("compose timed ties order;", "compose timed ties nondet;"):
        for name, (lo, hi) in _values(timed).items():
            assert loose[name][0] - 1e-6 <= lo <= hi <= loose[name][1] + 1e-6, (timed, name)
    # and the interleaving's freedom matters here: its range is wider than the timed one's
    order = _values("compose timed ties order;")
    assert any(loose[n][1] - loose[n][0] > order[n][1] - order[n][0] + 1e-6 for n in loose)
