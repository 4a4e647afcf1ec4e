"""Spellings from other languages (Python, PRISM) that the parser fails on, and hints
that rewrite a mistake with the names and values the author wrote."""

from __future__ import annotations

import re

from afsmc.syntax.errors.before import word_before
from afsmc.syntax.errors.messages import NOT_OPERATOR, OPERATORS
from afsmc.syntax.limits import clip

# A property's query head right before a failing comparison: `P==0.5 [ ... ]`
_QUERY_BEFORE = re.compile(r"\b(?:P|Pmin|Pmax|R|Rmin|Rmax)\s*(?:\{[^{}]*\})?\s*$")
# An update's target right before a failing '=': at the start of an outcome or after ','
_UPDATE_TARGET = re.compile(r"(?:[{;,]|:(?!=))\s*([A-Za-z_][\w.]*)\s*$")
# An update right before an `if`, and the condition after it: `x := e if c`
_UPDATE_BEFORE = re.compile(r"(?<![\w.])([A-Za-z_][\w.]*)\s*(:=|\+=|-=)\s*([^;{},:=]+?)\s*$")
_IF_AFTER = re.compile(r"if\s+([^;{},]+?)\s*(?:[;},]|$)")
# A word with dots after a position, blanks before it
_WORD_AFTER = re.compile(r"\s*([\w.]+)")


def foreign(text: str, pos: int, tok: str, kind: str,
            body: bool = False) -> tuple[str, str, tuple[int, int] | None] | None:
    """(message, hint, the offending word's offsets if not the failing token) for a spelling
    from another language (Python's `and`, `not`, `if ... then`, `x = 1`; an infix `mod`;
    a requirement's `P==0.5`) where the parser fails on it or
    right after it; None otherwise. `body`: the failing token is in an action's or hazard's
    outcomes."""
    word = re.search(r"\b(\w+)\s*$", text[:pos])
    before = word.group(1) if word else ""
    at = (word.start(1), word.end(1)) if word else None
    if kind == "NAME" and tok in ("and", "or"):
        return (f"'{tok}' is not an operator in afsm: write '{'&&' if tok == 'and' else '||'}'",
                OPERATORS, None)
    if kind == "NAME" and tok == "mod":
        return ("afsm has no infix 'mod': write 'mod(a, b)'",
                mod_hint(text, pos, pos + 3), None)
    if body and tok == "=" and (target := _UPDATE_TARGET.search(text, 0, pos)):
        name = clip(target.group(1))
        return ("'=' does not assign in afsm: an update is written 'x := value'",
                f"write '{name} := ...' (or '{name} += ...', '{name} -= ...')", None)
    if before == "not" and kind != "LPAR":
        return NOT_OPERATOR, OPERATORS, at
    if before == "if" or (kind == "NAME" and tok in ("if", "then", "elif")):
        return ("afsm has no 'if ... then ... else': write a conditional as 'COND ? A : B'",
                (_conditional_update(text, pos) if body and tok == "if" else None)
                or "for example 'weight (b > 3 ? 1 : 0)'", at if before == "if" else None)
    if tok in ("==", "!=", "=") and _QUERY_BEFORE.search(text, 0, pos):
        return (f"a requirement compares with <, <=, >= or >, not '{tok}'",
                "write 'P>=0.65 [ ... ]' for a requirement, or 'P=? [ ... ]' for the value", None)
    return None


def hazard_hint(text: str, start: int, pos: int) -> str:
    """For `hazard H from M when G with probability P {` (either order): 'with probability
    (G ? P : 0)', with G and P as written where both are found."""
    brace = text.find("{", pos)
    head = text[start:brace if brace >= 0 else len(text)]
    g = re.search(r"\bwhen\s+(.+?)\s*(?=\bwith\b|$)", head, re.S)
    p = re.search(r"\bwith\s+probability\s+(.+?)\s*(?=\bwhen\b|\bweight\b|$)", head, re.S)
    cond, prob = (" ".join(m.group(1).split()) if m else "" for m in (g, p))
    if not cond or not prob:
        cond, prob = "GUARD", "P"
    return f"for a probability that depends on the state, write 'with probability " \
           f"({cond} ? {prob} : 0)'"


def _conditional_update(text: str, pos: int) -> str | None:
    """The hint for Python's `x := e if c` at `if` (pos): `x := (c ? e : x)`."""
    # (the update is after the last ';', '{', '}' or ',', and its name starts a word)
    segment = max(text.rfind(c, 0, pos) for c in ";{},") + 1
    upd = _UPDATE_BEFORE.search(text, segment, pos)
    cond = _IF_AFTER.match(text, pos)
    if upd is None or cond is None:
        return None
    x, op, e = upd.groups()
    other = x if op == ":=" else "0"
    return f"write '{x} {op} ({cond.group(1)} ? {e} : {other})'"


def mod_hint(text: str, start: int, end: int) -> str:
    """'write mod(a, b)' with the operands around an infix `mod` or '%' where they are
    single names or numbers."""
    a = word_before(text, start)
    b = _WORD_AFTER.match(text, end)
    if a and b:
        return f"write 'mod({a.group(1)}, {b.group(1)})'"
    return "mod(a, b) is the remainder of a divided by b"
