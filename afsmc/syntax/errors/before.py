"""What stands right before the place a parse failed, found in time linear in the text.

A pattern that must end at a position, searched for from the start of the text, is tried
at every offset and read on to the position from each: a 40,000-character name before the
failure makes that 800 million steps. Each search here first finds the earliest offset a
match can start at, from the position backwards, and searches from there.
"""

from __future__ import annotations

import re

# Operands (a name, a number, a quoted label, a closing bracket) that end right before a
# position, blanks between.
_OPERAND = re.compile(r'([A-Za-z_][\w.]*|\d[\w.]*|"[^"]*"|\))\s*\Z')
# The keywords that decide whether an action's header has its weight before a `when`.
_HEADER_WORD = re.compile(r"\b(?:action|hazard|weight|when)\b")
_HAZARD = re.compile(r"\bhazard\b")
# A word, with dots, and the blanks after it up to the position.
_WORD = re.compile(r"([\w.]+)\s*\Z")


def run_start(text: str, pos: int) -> int:
    """Where the word (letters, digits, '_', '.') that ends at `pos`, blanks after it
    skipped, starts; `pos` itself after the blanks if no word ends there."""
    j = pos
    while j > 0 and text[j - 1].isspace():
        j -= 1
    k = j
    while k > 0 and (text[k - 1].isalnum() or text[k - 1] in "_."):
        k -= 1
    return k


def operand_before(text: str, pos: int) -> re.Match[str] | None:
    """The operand that ends right before `pos` (group 1), as the pattern
    `(name|number|"label"|')') blanks* end` finds it searched from the start of the text."""
    j = pos
    while j > 0 and text[j - 1].isspace():
        j -= 1
    start = run_start(text, pos)
    if j > 0 and text[j - 1] == '"':
        start = max(text.rfind('"', 0, j - 1), 0)
    elif j > 0 and text[j - 1] == ")":
        start = j - 1
    return _OPERAND.search(text, start, pos)


def word_before(text: str, pos: int) -> re.Match[str] | None:
    """The word with dots (group 1) that ends right before `pos`, blanks after it."""
    return _WORD.search(text, run_start(text, pos), pos)


def _segment_start(text: str, pos: int, stops: str) -> int:
    """Just after the last of the characters `stops` before `pos` (0 if none)."""
    return max(text.rfind(c, 0, pos) for c in stops) + 1


def weight_before_guard(text: str, pos: int) -> bool:
    """Does an action's or hazard's header with its weight (and no `when` between the
    keyword and the weight) run up to `pos`, with no '{', '}' or ';' in it?"""
    ready = False  # an `action`/`hazard` seen, and no `when` after it yet
    for m in _HEADER_WORD.finditer(text, _segment_start(text, pos, "{};"), pos):
        word = m.group()
        if word in ("action", "hazard"):
            ready = True
        elif word == "when":
            ready = False
        elif ready:  # weight
            return True
    return False


def hazard_header(text: str, pos: int) -> int | None:
    """Where the hazard header that runs up to `pos` starts: the first `hazard` from which
    the text up to `pos` is characters other than '{', '}' and ';', and '{...}' groups
    without braces inside (mode sets); None if there is none."""
    # Back from pos over that text, noting the groups: a `hazard` inside one is no start.
    groups: list[tuple[int, int]] = []
    semicolon = text.rfind(";", 0, pos)  # (a ';' inside a group does not stop it)
    k = pos
    while True:
        if semicolon >= k:
            semicolon = text.rfind(";", 0, k)
        b = max(text.rfind("{", 0, k), text.rfind("}", 0, k), semicolon)
        if b < 0 or text[b] != "}":  # (b < 0: nothing stops it before pos)
            k = b + 1
            break
        opening = max(text.rfind("{", 0, b), text.rfind("}", 0, b))
        if opening < 0 or text[opening] != "{":
            k = b + 1
            break
        groups.append((opening, b + 1))
        k = opening
    inside = sorted(groups)
    g = 0
    for m in _HAZARD.finditer(text, k, pos):
        while g < len(inside) and inside[g][1] <= m.start():
            g += 1
        if g < len(inside) and inside[g][0] < m.start():
            continue
        return m.start()
    return None
