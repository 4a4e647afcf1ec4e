"""The symmetry reduction by default (afsmc.lower.symmetry.decide): applied where the
mission and the properties checked (after `-p`) treat the alike agents alike and no
output asked for names the agents; otherwise the mission is checked whole and the output
says why in one line (a note N421 only for `--symmetry`). The oracle of every value is
the mission checked whole (`--no-symmetry`): the same min and max within 1e-9, on fewer
states where the reduction applies. examples/fleet.afsm, three alike robots: 661 states
reduced, 3,324 whole."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

import afsmc
from afsmc.api.sweep import sweep_file
from afsmc.lower.reduce import Reductions
from afsmc.verify.core.api import run
from afsmc.verify.outcome.results import VerifyResult, symmetry_words
from tests.conftest import EXAMPLES, run_cli

FLEET = str(EXAMPLES / "fleet.afsm")
WHOLE = Reductions(symmetry="off")
FORCED = Reductions(symmetry="on")
# a property that reads one robot: it tells r1 from the others
ONE = "property one = P=? [ F r1.mode == Finished ];\n"


@pytest.fixture(scope="module")
def whole() -> VerifyResult:
    return run(FLEET, isolate=False, reductions=WHOLE)


@pytest.fixture
def with_one(tmp_path: Path) -> str:
    path = tmp_path / "fleet_one.afsm"
    path.write_text((EXAMPLES / "fleet.afsm").read_text(encoding="utf-8") + ONE,
                    encoding="utf-8")
    return str(path)


def _assert_same(whole: VerifyResult, other: VerifyResult) -> None:
    by_name = {p.name: p for p in whole.properties}
    assert other.properties
    for p in other.properties:
        w = by_name[p.name]
        for end in ("min", "max", "value"):
            a, b = getattr(w, end), getattr(p, end)
            assert (a is None) == (b is None), (p.name, end)
            assert a is None or abs(a - b) <= 1e-9, (p.name, end, a, b)


def _n421(res: VerifyResult) -> list[str]:
    return [d.message for d in res.warnings if d.code == "N421"]


@pytest.mark.storm
def test_symmetric_properties_are_reduced_by_default_with_the_whole_missions_values(
        whole: VerifyResult) -> None:
    res = run(FLEET, isolate=False)
    assert res.symmetry is not None and res.symmetry.groups == (("r1", "r2", "r3"),)
    assert res.symmetry.reason is None
    assert res.model.states * 4 < whole.model.states, (res.model.states, whole.model.states)
    assert whole.symmetry is None  # --no-symmetry: nothing to say
    _assert_same(whole, res)
    assert not _n421(res)


@pytest.mark.storm
def test_a_selected_symmetric_property_is_reduced_beside_an_asymmetric_one(
        with_one: str, whole: VerifyResult) -> None:
    reduced = run(FLEET, isolate=False, properties=["shift"])
    for options in (None, FORCED):  # the default, and --symmetry: no refusal either
        res = run(with_one, isolate=False, properties=["shift"], reductions=options)
        assert res.symmetry is not None and res.symmetry.reason is None
        assert res.model.states == reduced.model.states < whole.model.states
        assert not _n421(res)
        _assert_same(whole, res)


@pytest.mark.storm
def test_an_asymmetric_property_selected_checks_the_mission_whole_and_says_why(
        with_one: str, whole: VerifyResult) -> None:
    res = run(with_one, isolate=False, properties=["one", "shift"])
    assert res.symmetry is not None and res.symmetry.groups == ()
    assert res.symmetry.reason == "the property one tells r1 and r2 apart"
    assert res.model.states == whole.model.states
    assert not _n421(res)  # the default's refusal is the header's line, not a note
    forced = run(with_one, isolate=False, properties=["one", "shift"], reductions=FORCED)
    assert _n421(forced) == ["no symmetry reduction (the model was checked whole): the "
                             "property one tells r1 and r2 apart"]
    assert forced.model.states == whole.model.states
    _assert_same(forced, res)
    oracle = run(with_one, isolate=False, properties=["one", "shift"], reductions=WHOLE)
    _assert_same(oracle, res)


@pytest.mark.storm
@pytest.mark.parametrize(("asked", "says"), [
    ({"strategy": True}, "--strategy names the agents"),
    ({"witness": ("shift", 1)}, "--witness names the agents"),
])
def test_an_output_naming_the_agents_turns_it_off(
        asked: dict[str, object], says: str, whole: VerifyResult) -> None:
    res = run(FLEET, isolate=False, properties=["shift"], **asked)
    assert res.symmetry is not None and res.symmetry.groups == ()
    assert res.symmetry.reason is not None and res.symmetry.reason.startswith(says)
    assert res.model.states == whole.model.states
    assert not _n421(res)
    _assert_same(whole, res)


@pytest.mark.storm
def test_the_strategy_names_the_robots_themselves(whole: VerifyResult) -> None:
    """--symmetry with --strategy keeps the canonical order (slots); the default does not."""
    plain = run(FLEET, isolate=False, properties=["shift"], strategy=True)
    forced = run(FLEET, isolate=False, properties=["shift"], strategy=True, reductions=FORCED)
    assert plain.model.states == whole.model.states
    assert forced.model.states < whole.model.states
    assert forced.symmetry is not None and forced.symmetry.reason is None


@pytest.mark.storm
def test_verify_says_it_in_its_heading_and_its_json() -> None:
    text = run_cli("verify", FLEET, "-p", "shift")
    assert text.code == 0, text.err
    assert text.out.splitlines()[1].startswith(
        "symmetry: r1, r2, r3 checked in a canonical order")
    witness = run_cli("verify", FLEET, "-p", "shift", "--witness", "1")
    assert witness.code == 0, witness.err
    assert witness.out.splitlines()[1].startswith(
        "no symmetry reduction (the alike agents checked as they are): --witness names "
        "the agents")
    js = run_cli("verify", FLEET, "-p", "shift", "--json")
    assert json.loads(js.out)["symmetry"] == {"groups": [["r1", "r2", "r3"]], "reason": None}
    off = run_cli("verify", FLEET, "-p", "shift", "--json", "--no-symmetry")
    assert "symmetry" not in json.loads(off.out)


def test_symmetry_and_no_symmetry_exclude_each_other() -> None:
    r = run_cli("verify", FLEET, "--symmetry", "--no-symmetry")
    assert r.code == 2 and "not allowed with argument" in r.err


@pytest.mark.storm
def test_the_python_api_and_the_sweep_take_the_same_decision(whole: VerifyResult) -> None:
    res = afsmc.load(FLEET).verify(properties=["shift"])
    assert res.raw.symmetry is not None and res.raw.symmetry.groups == (("r1", "r2", "r3"),)
    assert res.answer().symmetry is not None
    reduced = res.raw.model.states
    assert reduced < whole.model.states
    swept = sweep_file(FLEET, "K", [2], properties="shift", jobs=1).raw
    assert [p.states for p in swept.points] == [reduced]
    assert [p.symmetry for p in swept.points] == [symmetry_words(res.raw.symmetry)]
    # the sweep's --json carries it at each point, as its schema publishes
    from tests.e2e.test_json_schemas import validate

    cli = run_cli("sweep", FLEET, "--const", "K=2:2", "-p", "shift", "--json")
    assert cli.code == 0, cli.err
    points = validate("sweep", cli.out)["points"]
    assert [p["symmetry"] for p in points] == [symmetry_words(res.raw.symmetry)]
    # and its CSV, in a column of its own: the states it counts are the reduced model's
    import csv
    import io

    table = run_cli("sweep", FLEET, "--const", "K=2:2", "-p", "shift")
    assert table.code == 0, table.err
    rows = list(csv.DictReader(io.StringIO(table.out)))
    assert [(r["states"], r["symmetry"]) for r in rows] == [
        (str(reduced), symmetry_words(res.raw.symmetry))]
    whole_csv = run_cli("sweep", FLEET, "--const", "K=2:2", "-p", "shift", "--no-symmetry")
    assert whole_csv.code == 0, whole_csv.err
    assert "symmetry" not in whole_csv.out.splitlines()[0].split(",")


def test_compile_applies_it_where_every_property_is_symmetric_and_says_so(
        with_one: str) -> None:
    prism = run_cli("compile", FLEET, "-o", "-")
    header = prism.out.splitlines()[2]
    assert header == ("// Exact reductions: dead-variable reset, variable order, symmetry "
                      "(r1, r2, r3) (afsmc compile --no-reduce: none; --no-symmetry: the "
                      "agents as they are).")
    assert run_cli("compile", FLEET, "-o", "-").out == prism.out  # byte-deterministic
    # the .props file holds every property: one of them breaks the symmetry
    refused = run_cli("compile", with_one, "-o", "-").out.splitlines()[2]
    assert refused.endswith("no symmetry: the property one tells r1 and r2 apart "
                            "(afsmc compile --no-reduce: none).")
    off = run_cli("compile", FLEET, "-o", "-", "--no-symmetry").out.splitlines()[2]
    assert "symmetry" not in off
    jani = json.loads(run_cli("compile", FLEET, "-t", "jani", "-o", "-").out)
    assert "symmetry (r1, r2, r3)" in jani["metadata"]["description"]
    assert afsmc.load(FLEET).compile("prism") == prism.out


@pytest.mark.storm
def test_the_report_keeps_the_robots_named_where_it_shows_strategies(
        whole: VerifyResult) -> None:
    from afsmc.report.case import build

    plays = build(FLEET, properties=["shift"], sensitivity=False, causes=False)
    assert plays.result.symmetry is not None and plays.result.symmetry.reason is not None
    assert plays.result.symmetry.reason.startswith("the report's strategies name the agents")
    assert plays.result.model.states == whole.model.states
    values = build(FLEET, properties=["shift"], sensitivity=False, causes=False,
                   worst_case=False)
    assert values.result.symmetry is not None and values.result.symmetry.reason is None
    assert values.result.model.states < whole.model.states
    _assert_same(whole, values.result)
