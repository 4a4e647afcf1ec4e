"""Samples from a data file: the column of a CSV file that backs a constant
(`const int T_X = [8, 12] from data "logs/transport.csv" column duration;`).

The file is data, never code: it is read with the `csv` module, each cell converted with
`float` (and `true`/`false` for outcomes); nothing in it is imported or evaluated. Its path
is relative to the spec's folder. Blank cells are skipped (a run that did not record the
figure); anything else that is not a finite number is an error, as is a column with no
values, with a code and the spec's `from data` clause as the place.
"""

from __future__ import annotations

import csv
import difflib
import math
import os

import numpy as np
import numpy.typing as npt

from afsmc.diagnostics import CompileError, Diagnostic, Severity, codes
from afsmc.model import ir

MAX_BYTES = 256 * 2**20  # a data file larger than this is refused (E510), not read
_OUTCOMES = {"0": 0.0, "1": 1.0, "true": 1.0, "false": 0.0}
_SHOWN = 3  # bad cells named in a message


def path_of(spec: str, source: ir.SimSource) -> str:
    """The data file's path: as written if absolute, else relative to the spec's folder."""
    return os.path.join(os.path.dirname(os.path.abspath(spec)), source.ref)


def read(spec: str, const: ir.Constant, outcomes: bool) -> npt.NDArray[np.float64]:
    """The column's values (for `outcomes`, 1.0 for a success and 0.0 for a failure), or
    CompileError: E510 (the file), E511 (the column), E512 (a cell), E513 (no values),
    E514 (an outcome that is not 0 or 1)."""
    src = const.source
    assert src is not None and src.column is not None
    path = path_of(spec, src)
    rows = _rows(path, const)
    header, body = rows[0][1] if rows else [], rows[1:]
    names = [h.strip() for h in header]
    if src.column not in names:
        close = difflib.get_close_matches(src.column, names, n=1, cutoff=0.6)
        listed = ", ".join(repr(n) for n in names[:12]) + (", ..." if len(names) > 12 else "")
        raise _error(codes.E511, f"data file '{src.ref}' of constant '{const.name}' has no "
                     f"column '{src.column}'", src,
                     (f"did you mean '{close[0]}'? " if close else "")
                     + (f"its columns (first line): {listed}" if names else
                        "the file is empty: its first line must name the columns"))
    at = names.index(src.column)
    values: list[float] = []
    bad: list[str] = []
    for line, row in body:
        cell = row[at].strip() if at < len(row) else ""
        if not cell:
            continue
        value = _outcome(cell) if outcomes else _number(cell)
        if value is None:
            bad.append(f"line {line}: {cell[:40]!r}")
        else:
            values.append(value)
    if bad:
        shown = "; ".join(bad[:_SHOWN]) + (f"; and {len(bad) - _SHOWN} more"
                                           if len(bad) > _SHOWN else "")
        if outcomes:
            raise _error(codes.E514, f"column '{src.column}' of '{src.ref}' backs the "
                         f"probability '{const.name}', but holds values that are not "
                         f"outcomes: {shown}", src,
                         "each cell of an outcome column is 1 (or true) for a success and 0 "
                         "(or false) for a failure; a blank cell is skipped")
        raise _error(codes.E512, f"column '{src.column}' of '{src.ref}' holds cells that are "
                     f"not numbers: {shown}", src,
                     "each cell is a finite number such as 12 or 11.5 (a blank cell is "
                     "skipped); clean the file, or name another column")
    if not values:
        raise _error(codes.E513, f"column '{src.column}' of '{src.ref}' holds no values "
                     f"for constant '{const.name}'", src,
                     "the file needs a line per run below its header; blank cells are skipped")
    return np.asarray(values, dtype=np.float64)


def _rows(path: str, const: ir.Constant) -> list[tuple[int, list[str]]]:
    """The file's rows with their line numbers, or E510."""
    src = const.source
    assert src is not None
    try:
        size = os.path.getsize(path)
        if size > MAX_BYTES:
            raise _error(codes.E510, f"data file '{src.ref}' of constant '{const.name}' is "
                         f"{size / 2**20:.0f} MB, more than the {MAX_BYTES // 2**20} MB afsmc "
                         "reads", src, "keep the column it needs in a smaller file")
        with open(path, encoding="utf-8-sig", newline="") as f:
            reader = csv.reader(f)
            return [(reader.line_num, row) for row in reader]
    except CompileError:
        raise
    except FileNotFoundError:
        why = "there is no such file"
    except IsADirectoryError:
        why = "it is a directory"
    except UnicodeDecodeError as exc:
        why = f"it is not UTF-8 text (byte {exc.start})"
    except csv.Error as exc:
        why = f"it is not valid CSV ({exc})"
    except OSError as exc:
        why = exc.strerror or str(exc)
    raise _error(codes.E510, f"cannot read data file '{src.ref}' of constant "
                 f"'{const.name}': {why}", src,
                 f"the path is relative to the spec's folder: {path}")


def _number(cell: str) -> float | None:
    try:
        value = float(cell)
    except ValueError:
        return None
    return value if math.isfinite(value) else None


def _outcome(cell: str) -> float | None:
    value = _OUTCOMES.get(cell.lower())
    if value is None:
        number = _number(cell)
        return number if number in (0.0, 1.0) else None
    return value


def _error(code: codes.Code, message: str, src: ir.SimSource, hint: str) -> CompileError:
    return CompileError([Diagnostic(code, Severity.ERROR, message, src.span, hint=hint)])
