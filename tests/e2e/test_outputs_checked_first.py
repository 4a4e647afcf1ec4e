"""An output that cannot be written is refused before the work, as E003 and exit 1: an
empty name, the always-full /dev/full, a directory two levels missing, a directory that
refuses new files, a picture in a format afsmc does not draw, a read-only file; no exit 3
after the computation, and no directories made beyond the file's own."""

from __future__ import annotations

import os
import shutil
import stat
import time
from pathlib import Path

import pytest

from afsmc.diagnostics import CompileError
from afsmc.files import check_writable, write_atomic
from tests.conftest import EXAMPLES, run_cli

PATROL = str(EXAMPLES / "patrol.afsm")
REQUIRE = 'P>=0.5 [ F "done" ]'


def _refused(argv: list[str], said: str) -> None:
    t0 = time.monotonic()
    r = run_cli(*argv)
    assert r.code == 1, (r.code, r.err)
    assert "E003]" in r.err and said in r.err, r.err
    assert "internal error" not in r.err
    assert time.monotonic() - t0 < 30  # before the checks: no Storm run, no simulation


@pytest.mark.parametrize("argv", [
    ["verify", PATROL, "--junit", ""],
    ["verify", PATROL, "--witness", "2", "-p", "done", "--traces-out", ""],
    ["regions", PATROL, "--require", REQUIRE, "--param", "P_SLIP=0:0.2", "--plot", ""],
    ["sweep", PATROL, "--const", "CELLS=1:3", "--plot", ""],
    ["diagram", PATROL, "--reach", "-o", ""],
], ids=["verify-junit", "verify-traces-out", "regions-plot", "sweep-plot", "diagram-o"])
def test_an_empty_output_name_is_refused_not_silently_skipped(argv: list[str]) -> None:
    _refused(argv, "the file name is empty")


@pytest.mark.parametrize("argv", [
    ["verify", PATROL, "--junit", "/dev/full"],
    ["sweep", PATROL, "--const", "CELLS=1:3", "-o", "/dev/full"],
    ["simulate", PATROL, "--traces", "1", "--traces-out", "/dev/full"],
], ids=["verify-junit", "sweep-o", "simulate-traces-out"])
def test_the_full_device_is_refused_before_the_checks(argv: list[str]) -> None:
    if not os.path.exists("/dev/full"):
        pytest.skip("no /dev/full on this system")
    _refused(argv, "the device is always full")


def test_a_picture_format_afsmc_does_not_draw_is_refused_before_the_regions(
        tmp_path: Path) -> None:
    """A usage error (exit 2), as `diagram -o x.bmp` and `sweep --plot x.gif` are."""
    out = tmp_path / "r.bmp"
    for argv in (["regions", PATROL, "--require", REQUIRE, "--param", "P_SLIP=0:0.2"],
                 ["sweep", PATROL, "--const", "CELLS=1:3"]):
        t0 = time.monotonic()
        r = run_cli(*argv, "--plot", str(out))
        assert r.code == 2 and f"--plot {out}: the name must end in .png or .svg" in r.err, r.err
        assert time.monotonic() - t0 < 30
    assert not out.exists()


def test_a_missing_directory_is_refused_and_none_is_created(tmp_path: Path) -> None:
    deep = tmp_path / "no" / "such" / "x.xml"
    _refused(["verify", PATROL, "--junit", str(deep)],
             f"the directory {tmp_path / 'no'} does not exist")
    _refused(["compile", PATROL, "-o", str(tmp_path / "a" / "b") + "/"],
             f"the directory {tmp_path / 'a'} does not exist")
    assert sorted(os.listdir(tmp_path)) == []


def test_the_files_own_directory_is_still_created(tmp_path: Path) -> None:
    r = run_cli("compile", PATROL, "-o", str(tmp_path / "out") + "/")
    assert r.code == 0, r.err
    assert sorted(os.listdir(tmp_path / "out")) == ["patrol.prism", "patrol.props"]


def test_a_directory_that_refuses_files_is_refused(tmp_path: Path) -> None:
    blocker = tmp_path / "afile"
    blocker.write_text("mine\n")
    _refused(["verify", PATROL, "--junit", str(blocker / "x.xml")],
             f"{blocker} is not a directory")
    if os.path.isdir("/proc"):  # no file can be made there, not even by root
        _refused(["verify", PATROL, "--junit", "/proc/afsmc-x.xml"], "cannot create files in /proc")


def _read_only(path: Path) -> None:
    path.chmod(stat.S_IRUSR | stat.S_IRGRP | stat.S_IROTH)


def test_fmt_leaves_a_read_only_file_as_it_is(tmp_path: Path) -> None:
    spec = tmp_path / "m.afsm"
    text = "machine m;\nmode A = 0   initial final;\n"  # fmt would change the spacing
    spec.write_text(text)
    _read_only(spec)
    r = run_cli("fmt", str(spec))
    assert r.code == 1 and "E003]" in r.err and "the file is read-only" in r.err, r.err
    assert spec.read_text() == text
    assert stat.S_IMODE(spec.stat().st_mode) == 0o444
    spec.chmod(0o644)  # writable again: now fmt rewrites it
    assert run_cli("fmt", str(spec)).code == 0
    assert spec.read_text() != text


def test_a_read_only_output_is_not_replaced(tmp_path: Path) -> None:
    out = tmp_path / "report.xml"
    out.write_text("keep\n")
    _read_only(out)
    _refused(["verify", PATROL, "--junit", str(out)], "the file is read-only")
    assert out.read_text() == "keep\n"


def test_update_of_a_read_only_spec_is_refused_before_the_runs(tmp_path: Path) -> None:
    spec = tmp_path / "uav.afsm"
    shutil.copy(EXAMPLES / "uav.afsm", spec)
    _read_only(spec)
    _refused(["sim-check", str(spec), "--update", "--runs", "1000000"], "the file is read-only")
    _refused(["conform", str(spec), str(tmp_path / "log.jsonl"), "--update"],
             "the file is read-only")


def test_check_writable_says_what_write_atomic_would(tmp_path: Path) -> None:
    """The up-front check and the write agree: each path it refuses, the write refuses."""
    bad = ["", "   ", str(tmp_path / "x" / "y" / "z.txt")]
    for path in bad:
        for attempt in (lambda p: check_writable(p), lambda p: write_atomic(p, "text\n")):
            with pytest.raises(CompileError) as exc:
                attempt(path)
            assert exc.value.diagnostics[0].code == "E003"
    assert not (tmp_path / "x").exists()
    check_writable(str(tmp_path / "new" / "z.txt"))  # one level: the file's own directory
    write_atomic(str(tmp_path / "new" / "z.txt"), "text\n")
    assert (tmp_path / "new" / "z.txt").read_text() == "text\n"


def test_a_pipe_that_no_process_reads_is_an_error_not_a_wait(tmp_path: Path) -> None:
    fifo = tmp_path / "pipe"
    os.mkfifo(fifo)
    t0 = time.monotonic()
    with pytest.raises(CompileError) as exc:
        write_atomic(str(fifo), "text\n")
    assert "a pipe that no process reads" in exc.value.diagnostics[0].message
    assert time.monotonic() - t0 < 5
    assert stat.S_ISFIFO(os.stat(fifo).st_mode)
