"""The grammar (afsm.lark) and the LALR parser lark builds from it.

Shared by the parser (text -> parse tree), the syntax-error diagnosis (which replays its
examples through the same parser) and the formatter (which lexes with its terminals).
"""

from __future__ import annotations

import contextvars
import re
from collections.abc import Callable
from functools import cache
from importlib import resources
from typing import Any

import lark
from lark import Token, Tree
from lark.parse_tree_builder import PropagatePositions

from afsmc.syntax import drive
from afsmc.syntax.limits import MAX_DEPTH

# The grammar's start rules: a whole file, and one property (`verify --formula`).
STARTS = ["start", "prop"]
# The grammar's expression rules (the ones that build an operator node): each is one level
# of nesting (E113).
EXPR_RULES = frozenset({"arith", "compare", "and_", "or_", "implies", "ite", "neg", "not_",
                        "call", "mode_in"})


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
    parser = lark.Lark(text, parser="lalr", propagate_positions=True, maybe_placeholders=False,
                       cache=True, start=STARTS, lexer_callbacks=callbacks)
    _faster_positions(parser)
    _count_depth(parser)
    return parser


def _faster_positions(parser: lark.Lark) -> None:
    """Replace lark's PropagatePositions, the outermost step of each rule's callback (the
    parser is LALR, so nothing is ambiguous), with `_positions`, which computes the same
    meta with a fifth of the attribute lookups: it was a fifth of a large file's parse."""
    callbacks: dict[Any, Callable[[list[Any]], Any]] = parser._callbacks
    for rule, build in list(callbacks.items()):
        if type(build) is PropagatePositions and build.node_filter is None:
            callbacks[rule] = _positions(build.node_builder)


def _positions(build: Callable[[list[Any]], Any]) -> Callable[[list[Any]], Any]:
    """lark's PropagatePositions for children that are tokens and trees: a node starts
    where its first child's container starts (the child itself, or the rule it was inlined
    from) and ends where its last child's container ends; a node passed on by a `?rule`
    keeps its own start and end but takes the new container's."""
    def node(children: list[Any]) -> Any:
        res = build(children)
        if not isinstance(res, Tree) or (len(children) == 1 and children[0] is res):
            # (a `?rule` passing its one child on: its container is the child itself)
            return res
        meta: Any = res.meta
        for c in children:
            if isinstance(c, Tree):
                m: Any = c._meta
                if m is not None and not m.empty:
                    line, column, pos = m.container_line, m.container_column, m.container_start_pos
                    break
            elif isinstance(c, Token):
                line, column, pos = c.line, c.column, c.start_pos
                break
        else:
            return res
        if not hasattr(meta, "line"):
            meta.line, meta.column, meta.start_pos, meta.empty = line, column, pos, False
        meta.container_line, meta.container_column, meta.container_start_pos = line, column, pos
        for c in reversed(children):
            if isinstance(c, Tree):
                m = c._meta
                if m is not None and not m.empty:
                    line, column, pos = (m.container_end_line, m.container_end_column,
                                         m.container_end_pos)
                    break
            elif isinstance(c, Token):
                line, column, pos = c.end_line, c.end_column, c.end_pos
                break
        if not hasattr(meta, "end_line"):
            meta.end_line, meta.end_column, meta.end_pos, meta.empty = line, column, pos, False
        meta.container_end_line, meta.container_end_column = line, column
        meta.container_end_pos = pos
        return res
    return node


class TooDeep(Exception):
    """An expression nested deeper than MAX_DEPTH; `start` is where it starts."""

    def __init__(self, start: int) -> None:
        super().__init__(start)
        self.start = start


def _count_depth(parser: lark.Lark) -> None:
    """Make the parser count each expression node's nesting as it builds it, and stop the
    parse (TooDeep) at the first node nested deeper than MAX_DEPTH: a chain of a million
    operators is refused after 5,000 of them, in bounded time and memory, and no later
    (recursive) stage sees a deeper one."""
    callbacks: dict[Any, Callable[[list[Any]], Any]] = parser._callbacks
    for rule, build in list(callbacks.items()):
        if (rule.alias or rule.origin.name) in EXPR_RULES:
            callbacks[rule] = _counting(build)


def _counting(build: Callable[[list[Any]], Any]) -> Callable[[list[Any]], Any]:
    def node(children: list[Any]) -> Any:
        tree = build(children)
        depth = 1 + max((getattr(c, "afsmc_depth", 0) for c in children), default=0)
        if depth > MAX_DEPTH:
            raise TooDeep(tree.meta.start_pos)
        setattr(tree, "afsmc_depth", depth)  # noqa: B010 (lark's Tree declares no such field)
        return tree
    return node


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


def parse_fast(text: str, start: str, builder: Any) -> Any:
    """The AST of `text` from the start rule `start`, built by `builder` (a
    afsmc.syntax.build.Builder) in the parser's own loop, or None where that loop gives up
    (a syntax error, a keyword run into a name, an expression nested too deeply, ...):
    then `parse_tree` and the builder's `build` say what is wrong, or give the same AST.
    Diagnostics the builder reported before a None are not the text's: give it a reporter
    of its own."""
    reset = _LEXING.set(text)
    try:
        return drive.parse(lalr(), text, start, builder, EXPR_RULES)
    except Exception:  # anything unusual: lark's own parse decides
        return None
    finally:
        _LEXING.reset(reset)


def parse_tree(text: str, start: str) -> lark.Tree[Token]:
    """lark's parse tree of `text` from the start rule `start`. Raises lark's
    UnexpectedInput, or GluedKeyword for a keyword run into a name, or TooDeep."""
    reset = _LEXING.set(text)
    try:
        return lalr().parse(text, start=start)
    finally:
        _LEXING.reset(reset)
