"""A reachability property split by cause (afsmc.report.causes): the causes add up to
verify's own min and max, each cause's probability equals an independent check (the same
property on a model where every other way into the target is cut off, checked by the
ordinary route), and a small DTMC's causes equal their closed forms."""

from __future__ import annotations

import dataclasses
from collections.abc import Sequence

import pytest

from afsmc import verify
from afsmc.compiler import load, lowered
from afsmc.diagnostics import CompileError
from afsmc.lower.lowering import Branch, Command, Lowered
from afsmc.model import expr as E
from afsmc.model import ir
from afsmc.model.semantics import inline
from afsmc.report.causes import Cause, Split, split, split_all, why_not
from afsmc.verify import upper_bound
from afsmc.verify.core.api import ask
from tests.conftest import EXAMPLES

pytestmark = pytest.mark.storm

PATROL = str(EXAMPLES / "patrol.afsm")


def _prop(model: ir.Model, name: str) -> ir.Property:
    return next(p for p in model.properties if p.name == name)


def _post(e: E.Expr, updates: Sequence[tuple[str, E.Expr]]) -> E.Expr:
    new = dict(updates)

    def fn(n: E.Expr) -> E.Expr | None:
        if isinstance(n, E.CurrentMode):
            return new.get("mode")
        if isinstance(n, E.VarRef):
            return new.get(n.name)
        return None
    return E.transform(e, fn)


def restricted(low: Lowered, target: E.Expr, cause: Cause) -> Lowered:
    """`low` in which every step that would first enter `target` by another cause goes
    to a sink instead (a new flag, after which nothing moves): P [ F target ] of it is the
    probability of `cause` alone."""
    sunk = E.VarRef("restricted_sink", E.Type.BOOL)
    names = {m.name: m.number for m in low.model.modes}
    commands = []
    for cmd in low.commands:
        branches = []
        for b in cmd.branches:
            event = b.hazard if b.hazard is not None else cmd.action
            kind = "hazard" if b.hazard is not None or cmd.kind == "preemptive" else "action"
            during = cmd.action if b.hazard is not None else ""
            after = dict(b.updates).get("mode", E.CurrentMode())
            mine = (kind, event, during) == (cause.kind, cause.event, cause.during)
            same_mode = E.Binary("==", after, E.ModeVal(cause.mode, names[cause.mode]),
                                 E.Type.BOOL)
            other = E.conj(E.neg(target), _post(target, b.updates),
                           E.neg(same_mode) if mine else E.lit(True))
            ups = tuple((v, E.Ite(other, E.VarRef(v, E.Type.INT) if v != "mode"
                                  else E.CurrentMode(), x, E.Type.INT))
                        for v, x in b.updates)
            branches.append(dataclasses.replace(b, updates=(*ups, ("restricted_sink", other))))
        commands.append(dataclasses.replace(cmd, guard=E.conj(cmd.guard, E.neg(sunk)),
                                            branches=tuple(branches)))
    span = low.model.variables[0].span
    stay = Command("(sunk)", tuple(m.number for m in low.model.modes), sunk,
                   (Branch(E.lit(1), (), span),), span, kind="deadlock")
    flag = ir.Variable("restricted_sink", "restricted_sink", E.Type.BOOL, 0, 1, False, False,
                       span)
    model = dataclasses.replace(low.model, variables=(*low.model.variables, flag))
    return dataclasses.replace(low, model=model, commands=(*commands, stay))


def test_the_causes_of_fault_add_up_to_verifys_min_and_max() -> None:
    res = verify.run(PATROL, properties=["fault"], uniform=False)
    (p,) = res.properties
    model = load(PATROL).model
    splits: dict[str, Split] = {s.under: s for s in split(model, _prop(model, "fault"))}
    assert set(splits) == {"min", "max"}
    for under, want in (("min", p.min), ("max", p.max)):
        assert want is not None
        assert splits[under].summed == pytest.approx(want, abs=1e-9)
        assert splits[under].total == pytest.approx(want, abs=1e-9)
        # the hazard Fault, during each action that can be struck: nothing else halts
        assert {c.kind for c in splits[under].causes} == {"hazard"}
        assert {c.during for c in splits[under].causes} == {
            "Move", "GoDock", "Complete", "Charge", "Leave"}
    # the likeliest cause under both: a fault while moving
    assert splits["min"].causes[0].during == splits["max"].causes[0].during == "Move"


@pytest.mark.parametrize("name", ["fault", "finish"])
def test_each_cause_equals_the_property_restricted_to_it(name: str) -> None:
    # the uniform resolution: a DTMC, so that the restricted model has no choice of its own
    model = load(PATROL).model
    prop = _prop(model, name)
    low = lowered(model, "uniform")
    (s,) = split(model, prop, low=low)
    assert s.under == "value" and s.causes
    assert prop.path.target is not None and isinstance(prop.path, ir.Path)
    target = inline(prop.path.target, model)
    for c in s.causes:
        cut = restricted(low, target, c)
        got = ask(cut, {"q": f"P=? [ F {_printed(cut, target)} ]"}, bound=upper_bound(model),
                  what="restricted DTMC")
        assert got.failure is None, got.failure
        assert got.values["q"] == pytest.approx(c.probability, rel=1e-9, abs=1e-12), c


def _printed(low: Lowered, e: E.Expr) -> str:
    from afsmc.backends.prism import PrismPrinter, weight_formula_names

    return PrismPrinter(weight_formula_names(low), low).show(e, 0)


TINY = """
machine tiny;
const prob P_H = 0.1;
var n : [0..2] init 0;
mode Work = 0 initial;
mode Done = 1 final;
mode Broken = 2 final;
action Step in Work when n < 2 { 0.8: n += 1; 0.2: goto Broken; }
action Finish in Work when n == 2 { goto Done; }
hazard Crash from Work with probability P_H { goto Broken; }
property broken = P=? [ F mode == Broken ];
property over   = P=? [ F mode == Done || mode == Broken ];
"""


def test_a_small_dtmcs_causes_equal_their_closed_forms(tmp_path: object) -> None:
    model = load("tiny.afsm", {}, text=TINY).model
    got = split_all(model, [_prop(model, "broken"), _prop(model, "over")])
    (broken,) = got["broken"]
    by = {(c.kind, c.event, c.during): c.probability for c in broken.causes}
    # each step: the hazard with 0.1, else Step's outcome; two Steps, then Finish
    h, q = 0.1, 0.9
    step_ok = q * 0.8
    assert by[("hazard", "Crash", "Step")] == pytest.approx(h + step_ok * h, abs=1e-12)
    assert by[("action", "Step", "")] == pytest.approx(q * 0.2 + step_ok * q * 0.2, abs=1e-12)
    assert by[("hazard", "Crash", "Finish")] == pytest.approx(step_ok ** 2 * h, abs=1e-12)
    (over,) = got["over"]
    assert over.summed == pytest.approx(1.0, abs=1e-12)
    assert {c.mode for c in over.causes} == {"Done", "Broken"}
    done = [c for c in over.causes if c.mode == "Done"]
    assert [(c.kind, c.event, c.during) for c in done] == [("action", "Finish", "")]
    assert done[0].probability == pytest.approx(step_ok ** 2 * q, abs=1e-12)


PREEMPTED = """
machine clocked;
var t : [0..3] init 0;
mode Work = 0 initial;
mode Done = 1 final;
mode Late = 2 final;
action Step in Work when t < 3 { 0.5: t += 1; 0.5: goto Done; }
hazard TimeUp from Work when t >= 2 { goto Late; }
property late = P=? [ F mode == Late ];
"""


def test_a_preemptive_hazard_is_a_cause_of_its_own() -> None:
    # `hazard H from S when φ` preempts every action where φ holds: its own command
    model = load("clocked.afsm", {}, text=PREEMPTED).model
    (s,) = split(model, _prop(model, "late"))
    assert [(c.kind, c.event, c.during, c.mode) for c in s.causes] == [
        ("hazard", "TimeUp", "", "Late")]
    assert s.causes[0].probability == pytest.approx(0.25, abs=1e-12)  # two steps of t += 1


def test_properties_without_a_first_entry_are_refused_with_e417() -> None:
    model = load(PATROL).model
    for name in ("duration", "safe_soon", "finish_soon"):
        assert why_not(model, _prop(model, name)) is not None
        with pytest.raises(CompileError) as err:
            split(model, _prop(model, name))
        assert err.value.diagnostics[0].code == "E417"


def test_with_interval_probabilities_the_causes_are_the_midpoints(tmp_path: object) -> None:
    text = (EXAMPLES / "patrol.afsm").read_text(encoding="utf-8").replace(
        "const prob P_FAULT  = 0.01;", "const prob P_FAULT  = [0.005, 0.015];")
    res = verify.run("pint.afsm", text=text, properties=["fault"], uniform=False)
    (p,) = res.properties
    assert p.reference is not None and p.min is not None and p.max is not None
    model = load("pint.afsm", {}, text=text).model
    splits: dict[str, Split] = {s.under: s for s in split(model, _prop(model, "fault"))}
    for under, want in (("min", p.reference.min), ("max", p.reference.max)):
        assert splits[under].midpoint
        assert splits[under].summed == pytest.approx(want, abs=1e-9)
    # the bounds over the box are wider than the midpoint's: not what the causes add to
    assert p.min < splits["min"].summed and p.max > splits["max"].summed


def test_the_explorers_causes_and_paths_equal_storms(monkeypatch: pytest.MonkeyPatch) -> None:
    """afsmc's own exploration and backward pass (afsmc.report.causes_pass, the route of
    a mission whose clock only grows: the UAV's) and Storm's sparse engine on the same
    instrumented model give the same causes (20 of them into `emergency`), each to
    1e-12, and the same most probable paths into the largest cause, to the
    probabilities' last digits. (Patrol has cycles: Storm splits it.)"""
    from afsmc.report import causes, causes_pass

    model = load(str(EXAMPLES / "uav.afsm"), {"T_LIMIT": "90", "DEADLINE": "90"}).model
    props = [p for p in model.properties if why_not(model, p) is None]
    taken: list[bool] = []
    real = causes_pass.explored

    def spy(*args: object, **kw: object) -> object:
        got = real(*args, **kw)  # type: ignore[arg-type]
        taken.append(got is not None)
        return got

    monkeypatch.setattr(causes_pass, "explored", spy)
    ours = split_all(model, props, paths=3)
    assert taken == [True]
    monkeypatch.setattr(causes, "_explored", lambda *_a, **_k: None)
    storms = split_all(model, props, paths=3)
    assert ours.keys() == storms.keys()
    for name in ours:
        for a, b in zip(ours[name], storms[name], strict=True):
            assert a.under == b.under
            assert a.total == pytest.approx(b.total, abs=1e-12)
            assert [(c.kind, c.event, c.during, c.mode) for c in a.causes] == [
                (c.kind, c.event, c.during, c.mode) for c in b.causes]
            for x, y in zip(a.causes, b.causes, strict=True):
                assert x.probability == pytest.approx(y.probability, abs=1e-12)
            assert a.summed == pytest.approx(a.total, abs=1e-12)
            assert [w.probability for w in a.paths] == pytest.approx(
                [w.probability for w in b.paths], rel=1e-9)
            assert a.paths_note == b.paths_note


def test_a_causes_model_past_its_state_limit_is_e417_not_explored_on() -> None:
    """The report splits the causes beside the verification, each within its limits: a
    model past `max_states` stops the exploration with E417 and the count reached."""
    model = load(str(EXAMPLES / "uav.afsm"), {"T_LIMIT": "90", "DEADLINE": "90"}).model
    props = [p for p in model.properties if why_not(model, p) is None]
    with pytest.raises(CompileError) as err:
        split_all(model, props, max_states=500)
    (d,) = err.value.diagnostics
    assert d.code == "E417" and "more than --max-states 500" in d.message
