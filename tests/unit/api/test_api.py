"""The Python API without Storm: loading, errors, compiling, the diagram, and that its
defaults are the CLI's."""

from __future__ import annotations

import argparse
import dataclasses
import inspect
import json
from pathlib import Path

import pytest

import afsmc
from afsmc import verify as lib
from afsmc.api.results import VERIFY_DEFAULTS, Results
from afsmc.commands.simulate import add_arguments as simulate_arguments
from afsmc.commands.verify import add_storm_options
from afsmc.model import ir
from afsmc.verify.outcome.results import ModelStats, PropertyResult, VerifyResult
from afsmc.verify.outcome.verdicts import judge
from tests.conftest import EXAMPLES, run_cli

PATROL = str(EXAMPLES / "patrol.afsm")
BROKEN = "machine m;\nvar x : [0..3] init 0\nmode A = 0 initial final;\n"


def test_load_a_path_or_a_text_gives_the_same_mission() -> None:
    by_path = afsmc.load(PATROL)
    by_text = afsmc.load(Path(PATROL).read_text(encoding="utf-8"))
    assert by_path.name == by_text.name == "patrol"
    assert by_path.properties == by_text.properties == [
        "finish", "fault", "finish_soon", "safe_soon", "charges", "duration"]
    assert by_text.path == "<text>"
    assert afsmc.load(Path(PATROL)).constants == {"CELLS": 4, "ROUNDS": 3}


def test_with_consts_sets_open_constants_and_keeps_the_others() -> None:
    m = afsmc.load(PATROL, consts={"ROUNDS": 2}).with_consts(CELLS=6)
    assert m.constants == {"CELLS": 6, "ROUNDS": 2}
    assert afsmc.load(PATROL).constants == {"CELLS": 4, "ROUNDS": 3}  # unchanged


def test_a_broken_file_raises_afsm_error_with_the_diagnostics_of_check(tmp_path: Path) -> None:
    f = tmp_path / "broken.afsm"
    f.write_text(BROKEN)
    with pytest.raises(afsmc.AfsmError) as info:
        afsmc.load(str(f))
    cli = run_cli("check", "--json", str(f))
    assert cli.code == 1
    assert [d.to_json() for d in info.value.diagnostics] == json.loads(cli.out)
    assert str(info.value) == cli_text(f)
    html = info.value._repr_html_()
    assert html.startswith("<pre") and "E102" in html and "error(s)" in html


def cli_text(f: Path) -> str:
    """What `afsmc check` prints on standard error, without its summary line's extras."""
    err = run_cli("check", str(f)).err.rstrip("\n")
    return err


def test_the_error_html_escapes_the_source(tmp_path: Path) -> None:
    with pytest.raises(afsmc.AfsmError) as info:
        afsmc.load("machine m;\nvar x : [0..3] init 0;\nmode A = 0 initial;\n"
                   "action a in A when x <<< 1 { x := 1; }\n")
    html = info.value._repr_html_()
    assert "&lt;&lt;&lt;" in html and "<<<" not in html


def test_an_unreadable_path_raises_afsm_error() -> None:
    with pytest.raises(afsmc.AfsmError) as info:
        afsmc.load("no/such/file.afsm")
    assert info.value.diagnostics[0].code == "E001"


def test_check_returns_the_warnings_check_prints(tmp_path: Path) -> None:
    f = tmp_path / "w.afsm"
    f.write_text("machine m;\nconst int UNUSED = 3;\nvar x : [0..3] init 0;\n"
                 "mode A = 0 initial;\nmode B = 1 final;\naction go in A { goto B; }\n")
    warnings = afsmc.load(str(f)).check()
    assert warnings, "the file has an unused constant"
    assert [d.to_json() for d in warnings] == json.loads(run_cli("check", "--json", str(f)).out)


@pytest.mark.parametrize("target", ["prism", "jani", "dot"])
def test_compile_is_compile_to_stdout(target: str) -> None:
    cli = run_cli("compile", PATROL, "-t", target, "-o", "-")
    assert cli.code == 0
    assert afsmc.load(PATROL).compile(target) == cli.out


def test_compile_refuses_an_unknown_target() -> None:
    with pytest.raises(ValueError, match="target must be one of"):
        afsmc.load(PATROL).compile("promela")


def test_the_diagram_is_the_picture_diagram_draws(tmp_path: Path) -> None:
    d = afsmc.load(PATROL).diagram()
    svg = d._repr_svg_()
    assert svg.lstrip().startswith("<?xml") and "<svg" in svg and "Patrol" in svg
    cli_svg = tmp_path / "cli.svg"
    assert run_cli("diagram", PATROL, "-o", str(cli_svg)).code == 0
    api_svg = d.save(tmp_path / "api.svg")
    assert Path(api_svg).read_bytes() == cli_svg.read_bytes()
    d.save(tmp_path / "api.gv")
    assert (tmp_path / "api.gv").read_text() == d.source
    assert "digraph patrol {" in d.source


def _defaults(add: object) -> dict[str, object]:
    p = argparse.ArgumentParser()
    add(p)  # type: ignore[operator]
    return {a.dest: a.default for a in p._actions}


def test_verify_defaults_are_the_cli_defaults() -> None:
    cli = _defaults(add_storm_options)
    fields = {f.name: f.default for f in dataclasses.fields(lib.VerifyOptions)}
    api = {**fields, **VERIFY_DEFAULTS}
    # the options of `afsmc verify` and the run() arguments they become
    for option, arg in [("via", "via"), ("engine", "engine"), ("solver", "solver"),
                        ("uniform", "uniform"), ("max_states", "max_states"),
                        ("bisim", "bisimulation"), ("split", "split"), ("scratch", "scratch"),
                        ("no_scratch", "no_scratch")]:
        assert api[arg] == cli[option], option


def test_simulate_defaults_are_the_cli_defaults() -> None:
    from afsmc.api.simulate import simulate

    cli = _defaults(simulate_arguments)
    api = {k: v.default for k, v in inspect.signature(simulate).parameters.items()}
    for option, arg in [("runs", "runs"), ("seed", "seed"), ("resolve", "resolve"),
                        ("confidence", "confidence"), ("max_steps", "max_steps"),
                        ("jobs", "jobs"), ("batch_size", "batch_size"), ("traces", "traces"),
                        ("at", "at"), ("strategy", "strategy")]:
        assert api[arg] == cli[option], option


def test_sim_check_defaults_are_the_cli_defaults() -> None:
    from afsmc.api.sim_check import sim_check
    from afsmc.commands.sim_check import add_arguments as sim_check_arguments

    cli = _defaults(sim_check_arguments)
    api = {k: v.default for k, v in inspect.signature(sim_check).parameters.items()}
    for option in ("runs", "seed", "timeout", "update"):
        assert api[option] == cli[option], option


def _result(props: list[PropertyResult]) -> Results:
    stats = ModelStats("dtmc", "nondet", 3, 4, 0, 0.0, 0.0, 0.0, "sparse")
    return Results(VerifyResult("m.afsm", "m", {}, "prism", "auto", 3, 10, stats, None,
                                props, 0.0, 0.0))


def test_to_pandas_has_a_row_per_property_and_a_verdict_column() -> None:
    plain = _result([PropertyResult("a", "P=? [ F \"x\" ]", "P", value=0.5),
                     PropertyResult("b", "R=? [ F \"x\" ]", "R", value=float("inf"))])
    df = plain.to_pandas()
    assert list(df.index) == ["a", "b"]
    assert list(df.columns) == ["formula", "kind", "min", "max", "uniform", "value", "verdict"]
    assert df.loc["a", "value"] == 0.5 and df.loc["b", "value"] == float("inf")
    assert df["verdict"].isna().all()  # `=?` properties have none
    threshold = ir.Threshold(">=", 0.9, "0.9")
    judged = _result([PropertyResult("a", "P>=0.9 [ F \"x\" ]", "P", value=0.5,
                                     threshold=threshold,
                                     verdict=judge(threshold, 0.5, 0.5, 1e-6))])
    df = judged.to_pandas()
    assert df.loc["a", "verdict"] == "fails"
    assert "fails" in judged._repr_html_()
