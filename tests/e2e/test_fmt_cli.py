"""`afsmc fmt` on the command line: --check, --diff, standard input, and writing in place
(permissions, owner, umask, line endings, no temporary file left behind)."""

from __future__ import annotations

import io
import os
import re
import sys
from pathlib import Path

import pytest

from afsmc.diagnostics import CompileError
from afsmc.syntax.fmt import format_text
from tests.conftest import EXAMPLES, run_cli


def test_cli_in_place_check_and_stdin(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    messy = tmp_path / "messy.afsm"
    original = "machine m;\nvar x:[0..2] init 0;\nmode A=0 initial;\naction Go in A when x<2 " \
               "{ x:=x+1; }  // count\naction Stay in A when x==2 { skip; }\n"
    messy.write_text(original)
    res = run_cli("fmt", "--check", str(messy))
    assert res.code == 1 and res.out.strip() == str(messy)
    assert messy.read_text() == original  # --check changes nothing

    res = run_cli("fmt", str(messy))
    assert res.code == 0
    assert messy.read_text() == format_text(original)
    assert "action Go in A when x < 2 {\n    x := x + 1;\n}  // count\n" in messy.read_text()
    assert run_cli("fmt", "--check", str(messy)).code == 0
    assert list(tmp_path.iterdir()) == [messy]  # no temporary file left behind

    monkeypatch.setattr(sys, "stdin", io.StringIO(original))
    res = run_cli("fmt", "-")
    assert res.code == 0 and res.out == format_text(original)


MESSY = ("machine m;\nvar x:[0..2] init 0;\nmode A=0 initial;\naction Go in A when x<2 "
         "{ x:=x+1; }  // count\naction Stay in A when x==2 { skip; }\n")


def test_in_place_keeps_the_permission_bits(tmp_path: Path) -> None:
    """write_atomic keeps the mode of what it replaces: a private file stays private (was
    reset to 0644)."""
    path = tmp_path / "private.afsm"
    path.write_text(MESSY)
    for mode in (0o600, 0o755):
        path.write_text(MESSY)
        path.chmod(mode)
        res = run_cli("fmt", str(path))
        assert res.code == 0 and "reformatted" in res.err
        assert path.read_text() == format_text(MESSY)
        assert path.stat().st_mode & 0o7777 == mode


@pytest.mark.skipif(os.geteuid() != 0, reason="only root can give a file to another user")
def test_in_place_keeps_the_owner(tmp_path: Path) -> None:
    """A `sudo afsmc fmt` in a user's checkout keeps the file the user's: given to root
    with mode 640, its owner could not read it."""
    path = tmp_path / "theirs.afsm"
    path.write_text(MESSY)
    path.chmod(0o640)
    os.chown(path, 65534, 65534)  # nobody
    res = run_cli("fmt", str(path))
    assert res.code == 0 and path.read_text() == format_text(MESSY), res.err
    st = path.stat()
    assert (st.st_uid, st.st_gid, st.st_mode & 0o7777) == (65534, 65534, 0o640)
    assert [p.name for p in tmp_path.iterdir()] == ["theirs.afsm"]  # no temporary file left


def test_a_new_output_gets_the_umask_mode(tmp_path: Path) -> None:
    """The temporary file is created 600 (exclusively, under a fresh name); the output it
    becomes has the mode a plain open() would give it."""
    out = tmp_path / "out"
    res = run_cli("compile", _messy(tmp_path), "-t", "prism", "-o", f"{out}/")
    assert res.code == 0, res.err
    mask = os.umask(0)
    os.umask(mask)
    assert {p.name: p.stat().st_mode & 0o777 for p in out.iterdir()} == {
        "m.prism": 0o666 & ~mask, "m.props": 0o666 & ~mask}


def test_a_stopped_write_leaves_no_temporary_file(tmp_path: Path,
                                                  monkeypatch: pytest.MonkeyPatch) -> None:
    """A Ctrl-C during the write left `.NAME.XXXX.tmp` behind: only an OSError
    removed it."""
    from afsmc.files import write_atomic

    def stop(fd: int) -> None:
        raise KeyboardInterrupt

    monkeypatch.setattr(os, "fsync", stop)
    with pytest.raises(KeyboardInterrupt):
        write_atomic(str(tmp_path / "out.prism"), "text\n")
    assert list(tmp_path.iterdir()) == []


def _messy(tmp_path: Path) -> str:
    path = tmp_path / "m.afsm"
    path.write_text(MESSY)
    return str(path)


def test_diff_shows_the_change_and_writes_nothing(tmp_path: Path) -> None:
    """`fmt --diff` (--check could not show what would change)."""
    path = tmp_path / "messy.afsm"
    path.write_text(MESSY)
    r = run_cli("fmt", "--diff", str(path))
    assert r.code == 0 and path.read_text() == MESSY, r.err
    assert r.out.startswith(f"--- {path} (as it is)\n+++ {path} (formatted)\n"), r.out
    assert "\n-var x:[0..2] init 0;\n" in r.out and "\n+var x : [0..2] init 0;\n" in r.out
    assert run_cli("fmt", "--diff", "--check", str(path)).code == 1
    path.write_text(format_text(MESSY))
    r = run_cli("fmt", "--diff", "--check", str(path))
    assert (r.code, r.out) == (0, ""), r.out
    # a last line without its newline is marked, so that the patch applies
    path.write_text(MESSY.rstrip("\n"))
    r = run_cli("fmt", "--diff", str(path))
    assert "-action Stay in A when x==2 { skip; }\n\\ No newline at end of file\n" in r.out
    patched = tmp_path / "patched.afsm"
    patched.write_text(MESSY.rstrip("\n"))
    import shutil
    import subprocess
    if shutil.which("patch"):
        done = subprocess.run(["patch", "-s", str(patched)], input=r.out, text=True,
                              capture_output=True, timeout=60)
        assert done.returncode == 0, done.stderr + done.stdout
        assert patched.read_text() == format_text(MESSY)


def test_in_place_keeps_crlf_line_endings(tmp_path: Path) -> None:
    """A CRLF file is rewritten with CRLF (as `sim-check --update` keeps them); LF stays LF;
    line endings alone do not make a file unformatted."""
    crlf = tmp_path / "crlf.afsm"
    crlf.write_bytes(MESSY.replace("\n", "\r\n").encode())
    assert run_cli("fmt", str(crlf)).code == 0
    assert crlf.read_bytes() == format_text(MESSY).replace("\n", "\r\n").encode()
    assert run_cli("fmt", "--check", str(crlf)).code == 0
    before = crlf.stat().st_mtime_ns
    res = run_cli("fmt", str(crlf))  # already formatted: not rewritten, not converted
    assert res.code == 0 and "reformatted" not in res.err and crlf.stat().st_mtime_ns == before

    lf = tmp_path / "lf.afsm"
    lf.write_bytes(MESSY.encode())
    assert run_cli("fmt", str(lf)).code == 0
    assert lf.read_bytes() == format_text(MESSY).encode()

    cr = tmp_path / "cr.afsm"  # old Mac line endings: kept too
    cr.write_bytes(MESSY.replace("\n", "\r").encode())
    assert run_cli("fmt", str(cr)).code == 0
    assert cr.read_bytes() == format_text(MESSY).replace("\n", "\r").encode()
    assert run_cli("fmt", "--check", str(cr)).code == 0


def test_syntax_error_leaves_the_file_alone(tmp_path: Path) -> None:
    bad = tmp_path / "bad.afsm"
    bad.write_text("var x : [0..2] init 0\nmode A;\n")
    res = run_cli("fmt", str(bad))
    assert res.code == 1
    assert "E102" in res.err and "bad.afsm:1" in res.err
    assert bad.read_text() == "var x : [0..2] init 0\nmode A;\n"
    with pytest.raises(CompileError):
        format_text(bad.read_text())


def test_examples_are_formatted() -> None:
    res = run_cli("fmt", "--check", *map(str, sorted(EXAMPLES.glob("*.afsm"))))
    assert res.code == 0, f"not formatted:\n{res.out}"


def test_trailing_blanks_inside_a_block_comment_are_dropped_not_refused(tmp_path: Path) -> None:
    """An editor's trailing spaces inside `/* ... */` made fmt refuse the file (E190, 'would
    lose or reorder a comment'): the layout strips them, and the safety check did not."""
    text = ("machine t;\n/* a \n   b\t\n */\nvar x : [0..1] init 0; // c  \nmode A initial;\n"
            "mode B final;\naction Go in A {\n    goto B;\n}\n")
    out = format_text(text)
    assert "/* a\n   b\n */\n" in out and "// c\n" in out
    assert format_text(out) == out
    crlf = tmp_path / "crlf.afsm"
    crlf.write_bytes(text.replace("\n", "\r\n").encode())
    assert run_cli("fmt", str(crlf)).code == 0
    assert crlf.read_bytes() == out.replace("\n", "\r\n").encode()


@pytest.mark.parametrize("eol", ["\r\n", "\r"])
def test_diff_of_a_crlf_file_is_in_its_line_endings(tmp_path: Path, eol: str) -> None:
    """`fmt --diff` writes the file's lines as they are and the formatted ones in the file's
    ending, as `fmt` would write them: a CRLF file's patch applies to it (its lines were
    compared and printed as LF, and patch refused them), and gives what `fmt` writes."""
    path = tmp_path / "crlf.afsm"
    raw = MESSY.replace("\n", eol)
    path.write_bytes(raw.encode())
    r = run_cli("fmt", "--diff", str(path))
    assert r.code == 0
    body = [line for line in re.findall(r"[^\r\n]*(?:\r\n|\r|\n)", r.out)
            if line[:1] in " -+" and not line.startswith(("---", "+++"))]
    assert body and all(line.endswith(eol) for line in body), body
    # one hunk over the whole (short) file: its old side is the file, its new side fmt's
    assert "".join(x[1:] for x in body if x[0] in " -") == raw
    in_place = tmp_path / "in_place.afsm"
    in_place.write_bytes(raw.encode())
    assert run_cli("fmt", str(in_place)).code == 0
    assert "".join(x[1:] for x in body if x[0] in " +").encode() == in_place.read_bytes()
    import shutil
    import subprocess
    if eol == "\r\n" and shutil.which("patch"):
        done = subprocess.run(["patch", "-s", str(path)], input=r.out.encode(),
                              capture_output=True, timeout=60)
        assert done.returncode == 0, done.stderr + done.stdout
        assert path.read_bytes() == in_place.read_bytes()
    # formatted already: no diff, whatever the endings
    assert run_cli("fmt", "--diff", str(in_place)).out == ""
