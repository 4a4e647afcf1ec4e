"""A data file stays inside the mission (issue 50): `from data` paths lie under the spec's
folder or `--data-root`, never reach a device, a FIFO or a link out, and are refused before
the file is opened; the file is read in bounded memory with a clear error past its limits;
no message prints the file's content unless it is a CSV header naming the columns."""

from __future__ import annotations

import json
import os
import stat
import subprocess
import sys
import time
import tracemalloc
from pathlib import Path

import pytest

from afsmc.compiler import load
from afsmc.simlib import datafile
from tests.conftest import ROOT, run_cli

SPEC = ("machine carry;\n"
        'const int T_X = [1, 3] from data "{path}" column duration;\n'
        "var t : [0..40] init 0 clamp;\n"
        "mode Carry = 0 initial; mode Done = 1 final;\n"
        "action Step in Carry when t < 20 {{ t += T_X; }} "
        "action Finish in Carry when t >= 20 {{ goto Done; }}\n"
        "property done = P=? [ F mode == Done ];\n")
SECRET = "root:x:0:0:hunter2:/root:/bin/bash"


def mission(folder: Path, path: str) -> Path:
    folder.mkdir(parents=True, exist_ok=True)
    spec = folder / "m.afsm"
    spec.write_text(SPEC.format(path=path))
    return spec


def durations(n: int = 200) -> str:
    return "run,duration\n" + "".join(f"{i},{1.5 + (i % 10) / 10}\n" for i in range(n))


def refused(spec: Path, code: str, *args: str) -> str:
    r = run_cli("sim-check", str(spec), *args)
    assert r.code == 1, r.out + r.err
    assert f"error[{code}]" in r.err and "m.afsm:2:24" in r.err and "^^^" in r.err, r.err
    assert SECRET not in r.err + r.out and "hunter2" not in r.err + r.out
    assert "Traceback" not in r.err
    return r.err


def test_an_absolute_path_outside_the_folder_is_refused(tmp_path: Path) -> None:
    err = refused(mission(tmp_path, "/etc/passwd"), "E515")
    assert "data file '/etc/passwd' of constant 'T_X' is outside the mission's folder" in err
    assert "root:" not in err


def test_a_path_up_and_out_is_refused_and_a_data_root_admits_it(tmp_path: Path) -> None:
    (tmp_path / "shared").mkdir()
    (tmp_path / "shared" / "t.csv").write_text(durations())
    spec = mission(tmp_path / "missions", "../shared/t.csv")
    err = refused(spec, "E515")
    assert f"outside the mission's folder {tmp_path.resolve() / 'missions'}" in err
    assert "--data-root" in err  # the hint names the way to widen it
    r = run_cli("sim-check", str(spec), "--json", "--data-root", str(tmp_path))
    assert r.code == 0, r.err
    assert json.loads(r.out)["constants"][0]["runs"] == 200
    # the root is where files may lie, not where paths start: another folder admits none
    (tmp_path / "other").mkdir()
    refused(spec, "E515", "--data-root", str(tmp_path / "other"))
    r = run_cli("sim-check", str(spec), "--data-root", str(tmp_path / "nothere"))
    assert r.code == 2 and "--data-root" in r.err and "is not a folder" in r.err


def test_a_link_out_is_refused_and_a_link_inside_is_followed(tmp_path: Path) -> None:
    outside = tmp_path / "outside.csv"
    outside.write_text(f"{SECRET}\n1,2\n")
    spec = mission(tmp_path / "m", "link.csv")
    (tmp_path / "m" / "link.csv").symlink_to(outside)
    err = refused(spec, "E515")
    assert "is a link to a file outside the mission's folder" in err
    (tmp_path / "m" / "link.csv").unlink()
    (tmp_path / "m" / "real.csv").write_text(durations())
    (tmp_path / "m" / "link.csv").symlink_to("real.csv")
    r = run_cli("sim-check", str(spec), "--json")
    assert r.code == 0, r.err


def test_a_device_is_refused_before_it_is_read(tmp_path: Path) -> None:
    spec = mission(tmp_path, "/dev/zero")
    refused(spec, "E515")
    err = refused(spec, "E516", "--data-root", "/")
    assert "data file '/dev/zero' of constant 'T_X' is a character device, not a regular " \
        "file" in err


def test_a_fifo_gets_a_clear_error_within_seconds(tmp_path: Path) -> None:
    spec = mission(tmp_path, "pipe.csv")
    os.mkfifo(tmp_path / "pipe.csv")
    started = time.monotonic()
    # a child process: a read of the FIFO would block it, never the test
    r = subprocess.run([sys.executable, "-m", "afsmc", "sim-check", str(spec)],
                       capture_output=True, text=True, timeout=60,
                       env={**os.environ, "PYTHONPATH": str(ROOT)})
    assert time.monotonic() - started < 30
    assert r.returncode == 1, r.stderr
    assert "error[E516]: data file 'pipe.csv' of constant 'T_X' is a FIFO (a named pipe), " \
        "not a regular file" in r.stderr
    assert stat.S_ISFIFO(os.stat(tmp_path / "pipe.csv").st_mode)


def test_a_first_line_that_is_no_csv_header_is_never_echoed(tmp_path: Path) -> None:
    (tmp_path / "notes.csv").write_text(f"{SECRET}\nsecond line\n")
    err = refused(mission(tmp_path, "notes.csv"), "E511")
    assert "its first line does not look like a CSV header" in err
    # a header's names are listed, with the closest one
    (tmp_path / "notes.csv").write_text("run,durations,time (s)\n1,2,3\n")
    err = refused(mission(tmp_path, "notes.csv"), "E511")
    assert "did you mean 'durations'? its columns (first line): 'run', 'durations', " \
        "'time (s)'" in err


@pytest.mark.parametrize(("lines", "says"), [
    (["run,duration", "1,2", "2,3,4", "3", "4,5"],
     "rows that do not match its header of 2 columns: line 3 has 3 fields; line 4 has 1 field"),
    (["run,duration,duration", "1,2,3"], "names column 'duration' 2 times (columns 2, 3)"),
])
def test_ragged_rows_and_a_column_named_twice_are_e517(tmp_path: Path, lines: list[str],
                                                        says: str) -> None:
    (tmp_path / "t.csv").write_text("\n".join(lines) + "\n")
    err = refused(mission(tmp_path, "t.csv"), "E517")
    assert says in err


def test_a_huge_value_is_e512_in_a_short_message(tmp_path: Path) -> None:
    (tmp_path / "t.csv").write_text("run,duration\n1,1e308\n2,2\n3,-1e300\n")
    err = refused(mission(tmp_path, "t.csv"), "E512")
    assert "line 2 (larger than 1e15); line 4 (larger than 1e15)" in err
    assert "000000000" not in err and "overflow" not in err.lower()


@pytest.mark.parametrize(("limit", "value", "says"), [
    ("MAX_BYTES", 1000, "is 0 MB, more than the 0 MB afsmc reads"),
    ("MAX_LINE", 100, "holds a line longer than 100 characters"),
    ("MAX_VALUES", 50, "holds more than 50 values, more than afsmc keeps"),
])
def test_a_file_past_a_limit_is_e510(tmp_path: Path, monkeypatch: pytest.MonkeyPatch,
                                     limit: str, value: int, says: str) -> None:
    monkeypatch.setattr(datafile, limit, value)
    text = durations() if limit != "MAX_LINE" else "run,duration\n" + "1," + "9" * 200 + "\n"
    (tmp_path / "t.csv").write_text(text)
    err = refused(mission(tmp_path, "t.csv"), "E510")
    assert says in err


def test_a_file_is_read_in_memory_bounded_by_its_column(tmp_path: Path) -> None:
    # 100,000 rows of 12 columns (about 6 MB): the rows as lists of strings took ~ 90 MB
    # (17 GB at 250 MB); only the named column's doubles are kept
    rows = 100_000
    (tmp_path / "t.csv").write_text(
        "run,duration," + ",".join(f"c{i}" for i in range(10)) + "\n"
        + "".join(f"{i},{i % 7}.25," + ",".join(["abc"] * 10) + "\n" for i in range(rows)))
    spec = mission(tmp_path, "t.csv")
    const = next(c for c in load(str(spec)).model.constants if c.name == "T_X")
    tracemalloc.start()
    try:
        values = datafile.read(str(spec), const, outcomes=False)
        _, peak = tracemalloc.get_traced_memory()
    finally:
        tracemalloc.stop()
    assert len(values) == rows and float(values[3]) == 3.25
    assert peak < 4 * 8 * rows + 2**20, peak


def test_the_python_api_takes_the_data_root(tmp_path: Path) -> None:
    import afsmc

    (tmp_path / "shared").mkdir()
    (tmp_path / "shared" / "t.csv").write_text(durations())
    mission_ = afsmc.load(str(mission(tmp_path / "missions", "../shared/t.csv")))
    with pytest.raises(afsmc.AfsmError) as caught:
        mission_.sim_check()
    assert [d.code for d in caught.value.diagnostics] == ["E515"]
    assert mission_.sim_check(data_root=str(tmp_path))["T_X"].runs == 200
