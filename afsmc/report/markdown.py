"""The report as Markdown, for a repository's docs: the same sections as the HTML page,
the diagram left out (`afsmc diagram` draws it)."""

from __future__ import annotations

from afsmc.report.case import Case
from afsmc.report.sections import Block, Para, Picture, Table, sections


def _cell(text: str) -> str:
    return text.replace("|", "\\|").replace("\n", " ")


def _block(b: Block) -> str:
    if isinstance(b, Picture):
        return "_The diagram is in the HTML report (`afsmc report -o report.html`)._"
    if isinstance(b, Table):
        lines = ["| " + " | ".join(_cell(h) for h in b.head) + " |",
                 "|" + "---|" * len(b.head)]
        lines += ["| " + " | ".join(_cell(c) for c in r) + " |" for r in b.rows]
        return "\n".join(lines)
    assert isinstance(b, Para)
    if b.kind == "pre":
        return "\n".join("> " + line if line else ">" for line in b.text.splitlines())
    return f"_{b.text}_" if b.kind == "note" else b.text


def page(case: Case) -> str:
    out = [f"# Assurance case: {case.machine}", "", f"`{case.path}`", ""]
    for s in sections(case):
        out += [f"## {s.title}", ""]
        for b in s.blocks:
            out += [_block(b), ""]
    return "\n".join(out)
