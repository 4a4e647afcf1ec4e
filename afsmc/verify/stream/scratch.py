"""The scratch directory of a streamed pass: named groups of arrays, each group ONE file
read back with one open, the bytes on disk, and a full disk as one clear error.

A file is one or more records, each appended by :meth:`Scratch.save`: an 8-byte head
(``AFSL`` and the length of a JSON list of the arrays' names, dtypes and shapes), that
list padded to 8 bytes, then each array's raw bytes (C order, native byte order) padded
to 8 bytes. :meth:`Scratch.load` reads the whole file at once and gives every array of
every record, a later record's array replacing an earlier one of the same name (a
bucket's successors are appended once they are numbered). No pickle, no per-array header
to parse as with one .npy file per array.

The directory is made by :func:`made` (under the user's ``--scratch DIR``) and removed
by it on exit, on error and on interrupt; every file of the pass lives in it.
"""

from __future__ import annotations

import errno
import json
import os
import secrets
import shutil
import struct
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any

import numpy as np
import numpy.typing as npt

PREFIX = "afsmc-scratch-"


class ScratchFull(Exception):
    """The scratch directory's disk is full (or over its quota)."""

    def __init__(self, where: Path, written: int) -> None:
        super().__init__(f"the scratch disk is full: no room in {where.parent} after "
                         f"{written / 1e6:,.1f} MB of layers; free some space or give "
                         "--scratch a directory on a larger disk")
        self.written = written


def unusable(directory: str) -> str | None:
    """Why `directory` cannot hold the scratch files (None if it can)."""
    p = Path(directory)
    if not p.exists():
        return f"{directory} does not exist"
    if not p.is_dir():
        return f"{directory} is not a directory"
    if not os.access(p, os.W_OK | os.X_OK):
        return f"{directory} is not writable"
    return None


@contextmanager
def made(directory: str) -> Iterator[Path]:
    """A new subdirectory of `directory` for one job, removed with everything in it on
    the way out. It is made only once something is written there (Scratch makes it), so
    that a job that stays in memory leaves nothing behind even if its process is killed
    before the way out."""
    path = Path(directory) / f"{PREFIX}{os.getpid()}-{secrets.token_hex(6)}"
    try:
        yield path
    finally:
        shutil.rmtree(path, ignore_errors=True)


# A fault injection for the tests (a full disk, an interrupt): called with each file's
# path before it is written; FAULT for every Scratch that is given none.
BeforeWrite = Callable[[Path], None]
FAULT: BeforeWrite | None = None


MAGIC = b"AFSL"
_HEAD = struct.Struct("<4sI")  # the magic and the length of the JSON list
Arrays = dict[str, npt.NDArray[Any]]


def _pad(n: int) -> int:
    return -n % 8


def _record(arrays: Arrays) -> tuple[bytes, list[npt.NDArray[Any]]]:
    """A record's head and list, and its arrays as they are written."""
    data = [np.asarray(a, order="C") for a in arrays.values()]  # (0-d kept 0-d)
    listed = json.dumps([[k, a.dtype.str, list(a.shape)] for k, a in zip(arrays, data,
                                                                         strict=True)])
    text = listed.encode("ascii")
    return _HEAD.pack(MAGIC, len(text)) + text + b"\0" * _pad(len(text)), data


def parse(buf: bytearray) -> Arrays:
    """Every array of every record of a file's bytes (views into `buf`, writable)."""
    out: Arrays = {}
    at = 0
    while at < len(buf):
        magic, n = _HEAD.unpack_from(buf, at)
        if magic != MAGIC:
            raise ValueError(f"not a scratch record at byte {at}")
        at += _HEAD.size
        listed = json.loads(bytes(buf[at:at + n]).decode("ascii"))
        at += n + _pad(n)
        for key, dtype, shape in listed:
            dt = np.dtype(dtype)
            count = int(np.prod(shape, dtype=np.int64))
            out[key] = np.frombuffer(buf, dt, count, at).reshape(tuple(shape))
            at += count * dt.itemsize + _pad(count * dt.itemsize)
    return out


class Scratch:
    """Groups of arrays saved under `root` by name, one file each; `written`: the bytes
    on disk (a file replaced or removed counts no more)."""

    def __init__(self, root: Path, before_write: BeforeWrite | None = None) -> None:
        root.mkdir(mode=0o700, exist_ok=True)  # (made names it; it is made here)
        self.root = root
        self.written = 0
        self.before_write = before_write

    def path(self, name: str) -> Path:
        return self.root / name

    def save(self, name: str, append: bool = False, **arrays: npt.NDArray[Any]) -> None:
        """The arrays as one record of the file `name`, which they replace (or, with
        `append`, follow); a full disk raises ScratchFull, the file removed."""
        path = self.path(name)
        before = path.stat().st_size if path.exists() else 0
        head, data = _record(arrays)
        try:
            hook = self.before_write or FAULT
            if hook is not None:
                hook(path)
            with open(path, "ab" if append else "wb") as f:
                f.write(head)
                for a in data:
                    f.write(a.data if a.size else b"")
                    f.write(b"\0" * _pad(a.nbytes))
        except OSError as exc:
            if exc.errno in (errno.ENOSPC, errno.EDQUOT):
                path.unlink(missing_ok=True)
                self.written -= before
                raise ScratchFull(path, self.written) from None
            raise
        self.written += path.stat().st_size - before

    def load(self, name: str) -> Arrays:
        """Every array of the file `name`, read with one open."""
        with open(self.path(name), "rb") as f:
            buf = bytearray(os.fstat(f.fileno()).st_size)
            f.readinto(buf)
        return parse(buf)

    def remove(self, name: str) -> None:
        path = self.path(name)
        if path.exists():
            self.written -= path.stat().st_size
            path.unlink()


def clear(root: Path) -> None:
    """Remove every file under `root`, keeping the directory (its owner removes it)."""
    for p in root.iterdir():
        if p.is_dir():
            shutil.rmtree(p, ignore_errors=True)
        else:
            p.unlink(missing_ok=True)
