"""The report as one self-contained HTML page: inline CSS and the diagram as inline SVG,
no script and nothing fetched. Byte for byte the same for the same input, but for the
line that states when it was made."""

from __future__ import annotations

from html import escape

from afsmc.report.case import Case
from afsmc.report.sections import Block, Para, Picture, Section, Table, sections

RULES: tuple[tuple[str, str], ...] = (
    ("body", "font: 15px/1.45 system-ui, sans-serif; max-width: 72rem; margin: 2rem auto; "
             "padding: 0 1rem; color: #1b1b1b"),
    ("h1", "font-size: 1.6rem"),
    ("h2", "font-size: 1.25rem; border-bottom: 1px solid #ccc"),
    ("table", "border-collapse: collapse; margin: 0.6rem 0"),
    ("th, td", "border: 1px solid #ccc; padding: 0.2rem 0.5rem; text-align: left; "
               "vertical-align: top"),
    ("th", "background: #f2f2f2"),
    ("pre", "white-space: pre-wrap; background: #f8f8f8; padding: 0.6rem"),
    (".note", "color: #555; font-size: 0.9em"),
    (".holds", "color: #13631f; font-weight: 600"),
    (".fails", "color: #a0141e; font-weight: 600"),
    (".depends, .undecided", "color: #8a5a00; font-weight: 600"),
    ("figure", "margin: 1rem 0; overflow-x: auto"),
    ("figure svg", "max-width: 100%; height: auto"),
    ("nav ul", "columns: 2"),
)


def style(scope: str = "") -> str:
    """The rules; within `scope` (a selector), each applies to what is inside it ("body":
    to the scope itself)."""
    def within(selector: str) -> str:
        if not scope:
            return selector
        return ", ".join(scope if part.strip() == "body" else f"{scope} {part.strip()}"
                         for part in selector.split(","))
    return "\n".join(f"{within(sel)} {{ {decl}; }}" for sel, decl in RULES)


VERDICTS = ("holds", "fails", "depends", "undecided")


def _cell(text: str, tag: str) -> str:
    cls = f' class="{text}"' if text in VERDICTS else ""
    return f"<{tag}{cls}>{escape(text)}</{tag}>"


def _block(b: Block) -> str:
    if isinstance(b, Picture):
        return f"<figure>{b.svg}</figure>"
    if isinstance(b, Table):
        head = "".join(_cell(h, "th") for h in b.head)
        rows = "".join("<tr>" + "".join(_cell(c, "td") for c in r) + "</tr>\n"
                       for r in b.rows)
        cls = f' class="{b.cls}"' if b.cls else ""
        return f"<table{cls}>\n<thead><tr>{head}</tr></thead>\n<tbody>\n{rows}</tbody></table>"
    assert isinstance(b, Para)
    if b.kind == "pre":
        return f"<pre>{escape(b.text)}</pre>"
    cls = ' class="note"' if b.kind == "note" else ""
    return f"<p{cls}>{escape(b.text)}</p>"


def _section(s: Section) -> str:
    body = "\n".join(_block(b) for b in s.blocks)
    return f'<section id="{s.id}">\n<h2>{escape(s.title)}</h2>\n{body}\n</section>'


def _title(case: Case) -> str:
    return f"Assurance case: {case.machine}"


def body(case: Case) -> str:
    """The page's content: its title, the contents and every section."""
    parts = sections(case)
    nav = "".join(f'<li><a href="#{s.id}">{escape(s.title)}</a></li>' for s in parts)
    return (f"<h1>{escape(_title(case))}</h1>\n<p>{escape(case.path)}</p>\n"
            f"<nav><ul>{nav}</ul></nav>\n" + "\n".join(_section(s) for s in parts))


def fragment(case: Case) -> str:
    """The report inside a page of its own (a notebook's output): its style scoped."""
    return (f'<div class="afsmc-report"><style>{style(".afsmc-report")}</style>\n'
            f"{body(case)}\n</div>")


def page(case: Case) -> str:
    return (f'<!DOCTYPE html>\n<html lang="en">\n<head>\n<meta charset="utf-8">\n'
            f"<title>{escape(_title(case))}</title>\n<style>\n{style()}\n</style>\n</head>\n"
            f"<body>\n{body(case)}\n</body>\n</html>\n")
