"""`compose interleaving fair;`: min and max over the fair schedulers only (every agent that
stays able to move eventually moves), against values worked out by hand.

starve.afsm: r1 works once and then wanders forever; r2 waits for the charger, is granted
it together with the station (a synchronised action) and then charges (P_PLUG: done,
else lost). An unfair scheduler moves only r1, so r2 never charges: Pmin F both_done = 0
and Pmax G !both_done = 1. A fair one must move r2, which can move from the start until it
has: Pmin = Pmax = P_PLUG, and G !both_done = 1 - P_PLUG. What a finite prefix decides
(F<=3) is the same over fair and all schedulers. Where r2 can move only now and then
(the station grants only while r1 is not away, and r1 comes and goes), it may be starved fairly (weak fairness): Pmin 0.
"""

from __future__ import annotations

import os

import pytest

from afsmc.compiler import load
from afsmc.diagnostics import CompileError
from afsmc.verify.core.api import run

HERE = os.path.dirname(__file__)
STARVE = os.path.join(HERE, "starve.afsm")
P_PLUG = 0.8

pytestmark = pytest.mark.storm


def _text(compose: str = "compose interleaving fair;") -> str:
    with open(STARVE, encoding="utf-8") as f:
        return f.read().replace("compose interleaving fair;", compose)


def _values(text: str) -> dict[str, tuple[float | None, float | None]]:
    pytest.importorskip("stormpy")
    res = run(STARVE, text=text, uniform=False)
    return {p.name: (p.min, p.max) for p in res.properties}


def test_fairness_keeps_the_waiting_robot_from_starving() -> None:
    fair = _values(_text())
    assert fair["both_done"] == pytest.approx((P_PLUG, P_PLUG), abs=1e-6)
    assert fair["stays_away"] == pytest.approx((1 - P_PLUG, 1 - P_PLUG), abs=1e-6)
    unfair = _values(_text("compose interleaving;"))
    assert unfair["both_done"] == pytest.approx((0, P_PLUG), abs=1e-6)
    assert unfair["stays_away"] == pytest.approx((1 - P_PLUG, 1), abs=1e-6)
    # a prefix decides F<=3: the same over fair schedulers as over all
    assert fair["soon"] == unfair["soon"] == pytest.approx((0, P_PLUG), abs=1e-6)


def test_an_agent_able_to_move_only_now_and_then_may_be_starved() -> None:
    text = (_text()
            .replace("action Wander in Roam { goto Roam; }",
                     "action Wander in Roam { goto Away; }\n    mode Away = 2;\n"
                     "    action Back in Away { goto Roam; }")
            .replace("sync action Grant in Free { goto Busy; }",
                     "sync action Grant in Free when r1.mode == Roam { goto Busy; }"))
    values = _values(text)
    assert values["both_done"] == pytest.approx((0, P_PLUG), abs=1e-6)


def test_fairness_is_a_rule_of_the_interleaving() -> None:
    with pytest.raises(CompileError) as info:
        load("s.afsm", {}, text=_text("compose timed fair;"))
    assert "'fair' is a rule of the interleaving, not of the timed composition" in [
        d.message for d in info.value.diagnostics]
    model = load("s.afsm", {}, text=_text()).model
    assert model.composition is not None and model.composition.text == "interleaving, fair"


@pytest.mark.parametrize("options", [{"via": "jani"}, {"engine": "dd"}, {"exact": True}])
def test_what_fairness_is_not_computed_with_is_refused(options: dict[str, object]) -> None:
    pytest.importorskip("stormpy")
    with pytest.raises(CompileError) as info:
        run(STARVE, text=_text(), **options)
    (d,) = info.value.diagnostics
    assert d.code == "E404" and d.message.startswith(
        "min and max over fair schedulers ('compose interleaving fair') are computed on the "
        "sparse engine via PRISM")
