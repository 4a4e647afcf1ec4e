"""Usage errors exit 2 with the command's own usage: unknown commands and options, missing
arguments, outputs a command cannot write."""

from __future__ import annotations

from pathlib import Path

import pytest

from tests.conftest import EXAMPLES, run_cli


def test_usage_errors_exit_2() -> None:
    assert run_cli("check").code == 2
    assert run_cli("frobnicate").code == 2
    assert run_cli("check", "examples/patrol.afsm", "--const", "NOEQUALS").code == 2


PATROL = str(EXAMPLES / "patrol.afsm")


def test_compile_dot_to_a_picture_name_is_a_usage_error(tmp_path: Path) -> None:
    out = tmp_path / "x.svg"
    r = run_cli("compile", PATROL, "-t", "dot", "-o", str(out))
    assert r.code == 2 and "afsmc diagram" in r.err and "DOT text" in r.err, r.err
    assert not out.exists()
    # a .dot or .gv name is what -t dot writes
    r = run_cli("compile", PATROL, "-t", "dot", "-o", str(tmp_path / "x.gv"))
    assert r.code == 0 and (tmp_path / "x.gv").read_text().count("\ndigraph ") == 1, r.err


@pytest.mark.storm
def test_a_usage_error_shows_the_command_s_usage() -> None:
    """An unknown option of a command shows that command's usage, not afsmc's top-level one;
    a missing argument file is named, without a bare '[Errno 2] ...'."""
    from tests.conftest import EXAMPLES, run_cli

    r = run_cli("fmt", "--nope", str(EXAMPLES / "patrol.afsm"))
    assert r.code == 2 and "usage: afsmc fmt" in r.err and \
        "afsmc fmt: error: unrecognized arguments: --nope" in r.err, r.err
    r = run_cli("--nope", "fmt", str(EXAMPLES / "patrol.afsm"))  # before the command: afsmc's
    assert r.code == 2 and "afsmc: error: unrecognized arguments: --nope" in r.err, r.err
    r = run_cli("verify", str(EXAMPLES / "patrol.afsm"), "@no-such.args")
    assert r.code == 2 and "cannot read the argument file 'no-such.args': No such file" in \
        r.err and "Errno" not in r.err, r.err


def test_compile_to_an_empty_output_name_is_a_usage_error(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    # `-o ''` must not write ./.prism and ./.props, hidden files named by the suffix alone.
    monkeypatch.chdir(tmp_path)
    r = run_cli("compile", str(EXAMPLES / "patrol.afsm"), "-o", "")
    assert r.code == 2 and "-o: an empty name" in r.err, r.err
    assert list(tmp_path.iterdir()) == []
