"""`Report`: what :meth:`afsmc.api.mission.Mission.report` returns, the assurance case of
`afsmc report` as an object: ``html()``, ``markdown()``, ``save(path)``, and shown inline
in Jupyter (``_repr_html_``)."""

from __future__ import annotations

import os
from dataclasses import dataclass

from afsmc.files import write_atomic
from afsmc.report import html, markdown
from afsmc.report.case import Case


@dataclass(frozen=True)
class Report:
    """``case`` holds what the report shows: ``case.result`` is the one
    :class:`afsmc.verify.VerifyResult` every number comes from, ``case.causes`` the
    failure properties split by cause, ``case.sensitivity`` the derivatives,
    ``case.baseline`` the comparison with a baseline."""

    case: Case

    def html(self) -> str:
        """The self-contained page `afsmc report -o report.html` writes."""
        return html.page(self.case)

    def markdown(self) -> str:
        """The Markdown `afsmc report --format md` writes."""
        return markdown.page(self.case)

    def save(self, path: str | os.PathLike[str]) -> str:
        """Write the report: Markdown for a name ending in .md, else HTML. Atomic; returns
        the path."""
        path = os.fspath(path)
        write_atomic(path, self.markdown() if path.endswith(".md") else self.html(),
                     protect=(self.case.path,))
        return path

    def _repr_html_(self) -> str:
        return html.fragment(self.case)
