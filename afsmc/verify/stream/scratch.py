"""The scratch directory of a streamed pass: numbered arrays written with np.save and read
back, the bytes written so far, and a full disk as one clear error.

The directory is made by :func:`made` (under the user's ``--scratch DIR``) and removed
by it on exit, on error and on interrupt; every file of the pass lives in it.
"""

from __future__ import annotations

import errno
import os
import shutil
import tempfile
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
    """A new subdirectory of `directory`, removed with everything in it on the way out."""
    path = Path(tempfile.mkdtemp(prefix=PREFIX, dir=directory))
    try:
        yield path
    finally:
        shutil.rmtree(path, ignore_errors=True)


# A fault injection for the tests (a full disk, an interrupt): called with each file's
# path before it is written; FAULT for every Scratch that is given none.
BeforeWrite = Callable[[Path], None]
FAULT: BeforeWrite | None = None


class Scratch:
    """Arrays saved under `root` by name; `written`: the bytes on disk (a file written
    over counts once)."""

    def __init__(self, root: Path, before_write: BeforeWrite | None = None) -> None:
        self.root = root
        self.written = 0
        self.before_write = before_write

    def save(self, name: str, **arrays: npt.NDArray[Any]) -> None:
        """Each array as `name`.`key`.npy; a full disk raises ScratchFull."""
        for key, a in arrays.items():
            path = self.root / f"{name}.{key}.npy"
            if path.exists():
                self.written -= path.stat().st_size
            try:
                hook = self.before_write or FAULT
                if hook is not None:
                    hook(path)
                with open(path, "wb") as f:
                    np.save(f, np.ascontiguousarray(a), allow_pickle=False)
            except OSError as exc:
                if exc.errno in (errno.ENOSPC, errno.EDQUOT):
                    path.unlink(missing_ok=True)
                    raise ScratchFull(path, self.written) from None
                raise
            self.written += path.stat().st_size

    def load(self, name: str, key: str) -> npt.NDArray[Any]:
        out: npt.NDArray[Any] = np.load(self.root / f"{name}.{key}.npy", allow_pickle=False)
        return out



def clear(root: Path) -> None:
    """Remove every file under `root`, keeping the directory (its owner removes it)."""
    for p in root.iterdir():
        if p.is_dir():
            shutil.rmtree(p, ignore_errors=True)
        else:
            p.unlink(missing_ok=True)
