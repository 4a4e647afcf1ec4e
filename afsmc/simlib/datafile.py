"""Samples from a data file: the column of a CSV file that backs a constant
(`const int T_X = [8, 12] from data "logs/transport.csv" column duration;`).

The file is data, never code: it is read with the `csv` module, each cell converted with
`float` (and `true`/`false` for outcomes); nothing in it is imported or evaluated. Its path
is relative to the spec's folder, and the file must lie inside the mission: under the spec's
folder, or under the data root the user names (`sim-check --data-root DIR`). A path that
leaves it, whether written so or through a symbolic link, is refused (E515), as is anything
but a regular file, a device or a FIFO say (E516); both before the file is opened, so that
a FIFO cannot block the command. The file is read as a stream, in bounded memory: only the
named column's values are kept, at most MAX_VALUES of them, and a file beyond MAX_BYTES or
a line beyond MAX_LINE is refused (E510).

Messages quote the file only where it names its columns, and only when its first line
looks like a CSV header (short names of letters, digits and a few signs); a bad cell is
named by its line and what is wrong with it, never by its text, so that a spec cannot make
a CI log print another file's content.

Blank cells are skipped (a run that did not record the figure); anything else that is not
a finite number within MAX_MAGNITUDE is an error, as is a column with no values, a row
whose number of fields differs from the header's, or a column named twice, each with a
code and the spec's `from data` clause as the place.
"""

from __future__ import annotations

import array
import csv
import difflib
import math
import os
import re
import stat
from collections.abc import Iterator
from typing import IO

import numpy as np
import numpy.typing as npt

from afsmc.diagnostics import CompileError, Diagnostic, Severity, codes
from afsmc.model import ir
from afsmc.text import plural

MAX_BYTES = 256 * 2**20  # a data file larger than this is refused (E510), not read
MAX_LINE = 2**20  # characters on one line of a data file (a CSV row is a few dozen)
MAX_VALUES = 10_000_000  # values of one column afsmc keeps (80 MB as doubles)
# The largest magnitude a cell may hold: Storm's state integers (±2^48) and far beyond any
# duration or charge; a larger one overflows the statistics (a mean of 1e308s is inf).
MAX_MAGNITUDE = 1e15  # (the messages say "1e15")
_OUTCOMES = {"0": 0.0, "1": 1.0, "true": 1.0, "false": 0.0}
_SHOWN = 3  # bad lines named in a message
# A column name as CSV headers write them: what a first line must be made of before a
# message lists it (a line of another kind of file, /etc/passwd's say, is never shown).
_HEADER_NAME = re.compile(r"[A-Za-z0-9_ .()\[\]%/#+-]{1,64}")
_KINDS = ((stat.S_ISDIR, "a directory"), (stat.S_ISFIFO, "a FIFO (a named pipe)"),
          (stat.S_ISCHR, "a character device"), (stat.S_ISBLK, "a block device"),
          (stat.S_ISSOCK, "a socket"))


def path_of(spec: str, source: ir.SimSource) -> str:
    """The data file's path: as written if absolute, else relative to the spec's folder."""
    return os.path.normpath(os.path.join(os.path.dirname(os.path.abspath(spec)), source.ref))


def root_of(spec: str, data_root: str | None = None) -> str:
    """The folder every data file of `spec` must lie under: `data_root` if given, else the
    spec's folder; with its symbolic links resolved."""
    return os.path.realpath(data_root if data_root is not None
                            else os.path.dirname(os.path.abspath(spec)))


def read(spec: str, const: ir.Constant, outcomes: bool,
         data_root: str | None = None) -> npt.NDArray[np.float64]:
    """The column's values (for `outcomes`, 1.0 for a success and 0.0 for a failure), or
    CompileError: E515 (the path leaves the data root), E516 (not a regular file), E510
    (the file cannot be read, or is too large), E511 (no such column), E517 (rows that do
    not match the header, a column named twice), E512 (a cell), E513 (no values), E514 (an
    outcome that is not 0 or 1)."""
    src = const.source
    assert src is not None and src.column is not None
    path = _locate(spec, const, root_of(spec, data_root))
    try:
        with _open(path, const) as f:
            return _column(_lines(f, const), const, outcomes)
    except UnicodeDecodeError:
        why = "it is not UTF-8 text"
    except csv.Error as exc:
        why = f"it is not valid CSV ({exc})"
    except MemoryError:
        why = "there is not enough memory to hold its column"
    except OSError as exc:
        why = exc.strerror or type(exc).__name__
    raise _error(codes.E510, f"cannot read data file '{src.ref}' of constant "
                 f"'{const.name}': {why}", src, f"the path is relative to the spec's folder: {path}")


def _locate(spec: str, const: ir.Constant, root: str) -> str:
    """The file's real path, checked to lie under `root` and to be a regular file, without
    opening it; E515, E516 or E510 (no such file) otherwise."""
    src = const.source
    assert src is not None
    what = f"data file '{src.ref}' of constant '{const.name}'"
    if "\0" in src.ref:
        raise _error(codes.E510, f"cannot read {what}: its path holds a NUL character", src,
                     "write the file's path relative to the spec's folder")
    written = os.path.normpath(os.path.join(root_of(spec), src.ref))
    real = os.path.realpath(path_of(spec, src))
    if not _under(real, root):
        link = _under(written, root)  # inside as written: a symbolic link leads out
        raise _error(codes.E515, f"{what} is {'a link to a file ' if link else ''}outside "
                     f"the mission's folder {root}", src,
                     "a data file must lie under the spec's folder (or under the folder "
                     "`--data-root DIR` names); copy the file there" if not link else
                     "a symbolic link may lead to a file under the same folder only; copy "
                     "the file there")
    try:
        info = os.stat(real)
    except FileNotFoundError:
        raise _error(codes.E510, f"cannot read {what}: there is no such file", src,
                     f"the path is relative to the spec's folder: {real}") from None
    except OSError as exc:
        raise _error(codes.E510, f"cannot read {what}: {exc.strerror or type(exc).__name__}",
                     src, f"the path is relative to the spec's folder: {real}") from None
    kind = _kind(info)
    if kind is not None:
        raise _error(codes.E516, f"{what} is {kind}, not a regular file", src,
                     "name a CSV file: afsmc reads no devices, pipes or folders")
    if info.st_size > MAX_BYTES:
        raise _error(codes.E510, f"{what} is {info.st_size / 2**20:.0f} MB, more than the "
                     f"{MAX_BYTES // 2**20} MB afsmc reads", src,
                     "keep the column it needs in a smaller file")
    return real


def _under(path: str, root: str) -> bool:
    return path == root or path.startswith(root.rstrip(os.sep) + os.sep)


def _kind(info: os.stat_result) -> str | None:
    """What a file that is not a regular one is ("a FIFO (a named pipe)"), or None."""
    if stat.S_ISREG(info.st_mode):
        return None
    return next((name for test, name in _KINDS if test(info.st_mode)), "not a regular file")


def _open(path: str, const: ir.Constant) -> IO[str]:
    """The checked file opened for reading text; a file swapped for a link, a FIFO or a
    device since it was checked is refused (no link followed, never blocking)."""
    flags = os.O_RDONLY | getattr(os, "O_NOFOLLOW", 0) | getattr(os, "O_NONBLOCK", 0)
    fd = os.open(path, flags | getattr(os, "O_CLOEXEC", 0))
    try:
        info = os.fstat(fd)
        kind = _kind(info)
        if kind is not None or info.st_size > MAX_BYTES:
            assert const.source is not None
            raise _error(codes.E516 if kind else codes.E510, f"data file '{const.source.ref}' "
                         f"of constant '{const.name}' changed while it was read: it is now "
                         + (f"{kind}" if kind else "larger than "
                            f"{MAX_BYTES // 2**20} MB"), const.source, "read it again")
        return open(fd, encoding="utf-8-sig", newline="", closefd=True)
    except BaseException:
        os.close(fd)
        raise


def _lines(f: IO[str], const: ir.Constant) -> Iterator[str]:
    """The file's lines, none longer than MAX_LINE and at most MAX_BYTES in all (the file
    may grow while it is read); E510 past either."""
    assert const.source is not None
    total = 0
    while line := f.readline(MAX_LINE + 1):
        total += len(line)
        if len(line) > MAX_LINE or total > MAX_BYTES:
            too = (f"a line longer than {MAX_LINE:,} characters" if len(line) > MAX_LINE
                   else f"more than {MAX_BYTES // 2**20} MB")
            raise _error(codes.E510, f"data file '{const.source.ref}' of constant "
                         f"'{const.name}' holds {too}", const.source,
                         "a data file is a CSV file of one run per line")
        yield line


def looks_like_header(names: list[str]) -> bool:
    """Whether a first line looks like the names of CSV columns: each short, of letters,
    digits, spaces and _ . ( ) [ ] % / # + -, with a letter or an underscore."""
    return bool(names) and len(names) <= 1000 and all(
        _HEADER_NAME.fullmatch(n) and any(ch.isalpha() or ch == "_" for ch in n) for n in names)


def _column(lines: Iterator[str], const: ir.Constant, outcomes: bool) -> npt.NDArray[np.float64]:
    src = const.source
    assert src is not None and src.column is not None
    reader = csv.reader(lines)
    names = [h.strip() for h in next(reader, [])]
    at = _header(names, const)
    width = len(names)
    values = array.array("d")
    bad: list[str] = []
    ragged: list[str] = []
    n_bad = n_ragged = 0
    for row in reader:
        if not row:
            continue  # a blank line
        if len(row) != width:
            n_ragged += 1
            if len(ragged) < _SHOWN:
                ragged.append(f"line {reader.line_num} has {plural(len(row), 'field')}")
            continue
        cell = row[at].strip()
        if not cell:
            continue
        value, why = _outcome(cell) if outcomes else _number(cell)
        if why:
            n_bad += 1
            if len(bad) < _SHOWN:
                bad.append(f"line {reader.line_num} ({why})")
            continue
        if len(values) >= MAX_VALUES:
            raise _error(codes.E510, f"column '{src.column}' of '{src.ref}' holds more than "
                         f"{MAX_VALUES:,} values, more than afsmc keeps", src,
                         "a sample of the runs in a smaller file is judged as well")
        values.append(value)
    if n_ragged:
        raise _error(codes.E517, f"data file '{src.ref}' has rows that do not match its "
                     f"header of {plural(width, 'column')}: {_listed(ragged, n_ragged)}", src,
                     "each line holds one field per column of the first line (a blank field "
                     "is written as nothing between two commas)")
    if n_bad:
        if outcomes:
            raise _error(codes.E514, f"column '{src.column}' of '{src.ref}' backs the "
                         f"probability '{const.name}', but holds values that are not "
                         f"outcomes: {_listed(bad, n_bad)}", src,
                         "each cell of an outcome column is 1 (or true) for a success and 0 "
                         "(or false) for a failure; a blank cell is skipped")
        raise _error(codes.E512, f"column '{src.column}' of '{src.ref}' holds cells that are "
                     f"not finite numbers of at most 1e15: {_listed(bad, n_bad)}", src,
                     "each cell is a finite number such as 12 or 11.5, at most 1e15 in "
                     "size (a blank cell is skipped); clean the file, or name another column")
    if not values:
        raise _error(codes.E513, f"column '{src.column}' of '{src.ref}' holds no values "
                     f"for constant '{const.name}'", src,
                     "the file needs a line per run below its header; blank cells are skipped")
    return np.frombuffer(values, dtype=np.float64).copy()


def _header(names: list[str], const: ir.Constant) -> int:
    """The named column's index in the header; E511 (listing the names only if the line
    looks like a header) or E517 (named twice)."""
    src = const.source
    assert src is not None and src.column is not None
    found = [i for i, n in enumerate(names) if n == src.column]
    if len(found) > 1:
        raise _error(codes.E517, f"data file '{src.ref}' names column '{src.column}' "
                     f"{len(found)} times (columns {', '.join(str(i + 1) for i in found)})",
                     src, "give each column of the first line its own name")
    if found:
        return found[0]
    what = f"data file '{src.ref}' of constant '{const.name}' has no column '{src.column}'"
    if not names or names == [""]:
        raise _error(codes.E511, what, src,
                     "the file is empty: its first line must name the columns")
    if not looks_like_header(names):
        raise _error(codes.E511, what, src,
                     "its first line does not look like a CSV header (names of letters, "
                     "digits, spaces and _ . ( ) [ ] % / # + - separated by commas): the "
                     "first line must name the columns")
    close = difflib.get_close_matches(src.column, names, n=1, cutoff=0.6)
    listed = ", ".join(repr(n) for n in names[:12]) + (", ..." if len(names) > 12 else "")
    raise _error(codes.E511, what, src, (f"did you mean '{close[0]}'? " if close else "")
                 + f"its columns (first line): {listed}")


def _listed(items: list[str], total: int) -> str:
    return "; ".join(items) + (f"; and {total - len(items)} more" if total > len(items) else "")


def _number(cell: str) -> tuple[float, str]:
    """The cell's value and "" , or 0.0 and what is wrong with it."""
    try:
        value = float(cell)
    except ValueError:
        return 0.0, "not a number"
    if not math.isfinite(value):
        return 0.0, "not finite"
    if abs(value) > MAX_MAGNITUDE:
        return 0.0, "larger than 1e15"
    return value, ""


def _outcome(cell: str) -> tuple[float, str]:
    value = _OUTCOMES.get(cell.lower())
    if value is not None:
        return value, ""
    number, why = _number(cell)
    return (number, "") if not why and number in (0.0, 1.0) else (0.0, "not 0, 1, true or false")


def _error(code: codes.Code, message: str, src: ir.SimSource, hint: str) -> CompileError:
    return CompileError([Diagnostic(code, Severity.ERROR, message, src.span, hint=hint)])
