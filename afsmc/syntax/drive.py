"""A faster run of lark's LALR parser over a whole text, giving the tree lark gives.

lark's loop (`ParserState.feed_token` fed by the contextual lexer's generator) costs a
method call, a generator step and several attribute lookups per token and per reduction,
and an expression operand goes through ten unit rules (`?ite: implies`, `?implies:
or_expr`, ...) whose callbacks hand their one child on. This loop reads the same parse
table, the same per-state lexers and the same callbacks, inlines the lexing, and moves a
unit rule's value without calling its callback: half of a large file's parse time.

It only ever succeeds with lark's result. At anything out of the ordinary (no action for a
token, no terminal matches, a callback raising: a keyword run into a name, an expression
nested too deeply) it gives up, and the caller parses the text again with lark itself,
whose exceptions the syntax-error diagnosis reads: a failed parse costs at most twice.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cache
from typing import Any

import lark
from lark import Token, Tree
from lark.parsers.lalr_analysis import Shift


class GiveUp(Exception):
    """The text is not an ordinary parse: ask lark."""


@dataclass(frozen=True)
class _Lexer:
    """One state's lexer: its patterns, token callbacks and the kinds of token it skips
    or counts newlines in."""

    patterns: tuple[Any, ...]
    callbacks: dict[str, Any]
    newlines: frozenset[str]
    ignore: frozenset[str]


@dataclass(frozen=True)
class _Tables:
    # state -> terminal -> a state to shift to (int), or a reduction:
    # (size, nonterminal, callback), callback None for a unit rule that passes its one
    # child on untouched.
    actions: dict[int, dict[str, Any]]
    gotos: dict[int, dict[str, int]]  # state -> nonterminal -> state
    lexers: dict[int, _Lexer]
    token_callbacks: dict[str, Any]  # the parser's callbacks keyed by terminal
    start_states: dict[str, int]
    end_states: dict[str, int]


def _passes_child_on(callback: Any) -> bool:
    """Whether a rule's callback returns its one child itself (a `?rule` of one symbol,
    no alias), for a tree and for a token alike."""
    try:
        tree: Tree[Token] = Tree("probe", [])
        token = Token("PROBE", "probe", 0, 1, 1, 1, 6, 5)
        return bool(callback([tree]) is tree and callback([token]) is token)
    except Exception:
        return False


@cache
def tables(parser: lark.Lark) -> _Tables:
    """The tables of `parser` (built once per parser) in the shape the loop reads."""
    frontend: Any = parser.parser
    table = frontend.parser.parser.parse_table
    callbacks: dict[Any, Any] = frontend.parser.parser.callbacks
    actions: dict[int, dict[str, Any]] = {}
    gotos: dict[int, dict[str, int]] = {}
    for state, row in table.states.items():
        acts: dict[str, Any] = {}
        goes: dict[str, int] = {}
        for symbol, (action, arg) in row.items():
            if action is Shift:
                (acts if symbol.isupper() or symbol == "$END" else goes)[symbol] = arg
                continue
            size = len(arg.expansion)
            callback = callbacks[arg]
            unit = size == 1 and _passes_child_on(callback)
            acts[symbol] = (size, arg.origin.name, None if unit else callback)
        actions[state], gotos[state] = acts, goes
    lexers: dict[int, _Lexer] = {}
    made: dict[int, _Lexer] = {}
    for state, basic in frontend.lexer.lexers.items():
        if id(basic) not in made:
            scanner = basic.scanner
            made[id(basic)] = _Lexer(tuple(scanner._mres), dict(basic.callback),
                                     frozenset(basic.newline_types),
                                     frozenset(basic.ignore_types))
        lexers[state] = made[id(basic)]
    token_callbacks = {k: v for k, v in callbacks.items() if isinstance(k, str)}
    return _Tables(actions, gotos, lexers, token_callbacks, dict(table.start_states),
                   dict(table.end_states))


def parse(parser: lark.Lark, text: str, start: str) -> Any:
    """lark's `parser.parse(text, start=start)`, or GiveUp."""
    t = tables(parser)
    actions, gotos, lexers = t.actions, t.gotos, t.lexers
    token_callbacks = t.token_callbacks
    end_state = t.end_states[start]
    states = [t.start_states[start]]
    values: list[Any] = []
    pos, line, line_start, size = 0, 1, 0, len(text)
    last: Token | None = None
    new_token: Any = Token._future_new  # Token(...) without its keyword-argument checks
    while True:
        # -- the next token, lexed in the context of the state on top
        token: Token | None = None
        while pos < size:
            lexer = lexers[states[-1]]
            for pattern in lexer.patterns:
                m = pattern.match(text, pos)
                if m:
                    break
            else:
                raise GiveUp
            value, kind = m.group(0), m.lastgroup
            ignored = kind in lexer.ignore
            callback = lexer.callbacks.get(kind)
            if not ignored or callback is not None:
                token = new_token(kind, value, pos, line, pos - line_start + 1)
            if kind in lexer.newlines:
                newlines = value.count("\n")
                if newlines:
                    line += newlines
                    line_start = pos + value.rindex("\n") + 1
            pos += len(value)
            if token is not None:
                token.end_line, token.end_column, token.end_pos = line, pos - line_start + 1, pos
                if callback is not None:
                    token = callback(token)
                if not ignored:
                    break
                token = None
        is_end = token is None
        if token is None:
            token = (Token.new_borrow_pos("$END", "", last) if last is not None
                     else Token("$END", "", 0, 1, 1))
        last = token
        kind = token.type
        # -- reductions, then the shift (or, at the end, the accepting reduction)
        while True:
            action = actions[states[-1]].get(kind)
            if action is None:
                raise GiveUp
            if type(action) is int:
                if is_end:
                    raise GiveUp
                states.append(action)
                callback = token_callbacks.get(kind)
                values.append(token if callback is None else callback(token))
                break
            n, origin, callback = action
            if callback is None:
                del states[-1]
            else:
                if n:
                    children = values[-n:]
                    del states[-n:]
                    del values[-n:]
                else:
                    children = []
                values.append(callback(children))
            states.append(gotos[states[-1]][origin])
            if is_end and states[-1] == end_state:
                return values[-1]
