"""`AfsmError`: what the Python API raises when a mission cannot be loaded, compiled or
verified. It carries the diagnostics, rendered as `afsmc check` prints them (``str``) and
as HTML in a notebook (``_repr_html_``)."""

from __future__ import annotations

import html
from collections.abc import Iterator, Sequence

from afsmc.diagnostics import CompileError, Diagnostic, render_all
from afsmc.diagnostics.render import render

_COLOURS = {"error": "#c0392b", "warning": "#b9770e", "note": "#117a8b"}


class AfsmError(CompileError):
    """The diagnostics of a failed step (``.diagnostics``, a list of
    :class:`afsmc.diagnostics.Diagnostic`), and what the step had finished (``.partial``:
    verify's answered queries, a sweep's points; None if nothing).

    ``str(err)`` is the text `afsmc check` prints; in Jupyter the error renders as HTML.
    A subclass of :class:`afsmc.diagnostics.CompileError`, so code that catches that catches
    this too."""

    def __init__(self, diagnostics: Sequence[Diagnostic], partial: object = None) -> None:
        super().__init__(diagnostics, partial)  # type: ignore[arg-type]

    @classmethod
    def of(cls, exc: CompileError) -> AfsmError:
        """The API's error for a stage's CompileError: the same diagnostics and partial."""
        return exc if isinstance(exc, AfsmError) else cls(exc.diagnostics, exc.partial)

    def __str__(self) -> str:
        return render_all(self.diagnostics)

    def __iter__(self) -> Iterator[Diagnostic]:
        return iter(self.diagnostics)

    def _repr_html_(self) -> str:
        return diagnostics_html(self.diagnostics)


def diagnostics_html(diagnostics: Sequence[Diagnostic]) -> str:
    """The diagnostics as `afsmc check` renders them, in a <pre>, each headed in the colour
    of its severity (HTML-escaped: a source line may hold `<`)."""
    parts = []
    for d in diagnostics:
        colour = _COLOURS.get(d.severity.value, "inherit")
        text = html.escape(render(d))
        head, _, rest = text.partition("\n")
        parts.append(f'<span style="color:{colour};font-weight:bold">{head}</span>'
                     + (f"\n{rest}" if rest else ""))
    errors = sum(d.is_error for d in diagnostics)
    warnings = sum(d.severity.value == "warning" for d in diagnostics)
    summary = f"{errors} error(s), {warnings} warning(s)"
    return ('<pre class="afsmc-diagnostics" style="white-space:pre-wrap">'
            + "\n\n".join(parts) + f"\n\n{summary}</pre>")
