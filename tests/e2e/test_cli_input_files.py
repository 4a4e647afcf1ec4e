"""Reading the input: files, standard input, byte-order marks, bytes that are not UTF-8,
missing and empty files."""

from __future__ import annotations

from pathlib import Path

import pytest

from tests.conftest import run_cli
from tests.specs import BOM, SMALL


def test_missing_file_is_a_diagnostic_not_a_traceback(tmp_path: Path) -> None:
    result = run_cli("check", str(tmp_path / "nope.afsm"))
    assert result.code == 1
    assert "error[E001]: cannot read" in result.err


@pytest.mark.storm
def test_standard_input_where_a_command_needs_a_file() -> None:
    r = run_cli("verify", "-")
    assert r.code == 1
    assert "E001]: cannot read -: this command reads a file, not standard input" in r.err, r.err
    assert "'afsmc check -'" in r.err, r.err


@pytest.mark.slow
def test_check_takes_several_files_and_standard_input(tmp_path: Path) -> None:
    """`check a.afsm b.afsm` and `check -` work, as `fmt` takes both. One report for all
    of them; exit 1 if any has an error."""
    import subprocess
    import sys

    from tests.conftest import CASES, EXAMPLES, run_cli

    good = [str(EXAMPLES / "patrol.afsm"), str(EXAMPLES / "uav.afsm")]
    assert run_cli("check", *good).code == 0
    bad = CASES / "err_weight_tie" / "input.afsm"
    r = run_cli("check", *good, str(bad), str(tmp_path / "none.afsm"))
    assert r.code == 1 and "error[E301]" in r.err and "error[E001]" in r.err, r.err
    r = subprocess.run([sys.executable, "-m", "afsmc", "check", "-"], input=bad.read_text(),
                       capture_output=True, text=True, timeout=120)
    assert r.returncode == 1 and "<stdin>:6:43: error[E301]" in r.stderr, r.stderr
    # standard input is read as strictly as a file, and only once
    b = subprocess.run([sys.executable, "-m", "afsmc", "check", "-"],
                       input=b"machine m;\nmode A\xe9 = 0 initial;\n", capture_output=True,
                       timeout=120)
    assert b.returncode == 1 and b"<stdin>:2:7: error[E001]" in b.stderr, b.stderr
    assert run_cli("check", "-", "-").code == 2


@pytest.mark.storm
def test_verify_of_an_empty_file_names_the_file(tmp_path: Path) -> None:
    # E213 names file:1:1 in verify as in check, with or without --formula.
    from tests.conftest import run_cli

    path = tmp_path / "empty.afsm"
    path.write_text("", encoding="utf-8")
    for extra in ((), ("-f", "P=? [ F true ]")):
        r = run_cli("verify", str(path), *extra)
        assert r.code == 1 and f"{path}:1:1: error[E213]" in r.err, r.err


def test_a_leading_byte_order_mark_is_skipped(tmp_path: Path) -> None:
    path = tmp_path / "bom.afsm"
    path.write_text(BOM + SMALL, encoding="utf-8")
    assert run_cli("check", str(path)).code == 0
    bad = tmp_path / "bad.afsm"
    bad.write_text(BOM + "const int 5;\n", encoding="utf-8")
    r = run_cli("check", str(bad))
    assert r.code == 1 and f"{bad}:1:11: error[E101]: unexpected '5'" in r.err
    assert "\n 1 | const int 5;\n   |           ^\n" in r.err


def test_a_byte_that_is_not_utf8_is_shown_at_its_line(tmp_path: Path) -> None:
    """A Latin-1 'é' is E001 "is not UTF-8 text" at its line and column."""
    from tests.conftest import run_cli

    path = tmp_path / "lat.afsm"
    path.write_bytes(b"machine m;\n// caf\xe9\nmode A = 0 initial;\n")
    r = run_cli("check", str(path))
    assert r.code == 1 and f"{path}:2:7: error[E001]: cannot read {path}: byte 0xe9 is not " \
        "UTF-8 text" in r.err, r.err
    assert "save the file as UTF-8" in r.err and "Traceback" not in r.err
