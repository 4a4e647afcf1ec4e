"""The explanations of the diagnostic codes, afsmc/diagnostics/explanations/<CODE>.md,
and their two renderings: text for `afsmc explain CODE`, Markdown for docs/diagnostics.md.

An explanation file reads exactly::

    # E301: weights of enabled actions tie

    Prose: one or more paragraphs of Markdown.

    ## Wrong

    ```afsm
    a complete .afsm file that `afsmc check` reports the code on
    ```

    ## Right

    ```afsm
    the same file fixed
    ```

The first line is `# CODE: title`, the title the registry declares. Each section holds one
or more fenced blocks; a code that `afsmc check` cannot show (reading files, Storm,
simulation) gives the command lines that show it in a ```sh block, optionally with the
```afsm file they name. Text between the blocks of a section is kept with them.
"""

from __future__ import annotations

import re
from dataclasses import dataclass
from functools import cache
from importlib import resources
from importlib.resources.abc import Traversable

_TITLE = re.compile(r"# ([EWN]\d{3}): (\S.*)")
_SECTION = re.compile(r"^## (Wrong|Right)[ \t]*$", re.M)
_BLOCK = re.compile(r"^```(\w+)[ \t]*\n(.*?)^```[ \t]*$", re.S | re.M)


@dataclass(frozen=True)
class Block:
    """One fenced block of a section: its language (afsm, sh) and text (lines ending in
    a newline)."""

    lang: str
    text: str


@dataclass(frozen=True)
class Section:
    """`## Wrong` or `## Right`: its fenced blocks, and its Markdown as written."""

    blocks: tuple[Block, ...]
    markdown: str

    def of(self, lang: str) -> list[str]:
        """The texts of the blocks in `lang`."""
        return [b.text for b in self.blocks if b.lang == lang]

    @property
    def checkable(self) -> bool:
        """One ```afsm block and nothing to run: `afsmc check` on it shows the point."""
        return [b.lang for b in self.blocks] == ["afsm"]


@dataclass(frozen=True)
class Explanation:
    code: str
    title: str
    prose: str
    wrong: Section
    right: Section


def parse(text: str) -> Explanation:
    """An explanation file's content; ValueError says what is not in the format above."""
    first, _, rest = text.replace("\r\n", "\n").partition("\n")
    m = _TITLE.fullmatch(first.rstrip())
    if m is None:
        raise ValueError(f"the first line is not '# CODE: title': {first!r}")
    parts = _SECTION.split(rest)
    if len(parts) != 5 or parts[1] != "Wrong" or parts[3] != "Right":
        raise ValueError("expected the sections '## Wrong' then '## Right', once each")
    sections = []
    for name, body in (("Wrong", parts[2]), ("Right", parts[4])):
        blocks = tuple(Block(b.group(1), b.group(2)) for b in _BLOCK.finditer(body))
        if not blocks:
            raise ValueError(f"'## {name}' has no fenced code block")
        sections.append(Section(blocks, body.strip()))
    prose = parts[0].strip()
    if not prose:
        raise ValueError("no prose between the title and '## Wrong'")
    return Explanation(m.group(1), m.group(2).strip(), prose, sections[0], sections[1])


# The explanation files: package data (pyproject.toml's package-data).
EXPLANATIONS: Traversable = resources.files("afsmc.diagnostics").joinpath("explanations")


def path_of(code: str) -> Traversable:
    """Where the explanation of `code` is (or would be)."""
    return EXPLANATIONS.joinpath(f"{code}.md")


@cache
def load(code: str) -> Explanation | None:
    """The explanation of `code`, None if it has no file. A file that is not in the format
    raises ValueError naming it."""
    path = path_of(code)
    if not path.is_file():
        return None
    try:
        return parse(path.read_text(encoding="utf-8"))
    except ValueError as exc:
        raise ValueError(f"afsmc/diagnostics/explanations/{code}.md: {exc}") from None


def as_text(code: str, severity: str, title: str, ex: Explanation | None) -> str:
    """What `afsmc explain CODE` prints: the heading, the prose, then the wrong and the
    right example, their blocks indented by four spaces."""
    lines = [f"{code} ({severity}): {title}", ""]
    if ex is None:
        return "\n".join([*lines, f"No explanation is written for {code} yet."])
    lines += [ex.prose, ""]
    for name, section in (("Wrong", ex.wrong), ("Right", ex.right)):
        lines += [f"{name}:", ""]
        for text in _section_text(section):
            lines += [text, ""]
    return "\n".join(lines).rstrip("\n")


def _section_text(section: Section) -> list[str]:
    """A section as text: its blocks indented, its other words as written."""
    out = []
    at = 0
    for m in _BLOCK.finditer(section.markdown):
        if words := section.markdown[at:m.start()].strip():
            out.append(words)
        out.append("\n".join(f"    {line}".rstrip() for line in m.group(2).splitlines()))
        at = m.end()
    if words := section.markdown[at:].strip():
        out.append(words)
    return out
