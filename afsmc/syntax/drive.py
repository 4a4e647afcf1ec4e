"""A faster run of lark's LALR parser over a whole text that builds the AST directly.

lark's loop (`ParserState.feed_token` fed by the contextual lexer's generator) costs a
method call, a generator step and several attribute lookups per token and per reduction,
then builds a parse tree with positions on every node, which a second pass turns into the
AST. This loop reads the same parse table and the same per-state lexers, inlines the
lexing, moves a unit rule's value (`?ite: implies`, ten per expression operand) without a
call, and at every other reduction calls the Builder's method for the rule at once, with
the rule's children filtered and inlined as lark would and its positions taken from a
stack kept beside the values (a node spans from where its first child's container starts
to where its last child's ends; `( e )` passed on by a `?rule` keeps its own span but its
container is the brackets). The AST, every span and every diagnostic are the ones the
tree and `Builder.build` give.

It only ever succeeds with that result. At anything out of the ordinary (no action for a
token, no terminal matches, a callback raising: a keyword run into a name, an expression
nested too deeply) it gives up, and the caller parses the text again with lark itself,
whose exceptions the syntax-error diagnosis reads: a failed parse costs at most twice.
"""

from __future__ import annotations

import re
from dataclasses import dataclass
from functools import cache
from typing import Any

import lark
from lark import Token, Tree
from lark.parsers.lalr_analysis import Shift

from afsmc.syntax.build import SIZED, Builder, rule_methods
from afsmc.syntax.limits import MAX_DEPTH

# How a reduction builds its value (the third item of a reduce action; None: a unit rule
# that passes its one child on untouched, container included).
INLINE, PASS, BUILD = 0, 1, 2
# The white space the grammar ignores everywhere (`%ignore WS`): the loop skips it without
# asking the state's lexer, as no other terminal starts with it.
BLANKS = frozenset(" \t\f\r\n")


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
    # (size, nonterminal, k) for a unit rule that passes its one child on untouched, with
    # k = 1 if the rule counts a level of nesting (`?ite: implies`) else 0,
    # else (size, nonterminal, (how, children kept, method, counts depth)); children kept
    # is None when all are, else (index, inlined) pairs.
    actions: dict[int, dict[str, Any]]
    gotos: dict[int, dict[str, int]]  # state -> nonterminal -> state
    lexers: dict[int, _Lexer]
    token_callbacks: dict[str, Any]  # the parser's callbacks keyed by terminal
    start_states: dict[str, int]
    end_states: dict[str, int]
    blank: Any  # WS's pattern's match
    dropped: frozenset[str]  # terminals no rule keeps as a child: no Token is made for them


def _passes_child_on(callback: Any) -> bool:
    """Whether a rule's callback returns its one child itself (a `?rule` of one symbol,
    no alias), for a tree and for a token alike."""
    try:
        tree: Tree[Token] = Tree("probe", [])
        token = Token("PROBE", "probe", 0, 1, 1, 1, 6, 5)
        return bool(callback([tree]) is tree and callback([token]) is token)
    except Exception:
        return False


def _reduction(rule: Any, callback: Any, expr_rules: frozenset[str]) -> Any:
    """How the loop reduces by `rule` (see _Tables.actions)."""
    size = len(rule.expansion)
    if size == 1 and _passes_child_on(callback):
        return 0
    keep_all = rule.options.keep_all_tokens
    expansion: list[Any] = rule.expansion
    include = tuple((i, not sym.is_term and sym.name.startswith("_"))
                    for i, sym in enumerate(expansion)
                    if keep_all or not (sym.is_term and sym.filter_out))
    kept = None if len(include) == size and not any(x for _, x in include) else include
    name = rule.alias or rule.origin.name
    if rule.origin.name.startswith("_"):
        how = INLINE
    elif rule.options.expand1 and not rule.alias:
        if size == 1 and kept is None and name in expr_rules:
            return 1  # passes its one child on, one level deeper (`?ite: implies`)
        how = PASS
    else:
        how = BUILD
    return (how, kept, rule_methods(Builder).get(name), name in expr_rules)


@cache
def tables(parser: lark.Lark, expr_rules: frozenset[str]) -> _Tables:
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
            acts[symbol] = (len(arg.expansion), arg.origin.name,
                            _reduction(arg, callbacks[arg], expr_rules))
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
    (ws,) = (term for term in parser.terminals if term.name == "WS")
    blank = re.compile(ws.pattern.to_regexp())
    # (skipping it is what every state's lexer does: WS ignored, no callback, and no
    # other terminal matches a blank)
    assert all(not (lx.ignore & set(lx.callbacks)) for lx in lexers.values())
    assert all("WS" in lx.ignore and "WS" not in lx.callbacks and all(
        next(m.lastgroup for p in lx.patterns if (m := p.match(c))) == "WS" for c in BLANKS)
        for lx in lexers.values())
    assert all(blank.fullmatch(c) for c in BLANKS) and not blank.match("\v")
    symbols: Any = [(rule, sym) for rule in parser.rules for sym in rule.expansion]
    kept = {sym.name for rule, sym in symbols if sym.is_term and (rule.options.keep_all_tokens or not sym.filter_out)}
    dropped = frozenset(term.name for term in parser.terminals
                        if term.name not in kept and term.name not in token_callbacks
                        and all(term.name not in lx.callbacks for lx in lexers.values()))
    return _Tables(actions, gotos, lexers, token_callbacks, dict(table.start_states),
                   dict(table.end_states), blank.match, dropped)


def _filtered(raw: list[Any], kept: tuple[tuple[int, bool], ...]) -> list[Any]:
    """A rule's children as lark's child filter gives them: anonymous tokens left out,
    an inlined rule's (a list) spliced in; a leading one is extended in place, as lark
    does, so that a long left-recursive list costs linear time."""
    out: list[Any] | None = None
    for i, inlined in kept:
        if inlined:
            if out is None:
                out = raw[i]
            else:
                out += raw[i]
        elif out is None:
            out = [raw[i]]
        else:
            out.append(raw[i])
    return [] if out is None else out


def _reduce(builder: Builder, red: Any, raw: list[Any], places: list[Any]) -> tuple[Any, Any]:
    """The value of a reduction and its place (start, line, column, end, end line, end
    column, nesting depth), from its children and theirs."""
    how, kept, method, counts = red
    first, last = places[0], places[-1]
    depth = _depth(places) if counts else 0
    place = (first[0], first[1], first[2], last[3], last[4], last[5], depth)
    children = raw if kept is None else _filtered(raw, kept)
    if how == BUILD:
        if method is None:
            raise GiveUp  # a rule the builder has no method for: lark's tree says what
        return method(builder, place, children), place
    if how == INLINE:
        return children, place
    if len(children) != 1:  # a `?rule` of several children builds a node
        if method is None:
            raise GiveUp
        return method(builder, place, children), place
    child = children[0]
    if isinstance(child, Token):  # a token passed on keeps its own place
        return child, (child.start_pos, child.line, child.column, child.end_pos,
                       child.end_line, child.end_column, 0)
    if not counts:  # the child's nesting, not the rule's (`( e )`)
        depth = places[next(i for i, c in enumerate(raw) if c is child)][6]
    return child, (*place[:6], depth)


def parse(parser: lark.Lark, text: str, start: str, builder: Builder,
          expr_rules: frozenset[str]) -> Any:
    """The AST of `text` from `start` (what `builder.build` gives lark's tree), or GiveUp."""
    t = tables(parser, expr_rules)
    actions, gotos, lexers, token_callbacks = t.actions, t.gotos, t.lexers, t.token_callbacks
    end_state, states = t.end_states[start], [t.start_states[start]]
    values: list[Any] = []
    places: list[Any] = []  # each value's place (see _reduce)
    pos, line, line_start, size = 0, 1, 0, len(text)
    new_token: Any = Token._future_new  # Token(...) without its keyword-argument checks
    sized, check_size = SIZED, builder.__default_token__
    blank, blanks, dropped = t.blank, BLANKS, t.dropped
    units: dict[tuple[int, int, str], tuple[int, int]] = {}
    while True:
        # -- the next token, lexed in the context of the state on top
        token: Any = None  # a Token, or a dropped terminal's name
        while pos < size:
            if text[pos] in blanks:  # white space: skipped in every state, no token
                value = blank(text, pos).group(0)
                newlines = value.count("\n")
                if newlines:
                    line += newlines
                    line_start = pos + value.rindex("\n") + 1
                pos += len(value)
                continue
            lexer = lexers[states[-1]]
            for pattern in lexer.patterns:
                m = pattern.match(text, pos)
                if m:
                    break
            else:
                raise GiveUp
            value, kind = m.group(0), m.lastgroup
            start_pos, start_line, start_column = pos, line, pos - line_start + 1
            if kind in lexer.newlines:
                newlines = value.count("\n")
                if newlines:
                    line += newlines
                    line_start = pos + value.rindex("\n") + 1
            pos += len(value)
            if kind in lexer.ignore:  # (a comment; no ignored terminal has a callback)
                continue
            place = (start_pos, start_line, start_column, pos, line, pos - line_start + 1, 0)
            if kind in dropped:  # no rule reads it: its place will do
                token = kind
                break
            token = new_token(kind, value, start_pos, start_line, start_column)
            token.end_line, token.end_column, token.end_pos = line, place[5], pos
            callback = lexer.callbacks.get(kind)
            if callback is not None:
                token = callback(token)
            break
        is_end = token is None
        kind = "$END" if token is None else token if type(token) is str else token.type
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
                if callback is not None:
                    token = callback(token)
                if kind in sized:
                    token = check_size(token)
                values.append(token)
                places.append(place)
                break
            n, origin, red = action
            if type(red) is int:  # a run of unit rules (see _units)
                key = (states[-2], states[-1], kind)
                top, deeper = units[key] if key in units else _units(units, t, key, end_state)
                states[-1] = top
                if deeper:
                    places[-1] = _deeper(places[-1], deeper)
                if is_end and top == end_state:
                    return values[-1]
                continue
            if n:
                raw, at = values[-n:], places[-n:]
                del states[-n:], values[-n:], places[-n:]
                how, kept, method, counts = red
                if how == BUILD and method is not None:  # the common case, inline
                    first, end = at[0], at[-1]
                    node_place = (first[0], first[1], first[2], end[3], end[4], end[5],
                                  _depth(at) if counts else 0)
                    value = method(builder, node_place, raw if kept is None
                                   else _filtered(raw, kept))
                else:
                    value, node_place = _reduce(builder, red, raw, at)
                values.append(value)
                places.append(node_place)
            else:  # an empty file's `start`
                _reduce_empty(builder, red, values, places)
            states.append(gotos[states[-1]][origin])
            if is_end and states[-1] == end_state:
                return values[-1]


def _depth(places: list[Any]) -> int:
    """The nesting of an expression node: one more than its deepest child's."""
    depth: int = 1 + max(p[6] for p in places)
    if depth > MAX_DEPTH:
        raise GiveUp  # lark's parse raises TooDeep at the same node
    return depth


def _units(known: dict[tuple[int, int, str], tuple[int, int]], t: _Tables,
           key: tuple[int, int, str], end_state: int) -> tuple[int, int]:
    """The state on top after the unit rules that reduce from `key` (state below, state
    on top, terminal), up to the first other action or the end state, and how many
    levels of nesting they count; kept in `known`. A unit rule replaces the state on top
    only, so the run depends on `key` alone."""
    below, top, kind = key
    actions, gotos = t.actions, t.gotos
    deeper = 0
    while True:
        action = actions[top].get(kind)
        if action is None or type(action) is int or type(action[2]) is not int:
            break
        deeper += action[2]
        top = gotos[below][action[1]]
        if top == end_state:
            break
    known[key] = (top, deeper)
    return top, deeper


def _deeper(place: Any, levels: int) -> Any:
    """`place` nested `levels` deeper (a value passed on by `?ite: implies` and the like)."""
    depth = place[6] + levels
    if depth > MAX_DEPTH:
        raise GiveUp  # lark's parse raises TooDeep at the same node
    return (*place[:6], depth)


def _reduce_empty(builder: Builder, red: Any, values: list[Any], places: list[Any]) -> None:
    """Push the value of a rule that matched nothing (an empty file's `start`)."""
    how, _, method, _ = red
    if how != BUILD or method is None:
        raise GiveUp
    values.append(method(builder, None, []))
    places.append((0, 1, 1, 0, 1, 1, 0))  # never read: an empty rule is the root
