"""Argument files (`@FILE`): split like a shell, read relative to the working directory,
refused when they are not text or include themselves."""

from __future__ import annotations

from pathlib import Path

import pytest

from afsmc.cli import build_parser
from afsmc.commands.common import overrides
from tests.conftest import EXAMPLES, run_cli


def test_an_argument_file_that_is_not_text_is_a_usage_error(tmp_path: Path) -> None:
    args = tmp_path / "bin.args"
    args.write_bytes(b"\xff\xfe")
    r = run_cli("check", "examples/patrol.afsm", f"@{args}")
    assert r.code == 2 and "Traceback" not in r.err and "is not text" in r.err
    r = run_cli(f"@{args}")
    assert r.code == 2 and "is not text" in r.err


@pytest.mark.storm
def test_argument_files_are_split_like_a_shell(tmp_path: Path) -> None:
    args = tmp_path / "a.args"
    args.write_text('# a preset\n--const "CELLS=2"  # quoted\n--const ROUNDS=1 --engine sparse\n'
                    "--formula 'P=? [ F \"done\" ]'\n")
    ns = build_parser().parse_args(["verify", "examples/patrol.afsm", f"@{args}"])
    assert overrides(ns) == {"CELLS": "2", "ROUNDS": "1"}
    assert ns.engine == "sparse" and ns.formula == ['P=? [ F "done" ]']
    assert run_cli("check", str(EXAMPLES / "patrol.afsm"), f"@{args}").code == 2  # --formula: verify's
    ok = tmp_path / "ok.args"
    ok.write_text('--const "CELLS=2"\n')
    assert run_cli("check", str(EXAMPLES / "patrol.afsm"), f"@{ok}").code == 0
    bad = tmp_path / "bad.args"
    bad.write_text('--const "CELLS=2\n')
    r = run_cli("check", str(EXAMPLES / "patrol.afsm"), f"@{bad}")
    assert r.code == 2 and "No closing quotation" in r.err


@pytest.mark.storm
def test_an_argument_file_that_includes_itself_is_a_usage_error(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """argparse expands @FILE inside argument files; a cycle would recurse until Python's
    limit (a traceback). Nested files without a cycle, and one file used twice side by
    side, still work."""
    (tmp_path / "self.args").write_text("@self.args\n")
    (tmp_path / "a.args").write_text("@b.args\n")
    (tmp_path / "b.args").write_text("--const CELLS=2\n@a.args\n")
    (tmp_path / "c.args").write_text("--engine sparse\n")
    (tmp_path / "d.args").write_text("--const CELLS=2\n@c.args\n")
    patrol = str(EXAMPLES / "patrol.afsm")
    monkeypatch.chdir(tmp_path)  # nested @files are read relative to the working directory
    for name, chain in (("self.args", "self.args"), ("a.args", "a.args -> b.args")):
        r = run_cli("check", patrol, f"@{name}")
        assert r.code == 2 and "Traceback" not in r.err, r.err
        assert f"includes itself (through {chain})" in r.err, r.err
    ns = build_parser().parse_args(["verify", patrol, "@d.args", "@c.args"])
    assert overrides(ns) == {"CELLS": "2"} and ns.engine == "sparse"


@pytest.mark.storm
def test_the_scenario_presets_still_read() -> None:
    ns = build_parser().parse_args(["verify", "examples/uav.afsm", f"@{EXAMPLES / 'uav-scenario1.args'}"])
    assert overrides(ns) == {"OBJECTS": "3", "T_LIMIT": "900", "DEADLINE": "900", "WIDTH": "7",
                             "HEIGHT": "7", "ALPHA": "0.085"}
