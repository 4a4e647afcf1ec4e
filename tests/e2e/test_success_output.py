"""Success is said, not left to silence: `afsmc check` on a clean file prints a one-line
summary, and `fmt --check` says what would change (and `--diff` shows it)."""

from __future__ import annotations

from pathlib import Path

from tests.conftest import EXAMPLES, run_cli

PATROL = str(EXAMPLES / "patrol.afsm")
MESSY = ("machine m;\nvar x:[0..2] init 0;\nmode A=0 initial;\nmode B=1 final;\n"
         "action Go in A when x<2 { x:=x+1; }\naction Stop in A when x==2 { goto B; }\n")


def test_check_of_a_clean_file_prints_one_summary_line() -> None:
    r = run_cli("check", PATROL)
    assert r.code == 0 and r.out == ""
    assert r.err == (f"{PATROL}: no errors, no warnings (machine patrol: 4 modes, "
                     "3 variables, 6 properties)\n")
    two = run_cli("check", PATROL, str(EXAMPLES / "uav.afsm"))
    assert two.code == 0 and two.err == "2 files: no errors, no warnings\n"


def test_check_with_warnings_ends_with_the_counts_not_the_clean_line(tmp_path: Path) -> None:
    f = tmp_path / "w.afsm"
    f.write_text(MESSY.replace("machine m;", "machine m;\nconst int UNUSED = 1;"))
    r = run_cli("check", str(f))
    assert r.code == 0 and "W30" in r.err
    assert r.err.rstrip().endswith("0 error(s), 1 warning(s)")
    assert "no errors, no warnings" not in r.err


def test_machine_readable_check_output_has_no_summary_line() -> None:
    r = run_cli("check", "--json", PATROL)
    assert r.out.strip() == "[]" and r.err == ""


def test_fmt_check_says_which_lines_would_change_and_how_to_see_them(tmp_path: Path) -> None:
    f = tmp_path / "messy.afsm"
    f.write_text(MESSY)
    r = run_cli("fmt", "--check", str(f), PATROL)
    assert r.code == 1
    assert r.out == f"{f}\n"  # the list of files, for scripts, as before
    assert (f"afsmc: {f}: the layout of 5 lines would change (lines 2-6); "
            f"'afsmc fmt --diff {f}' shows how, 'afsmc fmt {f}' rewrites it") in r.err
    assert r.err.rstrip().endswith("afsmc: 1 of 2 files would be reformatted")
    diff = run_cli("fmt", "--diff", str(f))
    assert diff.out.startswith(f"--- {f} (as it is)\n+++ {f} (formatted)\n@@ ")
    assert "-var x:[0..2] init 0;\n" in diff.out and "+var x : [0..2] init 0;\n" in diff.out
    assert f.read_text() == MESSY  # neither writes


def test_fmt_check_of_formatted_files_says_so() -> None:
    r = run_cli("fmt", "--check", PATROL)
    assert r.code == 0 and r.out == ""
    assert r.err == "afsmc: 1 file checked, all formatted\n"
