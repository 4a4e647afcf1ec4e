"""Collecting diagnostics: a stage appends to a :class:`Reporter` and goes on; a stage
that cannot go on raises :class:`CompileError` with everything collected so far."""

from __future__ import annotations

from collections.abc import Iterable, Sequence
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

from afsmc.diagnostics.codes import REGISTRY, Code
from afsmc.diagnostics.model import Diagnostic, Related, Severity, Span

if TYPE_CHECKING:  # afsmc.interrupt imports this package
    from afsmc.interrupt import JsonResult


def checked(code: Code | str, severity: Severity) -> str:
    """`code` as a plain string, once it is known to be in the registry with `severity`:
    a code reported at another severity than its declaration is a bug in afsmc."""
    declared = REGISTRY.get(code)
    if declared is None:
        raise ValueError(f"{code} is not declared in afsmc/diagnostics/codes.py")
    if declared.severity is not severity:
        raise ValueError(f"{code} is declared as {_article(declared.severity)}, "
                         f"reported as {_article(severity)}")
    return str(code)


def _article(severity: Severity) -> str:
    return ("an " if severity is Severity.ERROR else "a ") + severity.value


@dataclass
class Reporter:
    """Collects diagnostics; stages keep going after an error so that all are reported.
    Codes are the registry's (afsmc.diagnostics.codes), at their declared severity."""

    diagnostics: list[Diagnostic] = field(default_factory=list)

    def error(self, code: Code | str, message: str, span: Span | None,
              hint: str | None = None, related: Iterable[Related] = ()) -> None:
        self.diagnostics.append(Diagnostic(checked(code, Severity.ERROR), Severity.ERROR,
                                           message, span, hint, tuple(related)))

    def warning(self, code: Code | str, message: str, span: Span | None,
                hint: str | None = None, related: Iterable[Related] = ()) -> None:
        self.diagnostics.append(Diagnostic(checked(code, Severity.WARNING), Severity.WARNING,
                                           message, span, hint, tuple(related)))

    def note(self, code: Code | str, message: str, span: Span | None,
             hint: str | None = None) -> None:
        self.diagnostics.append(Diagnostic(checked(code, Severity.NOTE), Severity.NOTE,
                                           message, span, hint))

    @property
    def has_errors(self) -> bool:
        return any(d.is_error for d in self.diagnostics)

    def extend(self, diags: Iterable[Diagnostic]) -> None:
        self.diagnostics.extend(diags)

    def sorted(self) -> list[Diagnostic]:
        # Dedupe: the same problem reached by two routes is reported once.
        seen: set[tuple[str, str, int]] = set()
        out = []
        for d in sorted(self.diagnostics, key=Diagnostic.sort_key):
            key = (d.code, d.message, d.span.start if d.span else -1)
            if key not in seen:
                seen.add(key)
                out.append(d)
        return out


class CompileError(Exception):
    """Raised by a stage that cannot go on; carries every diagnostic collected so far.

    `partial`: what the stage had finished when it failed, for the caller to keep, so that
    one failed query does not lose an hour's others; None if there is nothing to keep. A
    result with a JSON form (verify's `Partial`, a `SweepResult`), which `--json` prints,
    or the points a sweep task answered in part, which the sweep merges; readers tell them
    apart with isinstance."""

    def __init__(self, diagnostics: Sequence[Diagnostic],
                 partial: JsonResult | Sequence[object] | None = None):
        super().__init__("; ".join(d.message for d in diagnostics))
        self.diagnostics = list(diagnostics)
        self.partial = partial
