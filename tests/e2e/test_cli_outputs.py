"""Writing results: an output path under a regular file, a device or pipe as the output,
standard output that is full or closed."""

from __future__ import annotations

import os
from pathlib import Path

import pytest

from tests.conftest import EXAMPLES, run_cli

PATROL = str(EXAMPLES / "patrol.afsm")


def test_an_output_under_a_regular_file_says_that_it_is_not_a_directory(tmp_path: Path) -> None:
    blocker = tmp_path / "afile"
    blocker.write_text("mine\n")
    for sub in ("x.svg", "deeper/x.svg"):
        r = run_cli("diagram", PATROL, "-o", str(blocker / sub))
        assert r.code == 1, r.err
        assert f"E003]: cannot write {blocker / sub}: {blocker} is not a directory" in r.err, r.err
    assert blocker.read_text() == "mine\n"


@pytest.mark.storm
def test_an_output_that_is_a_device_or_pipe_is_written_into_not_replaced(tmp_path: Path) -> None:
    """`sweep -o /dev/null` writes into the device; renaming its temporary file over it would
    make the machine's /dev/null a regular file. A FIFO stands in for the device here."""
    import os
    import stat
    import threading

    fifo = tmp_path / "pipe"
    os.mkfifo(fifo)
    got: list[bytes] = []
    reader = threading.Thread(target=lambda: got.append(fifo.read_bytes()), daemon=True)
    reader.start()
    r = run_cli("sweep", str(EXAMPLES / "patrol.afsm"), "--const", "CELLS=1:2", "-p", "finish",
                "--jobs", "1", "-o", str(fifo))
    reader.join(timeout=60)
    assert r.code == 0, r.err
    assert stat.S_ISFIFO(os.stat(fifo).st_mode)  # still the pipe, not a file put in its place
    assert got and got[0].decode().startswith("CELLS,property,min,max")
    r = run_cli("compile", str(EXAMPLES / "patrol.afsm"), "-o", str(fifo))
    assert r.code == 2 and "not a directory or a regular file" in r.err


@pytest.mark.slow
@pytest.mark.storm
@pytest.mark.parametrize("command", [
    ["simulate", "--runs", "50", "--json"], ["simulate", "--runs", "50"],
    ["sweep", "--bound", "0:4", "-p", "finish_soon"], ["compile", "-o", "-"]])
@pytest.mark.parametrize("stdout", ["full", "closed"])
def test_results_that_cannot_reach_stdout_are_e003(command: list[str], stdout: str) -> None:
    """A full disk or a closed descriptor behind stdout is E003 and exit 1: no traceback, no
    'internal error' (exit 3), no exit 0 with the results silently lost. /dev/full stands in
    for the full disk."""
    import subprocess
    import sys

    from tests.conftest import EXAMPLES

    argv = [sys.executable, "-m", "afsmc.cli", command[0], str(EXAMPLES / "patrol.afsm"),
            *command[1:]]
    if stdout == "full":
        with open("/dev/full", "w") as full:
            r = subprocess.run(argv, stdout=full, stderr=subprocess.PIPE, text=True,
                               timeout=300)
        why = "No space left on device"
    else:
        # the child starts with descriptor 1 closed
        r = subprocess.run(argv, stderr=subprocess.PIPE, text=True, timeout=300,
                           preexec_fn=lambda: os.close(1))
        why = "standard output is closed"
    assert r.returncode == 1, r.stderr
    assert f"error[E003]: cannot write to standard output: {why}" in r.stderr, r.stderr
    assert "Traceback" not in r.stderr and "internal error" not in r.stderr
