"""Wording of syntax diagnostics: messages the resolver repeats, and how the grammar's
terminals are named in "expected ..." hints."""

from __future__ import annotations

import lark
from lark import Token

from afsmc.syntax.grammar import lalr
from afsmc.syntax.limits import clip

# Also said by the resolver, where `F F (x == 1)` and `not (x == 1)` parse as calls.
NESTED_TEMPORAL = ("temporal operators (F, G, X, U) do not nest: one applies to state formulas "
                   "(labels, comparisons, and/or/not of them)")
NOT_OPERATOR = "'not' is not an operator in afsm: write '!'"
OPERATORS = "afsm's boolean operators are '&&' (and), '||' (or), '!' (not) and '=>' (implies)"

# Human names for the grammar's terminals, used in "expected ..." messages.
_TOKEN_NAMES = {
    "NAME": "a name", "NUMBER": "a number", "ESCAPED_STRING": "a quoted string",
    "SEMICOLON": "';'", "COLON": "':'", "COMMA": "','", "LBRACE": "'{'", "RBRACE": "'}'",
    "LPAR": "'('", "RPAR": "')'", "LSQB": "'['", "RSQB": "']'", "EQUAL": "'='",
    "__ANON_0": "'..'", "$END": "end of file", "DOT": "'.'", "STAR": "'*'",
}


def expected_hint(expected: set[str] | frozenset[str], the_end: str = "end of file") -> str:
    """'expected a name, ';', ...' for the terminals the parser would have accepted (at
    most eight named)."""
    names = sorted({the_end if t == "$END" else _TOKEN_NAMES.get(t, _literal_name(t))
                    for t in expected})
    if len(names) > 8:
        names = [*names[:8], "..."]
    return "expected " + ", ".join(names)


def _literal_name(terminal: str) -> str:
    try:
        pattern = lalr().get_terminal(terminal).pattern
    except KeyError:
        return terminal
    if isinstance(pattern, lark.lexer.PatternStr):
        return repr(pattern.value)
    return terminal.lower()


def found(tok: Token, the_end: str) -> str:
    """The failing token as quoted in a message: its text, or `the_end` at the end."""
    return the_end if tok.type == "$END" else repr(clip(str(tok)))
