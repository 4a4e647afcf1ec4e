"""The grammar (afsm.lark) and the LALR parser lark builds from it.

Shared by the parser (text -> parse tree), the syntax-error diagnosis (which replays its
examples through the same parser) and the formatter (which lexes with its terminals).
"""

from __future__ import annotations

import contextvars
import re
from functools import cache
from importlib import resources

import lark
from lark import Token

# The grammar's start rules: a whole file, and one property (`verify --formula`).
STARTS = ["start", "prop"]


def grammar_text() -> str:
    """The text of afsm.lark."""
    return resources.files("afsmc.syntax").joinpath("afsm.lark").read_text(encoding="utf-8")


@cache
def lalr() -> lark.Lark:
    """The LALR parser of the grammar, built once per process."""
    text = grammar_text()
    # cache=True: lark keeps the LALR tables in the temp directory, keyed by the grammar's
    # hash, which saves ~0.15 s at every start of afsmc (lark rebuilds if the file is bad).
    keywords = re.findall(r'"([A-Za-z]+)"', text)
    callbacks = {kw.upper(): _glued for kw in keywords}
    return lark.Lark(text, parser="lalr", propagate_positions=True, maybe_placeholders=False,
                     cache=True, start=STARTS, lexer_callbacks=callbacks)


# The text being lexed, for _glued.
_LEXING: contextvars.ContextVar[str] = contextvars.ContextVar("afsmc_lexing", default="")


class GluedKeyword(Exception):
    """A keyword run into a name (`modeA`); `token` is the keyword's token."""

    def __init__(self, token: Token) -> None:
        super().__init__(str(token))
        self.token = token


def _glued(tok: Token) -> Token:
    """A keyword run into a name (`modeA initial;`): where no name may stand, the
    contextual lexer takes the keyword's letters and a name after them, so the file read
    as `mode A`. A keyword is never followed by a letter, digit or '_'."""
    text, end = _LEXING.get(), tok.end_pos or 0
    if end < len(text) and (text[end].isalnum() or text[end] == "_") and not (
            # `Rmin=?` and `Rmax=?`, as PRISM writes them (`Pmin` is a keyword of its own)
            tok == "R" and re.match(r"m(?:in|ax)(?![\w])", text[end:end + 4])):
        raise GluedKeyword(tok)
    return tok


def parse_tree(text: str, start: str) -> lark.Tree[Token]:
    """The parse tree of `text` from the start rule `start`. Raises lark's UnexpectedInput,
    or GluedKeyword for a keyword run into a name."""
    reset = _LEXING.set(text)
    try:
        return lalr().parse(text, start=start)
    finally:
        _LEXING.reset(reset)
