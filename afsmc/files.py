"""Reading inputs and writing outputs, the only place that opens a user's files.

`read_source` reads an .afsm file as UTF-8 (E001 with the offending byte otherwise), and
no more of it than afsmc reads (E004 past MAX_SOURCE_CHARS);
`write_atomic` writes an output whole or not at all, never over an input (E002, E003).
"""

from __future__ import annotations

import contextlib
import errno
import os
import stat
import tempfile

from afsmc.diagnostics import CompileError, Diagnostic, Severity, Source, Span, codes
from afsmc.syntax.limits import MAX_SOURCE_CHARS


def read_source(path: str, *, newline: str | None = None) -> str:
    """The file's text; line endings read as '\n' (`newline=""`: as they are)."""
    try:
        with open(path, encoding="utf-8", newline=newline) as f:
            text = f.read(MAX_SOURCE_CHARS + 1)  # a larger file is refused unread
    except FileNotFoundError:
        if path == "-":  # the commands that read standard input handle '-' before this
            raise CompileError([Diagnostic(
                codes.E001, Severity.ERROR, "cannot read -: this command reads a file, not "
                "standard input", None, hint="'afsmc check -' and 'afsmc fmt -' read standard "
                "input; save the model to a file for the others")]) from None
        raise CompileError([_io_error(path, "no such file")]) from None
    except IsADirectoryError:
        raise CompileError([_io_error(path, "is a directory, not an .afsm file")]) from None
    except UnicodeDecodeError as exc:
        raise CompileError([_not_utf8(path, exc)]) from None
    except OSError as exc:
        raise CompileError([_io_error(path, exc.strerror or str(exc))]) from None
    if len(text) > MAX_SOURCE_CHARS:
        raise CompileError([Diagnostic(
            codes.E004, Severity.ERROR, f"{path} has more than {MAX_SOURCE_CHARS:,} characters; "
            f"afsmc reads files of up to {MAX_SOURCE_CHARS:,}", None,
            hint="split the model, or generate it with fewer declarations (a specification "
            "of this size is not checked in reasonable time)")])
    return text


def decode_source(raw: bytes, path: str) -> str:
    """Bytes read elsewhere (standard input) as read_source reads a file: UTF-8, or E001."""
    try:
        return raw.decode("utf-8")
    except UnicodeDecodeError as exc:
        raise CompileError([_not_utf8(path, exc, raw)]) from None


def _not_utf8(path: str, exc: UnicodeDecodeError, raw: bytes | None = None) -> Diagnostic:
    """E001 at the first byte that is not UTF-8, with its line (an editor saved it as
    Latin-1, say): the text before it decodes, the byte is shown as U+FFFD."""
    if raw is None:
        try:
            with open(path, "rb") as f:
                raw = f.read()
        except OSError:
            return _io_error(path, "is not UTF-8 text")
    source = Source(path, raw.decode("utf-8", errors="replace"))
    at = len(raw[:exc.start].decode("utf-8", errors="replace"))
    return Diagnostic(codes.E001, Severity.ERROR, f"cannot read {path}: byte 0x{raw[exc.start]:02x} "
                      "is not UTF-8 text", Span.at_offset(source, at),
                      hint="save the file as UTF-8 (it may be Latin-1 or another 8-bit "
                           "encoding)")


def _io_error(path: str, why: str) -> Diagnostic:
    return Diagnostic(codes.E001, Severity.ERROR, f"cannot read {path}: {why}", None)


def refuse_inputs(paths: list[str], protect: tuple[str, ...]) -> None:
    """E002 if any of `paths` is one of the inputs: checked for every output before the
    first is written, so that a refusal leaves nothing half-done."""
    for path in paths:
        real = os.path.realpath(path)
        for p in protect:
            if os.path.exists(p) and os.path.realpath(p) == real:
                raise CompileError([Diagnostic(codes.E002, Severity.ERROR,
                                               f"refusing to overwrite the input {p}", None,
                                               hint="choose another output path")])


def check_writable(path: str, *, protect: tuple[str, ...] = ()) -> None:
    """Raise now what `write_atomic(path, ...)` would raise later for the path itself
    (E002 an input, E003 not writable), for commands that compute for long before they
    write: an empty name, a directory, a missing directory above the file's own, a
    directory that refuses new files, a read-only file, the always-full /dev/full. (A pipe
    is not probed: see write_atomic.)"""

    def cannot(why: str, hint: str | None = None) -> CompileError:
        return CompileError([Diagnostic(codes.E003, Severity.ERROR,
                                        f"cannot write {path!r}: {why}" if not path.strip()
                                        else f"cannot write {path}: {why}", None, hint=hint)])

    if not path.strip():
        raise cannot("the file name is empty", hint="give a file name")
    refuse_inputs([path], protect)
    real = os.path.realpath(path)
    if os.path.isdir(real):
        raise cannot("it is a directory")
    if os.path.exists(real):
        why = _unwritable_file(real)
        if why is not None:
            raise cannot(why)
    directory = os.path.dirname(real) or "."
    if not os.path.isdir(directory):
        # write_atomic creates the file's own directory, never the ones above it
        why = _missing_directory(directory)
        if why is not None:
            raise cannot(why)
        directory = os.path.dirname(directory)
    if not os.access(directory, os.W_OK | os.X_OK):
        raise cannot(f"permission denied in {directory}")
    # os.access does not know every refusal (root in /proc, a read-only mount): try it.
    try:
        probe = tempfile.mkdtemp(prefix=".afsmc-probe-", dir=directory)
        os.rmdir(probe)
    except OSError as exc:
        raise cannot(f"cannot create files in {directory} ({exc.strerror or exc})") from None


PLOT_SUFFIXES = (".png", ".svg")  # the pictures of `sweep --plot` and `regions --plot`
DEV_FULL = (1, 7)  # Linux's /dev/full: every write to it fails with "No space left on device"


def _unwritable_file(real: str) -> str | None:
    """Why the existing file `real` (not a directory) cannot take the output, or None."""
    st = os.stat(real)
    if stat.S_ISREG(st.st_mode):
        # root may write anything; a file with no write bit is still meant to stay as is
        if not st.st_mode & 0o222:
            return "the file is read-only (chmod u+w it to let afsmc replace it)"
        if not os.access(real, os.W_OK):
            return "permission denied (this user may not write the file)"
        return None
    if stat.S_ISCHR(st.st_mode) and (os.major(st.st_rdev), os.minor(st.st_rdev)) == DEV_FULL:
        return "the device is always full (No space left on device)"
    # A pipe is not opened to look: its reader would take that for the end of the output.
    if not os.access(real, os.W_OK):
        return "permission denied"
    return None


def _missing_directory(directory: str) -> str | None:
    """Why the file's directory `directory`, which does not exist, cannot be created (only
    it, in an existing directory: a mistyped path makes no tree of directories), or None."""
    if os.path.exists(directory):
        return f"{directory} is not a directory"
    parent = os.path.dirname(directory)
    if not os.path.isdir(parent):
        near = _nearest_existing(directory)
        if not os.path.isdir(near):
            return f"{near} is not a directory"
        return f"the directory {parent} does not exist"
    return None


def _nearest_existing(real: str) -> str:
    """The nearest existing ancestor of the (resolved) path `real`."""
    directory = os.path.dirname(real) or "."
    while not os.path.exists(directory):
        directory = os.path.dirname(directory)
    return directory


def _umask() -> int:
    """This process's umask, read without setting it (os.umask sets it, for every thread)."""
    try:
        with open("/proc/self/status", encoding="ascii") as f:
            for line in f:
                if line.startswith("Umask:"):
                    return int(line.split()[1], 8)
    except (OSError, ValueError):
        pass
    return 0o022


def write_atomic(path: str, content: str | bytes, *, protect: tuple[str, ...] = (),
                 newline: str | None = "\n") -> None:
    """Write via a temporary file and rename, so a reader never sees half a file.

    Refuses to overwrite any of `protect` (the inputs). Text is written with `newline`
    (None: as given). A file it replaces keeps its permission bits and, where this process
    may set them (root), its owner and group: an output made private (chmod 640) or an
    input rewritten in place (`fmt`, `sim-check --update`; a `sudo afsmc fmt` must not
    hand the user's file to root). The rename gives the path a new file, as `sed -i` does:
    other hard links to the old one keep the old text."""
    refuse_inputs([path], protect)
    real = os.path.realpath(path)
    if not path.strip() or os.path.isfile(real):
        check_writable(path)  # an empty name, a read-only file: E003, as said up front
    if os.path.exists(real) and not (os.path.isfile(real) or os.path.isdir(real)):
        # A device or a pipe (`-o /dev/null`, `/dev/stdout`): a file renamed over it would
        # replace the device node itself, for every program on the machine.
        try:
            # not blocking: a pipe that no process reads is ENXIO, not a wait for ever
            fd = os.open(real, os.O_WRONLY | os.O_NONBLOCK)
            os.set_blocking(fd, True)
            with open(fd, "wb") as fb:
                fb.write(content if isinstance(content, bytes) else content.encode()
                         if newline is None else content.replace("\n", newline).encode())
        except OSError as exc:
            why = ("a pipe that no process reads" if exc.errno == errno.ENXIO
                   else exc.strerror or exc)
            raise CompileError([Diagnostic(codes.E003, Severity.ERROR,
                                           f"cannot write {path}: {why}",
                                           None)]) from None
        return
    directory = os.path.dirname(real) or "."
    tmp = ""
    try:
        if not os.path.isdir(directory) and _missing_directory(directory) is None:
            os.mkdir(directory)  # the file's own directory only (check_writable)
        old = os.stat(real) if os.path.exists(real) else None
        # A fresh name, created exclusively (mode 600): no other user's file or link in a
        # shared directory is written through.
        fd, tmp = tempfile.mkstemp(prefix=f".{os.path.basename(real)}.", suffix=".tmp",
                                   dir=directory)
        if isinstance(content, bytes):
            with open(fd, "wb") as fb:
                fb.write(content)
                fb.flush()
                os.fsync(fb.fileno())
        else:
            with open(fd, "w", encoding="utf-8", newline="" if newline is None else newline) as f:
                f.write(content)
                f.flush()
                os.fsync(f.fileno())
        if old is not None:
            if (old.st_uid, old.st_gid) != (os.getuid(), os.getgid()):
                try:
                    os.chown(tmp, old.st_uid, old.st_gid)
                except PermissionError:  # not root: ours, with its group if we are in it
                    with contextlib.suppress(PermissionError):
                        os.chown(tmp, -1, old.st_gid)
            os.chmod(tmp, old.st_mode & 0o7777)
        else:  # a new file: the mode open() would give it (mkstemp's is 600)
            os.chmod(tmp, 0o666 & ~_umask())
        os.replace(tmp, real)
    except BaseException as exc:
        # no temporary file left behind, whatever stopped the write (a Ctrl-C too)
        if tmp and os.path.exists(tmp):
            os.unlink(tmp)
        if not isinstance(exc, OSError):
            raise
        why = exc.strerror or str(exc)
        if not os.path.isdir(directory) and (missing := _missing_directory(directory)):
            why = missing  # not mkstemp's "No such file or directory"
        raise CompileError([Diagnostic(codes.E003, Severity.ERROR,
                                       f"cannot write {path}: {why}", None)]) from None
