"""What a long command keeps when it is stopped: the typed interrupt that carries it.

A Ctrl-C (or SIGTERM) during an hour of verification must not lose the queries already
answered. The stage that is interrupted raises :class:`Stopped` from the KeyboardInterrupt,
with what it finished; the CLI prints `errors` and `notes` and, under `--json`, merges
`partial.to_json()` into its one JSON object.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Generic, Protocol, TypeVar, runtime_checkable

from afsmc.diagnostics import Diagnostic


@runtime_checkable
class JsonResult(Protocol):
    """A result with a JSON form, as `afsmc ... --json` prints it."""

    def to_json(self) -> dict[str, object]: ...


P = TypeVar("P")


class Stopped(KeyboardInterrupt, Generic[P]):
    """An interrupt with what was finished by then.

    - `errors`: diagnostics of the work that failed before the interrupt (a query Storm
      refused), shown as they would have been at the end;
    - `notes`: one line each on what was kept (the values so far);
    - `partial`: the kept answers as data (verify's `Partial`, a `SweepResult`, simulate's
      `Outcome`), or None.

    Raise it `from` the KeyboardInterrupt, so that the CLI still sees a SIGTERM behind it.
    """

    def __init__(self, errors: Sequence[Diagnostic] = (), notes: Sequence[str] = (),
                 partial: P | None = None) -> None:
        super().__init__()
        self.errors = list(errors)
        self.notes = list(notes)
        self.partial = partial
