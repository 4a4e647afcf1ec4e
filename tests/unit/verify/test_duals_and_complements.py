"""afsmc.verify.plan.queries: a bounded G asked as its dual, a Pmax as 1 - its complementary Pmin,
and the words the user sees for these internal queries."""

from __future__ import annotations

import pytest

from afsmc.model import expr as E
from afsmc.model import ir
from afsmc.verify.plan.queries import (
    DUAL,
    REST,
    TERMINATES,
    complements,
    dual,
    duals_of,
    kept_note,
    not_failed,
    query_text,
    readable,
    rewrite,
    unanswered,
)
from tests.unit.verify.models import TEXT, prop, tiny


def test_the_dual_of_a_bounded_g_is_a_bounded_f_of_the_negation_with_min_and_max_swapped() -> None:
    model = tiny()
    short = prop(model, "short")  # Pmin=? [ G<=3 "low" ]
    d = dual(short)
    assert d.name == DUAL + "short"
    assert d.opt == "max"
    assert isinstance(d.path, ir.Path) and isinstance(short.path, ir.Path)
    assert d.path.kind == "F"
    assert d.path.bound == short.path.bound
    assert d.path.target == E.neg(short.path.target)
    stay = dual(prop(model, "stay"))  # no min or max: both, as the MDP's variants
    assert stay.opt == ""


def test_duals_of_names_each_query_by_the_value_it_gives() -> None:
    model = tiny()
    got = duals_of(model.properties)
    assert got == {
        DUAL + "stay": ("stay", "stay as 1 - P [F<=k !φ]"),
        DUAL + "stay_min": ("stay_max", "stay_max as 1 - Pmin [F<=k !φ]"),
        DUAL + "stay_max": ("stay_min", "stay_min as 1 - Pmax [F<=k !φ]"),
        DUAL + "short": ("short", "short as 1 - Pmax [F<=k !φ]"),
    }


def test_a_pmax_whose_target_lies_in_a_final_mode_has_a_complement() -> None:
    model = tiny()
    comp = complements(model, model.properties)
    # `done` (mode == End) is final; `far` (x >= 4) is not; bounded G has no complement
    assert set(comp) == {"done_max", TERMINATES}
    rest = comp["done_max"]
    assert rest.name == REST + "done"
    assert (rest.kind, rest.opt) == ("P", "min")
    assert isinstance(rest.path, ir.Path) and rest.path.kind == "F" and rest.path.bound is None
    terminates = comp[TERMINATES]
    assert (terminates.name, terminates.opt) == (TERMINATES, "min")


def test_a_dtmc_has_no_complements() -> None:
    model = tiny(TEXT.replace("[1, 2]", "1"))  # no interval constant: a DTMC
    assert not model.is_nondeterministic
    assert complements(model, model.properties) == {}


def test_rewrite_asks_termination_once_and_each_complement_instead_of_its_pmax() -> None:
    model = tiny()
    comp = complements(model, model.properties)
    done, far = prop(model, "done"), prop(model, "far")
    queries = [(done, "done_min"), (done, "done_max"), (far, "far_max")]
    assert [n for _, n in rewrite(queries, comp)] == [
        "done_min", TERMINATES, REST + "done", "far_max"]
    # answered by its complement and termination: the Pmax counts as answered
    vals = {TERMINATES: 1.0, REST + "done": 0.2}
    assert unanswered(queries, vals, comp) == [(done, "done_min"), (far, "far_max")]
    # its complement failed: the Pmax is not asked either
    assert not_failed(queries, {REST + "done"}, comp) == [(done, "done_min"), (far, "far_max")]


def test_kept_note_gives_a_pmax_from_its_complement_only_if_every_path_ends() -> None:
    model = tiny()
    comp = complements(model, model.properties)
    ends = kept_note([("MDP", {"done_min": 0.5, TERMINATES: 1.0, REST + "done": 0.25})], comp)
    assert [d.message for d in ends] == [
        "answered before this:\n  done_min = 0.5 on the MDP\n  done_max = 0.75 on the MDP"]
    assert ends[0].code == "N412"
    open_ = kept_note([("MDP", {"done_min": 0.5, TERMINATES: 0.9, REST + "done": 0.25})], comp)
    assert [d.message for d in open_] == ["answered before this:\n  done_min = 0.5 on the MDP"]
    assert kept_note([("MDP", {})], comp) == []


def test_internal_query_names_are_worded_by_what_they_give() -> None:
    texts = {DUAL + "short": "short as 1 - Pmax [F<=k !φ]"}
    assert query_text(TERMINATES, texts) == "termination"
    assert query_text(REST + "done", texts) == "done_max as 1 - Pmin"
    assert query_text(DUAL + "short", texts) == "short as 1 - Pmax [F<=k !φ]"
    assert query_text("far", texts) == "far"
    assert readable(f"checking {REST}done, then {DUAL}short and {TERMINATES}", texts) == (
        "checking done_max as 1 - Pmin, then short as 1 - Pmax [F<=k !φ] and termination")


@pytest.mark.storm
def test_check_gives_a_bounded_g_as_one_minus_its_dual() -> None:
    from afsmc.verify import check

    model = tiny()
    got = check(model, [prop(model, "short")], isolate=False)
    short = got.properties[0]
    assert short.name == "short" and short.min is not None and short.max is None
    direct = dual(prop(model, "short"))  # Pmax=? [ F<=3 !"low" ], checked as a property
    hand = check(model, [ir.Property("hand", "P", "max", direct.path, None, direct.span)],
                 isolate=False)
    assert hand.properties[0].max is not None
    assert short.min == pytest.approx(1.0 - hand.properties[0].max, abs=1e-12)
