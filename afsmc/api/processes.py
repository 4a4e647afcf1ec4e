"""Starting afsmc's worker processes from a user's script without re-running it.

A process started by multiprocessing's "spawn" first imports the parent's main module (as
``__mp_main__``), found through ``__main__.__spec__`` or ``__main__.__file__``. A plain
script has no ``if __name__ == "__main__":`` guard around its ``m.sweep(...)``, so the
child would run the script's sweep again, which multiprocessing stops with "An attempt has
been made to start a new process before the current process has finished its
bootstrapping phase". afsmc's workers need nothing from the main module (their functions
live in afsmc), so while the API runs, the main module shows neither attribute. (Jupyter's
and ``python - < file``'s main modules have neither to begin with.)
"""

from __future__ import annotations

import sys
import threading
from collections.abc import Iterator
from contextlib import contextmanager

_HIDDEN = ("__file__", "__spec__")


@contextmanager
def main_not_reimported() -> Iterator[None]:
    """Hide the main module's ``__file__`` and ``__spec__`` from the processes started
    within; restored on the way out. Only on the main thread (another thread's user code
    may read them meanwhile)."""
    main = sys.modules.get("__main__")
    if main is None or threading.current_thread() is not threading.main_thread():
        yield
        return
    saved = {k: main.__dict__[k] for k in _HIDDEN if k in main.__dict__}
    try:
        main.__dict__.pop("__file__", None)
        if "__spec__" in saved:
            main.__dict__["__spec__"] = None
        yield
    finally:
        for k in _HIDDEN:
            main.__dict__.pop(k, None)
        main.__dict__.update(saved)
