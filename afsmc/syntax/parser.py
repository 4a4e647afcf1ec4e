"""Parsing: text -> :class:`afsmc.syntax.ast.Module`, or diagnostics written for people."""

from __future__ import annotations

import contextvars
import re
from collections.abc import Iterator
from dataclasses import dataclass, field
from functools import cache, lru_cache
from importlib import resources
from typing import Any, cast

import lark
from lark import Token, Transformer, v_args
from lark.exceptions import UnexpectedCharacters, UnexpectedInput, UnexpectedToken

from afsmc.diagnostics import BOM, CompileError, Related, Reporter, Source, Span
from afsmc.syntax import ast

# Human names for the grammar's terminals, used in "expected ..." messages.
_TOKEN_NAMES = {
    "NAME": "a name", "NUMBER": "a number", "ESCAPED_STRING": "a quoted label name",
    "SEMICOLON": "';'", "COLON": "':'", "COMMA": "','", "LBRACE": "'{'", "RBRACE": "'}'",
    "LPAR": "'('", "RPAR": "')'", "LSQB": "'['", "RSQB": "']'", "EQUAL": "'='",
    "__ANON_0": "'..'", "$END": "end of file", "DOT": "'.'", "STAR": "'*'",
}

# Also said by the resolver, where `F F (x == 1)` and `not (x == 1)` parse as calls.
NESTED_TEMPORAL = ("temporal operators (F, G, X, U) do not nest: one applies to state formulas "
                   "(labels, comparisons, and/or/not of them)")
NOT_OPERATOR = "'not' is not an operator in afsm: write '!'"
OPERATORS = "afsm's boolean operators are '&&' (and), '||' (or), '!' (not) and '=>' (implies)"

_E115 = ("E115", NESTED_TEMPORAL)

_MISSING_SEMICOLON = (("E102", "missing ';' at the end of the declaration"),
                      ("E116", "missing ';' at the end of the outcome"))
_E120 = ("E120", "the guard comes before the weight: 'action NAME in MODES when GUARD "
                "weight W { ... }'")

# Common mistakes, each learnt from examples (lark's match_examples): the parser
# state where an example fails identifies the mistake, whatever the names in it.
_EXAMPLES: dict[tuple[str, str], list[str]] = {
    ("E102", "missing ';' at the end of the declaration"): [
        "const int A = 1\nconst int B = 2;",
        "param int A = 1\nvar x : [0..1];",
        "var x : [0..1] init 0\nmode A;",
        "var x : [0..1]\nmode A;",
        "mode A = 0\nmode B;",
        "mode A = 0 initial\nmode B;",
        "label a = true\nlabel b = true;",
        "formula f = 1\nlabel b = true;",
        "machine m\nmode A;",
    ],
    # Before '}': the last outcome of an action or hazard body lacks its ';'.
    ("E116", "missing ';' at the end of the outcome"): [
        "action A in S { goto B }",
        "action A in S { x := 1, goto B }",
        "action A in S { 0.5: goto B; 0.5: skip }",
        "action A in S { skip }",
        "hazard H from * with probability 0.1 { goto B }",
        # ... and after each way an update's expression can end
        "action A in S { x := x }",
        "action A in S { x := 1 - x }",
        "action A in S { x += K }",
        "action A in S { x += 1 }",
        "action A in S { x := 1 }",
        "action A in S { b := !b }",
        "action A in S { b := x == 1 }",
        "action A in S { x := min(x, 1) }",
        "action A in S { x := (x) }",
        "action A in S { x := b ? 1 : 0 }",
        "action A in S { p := (1, 2) }",
        "action A in S { x := p.x }",
        "action A in S { 0.5: x += 2 }",
        "action A in S { 0.5: x := 2, goto B; 0.5: x := y }",
    ],
    ("E103", "'=' is not a comparison; write '==' to compare"): [
        "label a = x = 1;",
        "formula f = x = 1;",
        "action A in S when x = 1 { skip; }",
        "action A in S weight x = 1 { skip; }",
        "action A in S when mode = A { skip; }",  # PRISM's own spelling
        "label a = mode = A;",
    ],
    _E115: [
        'property p = P=? [ F F "l" ];',
        'property p = P=? [ X X "l" ];',
        'property p = P=? [ G F "l" ];',
        'property p = P=? [ F G x > 1 ];',
    ],
    ("E104", "a bounded integer is written [low..high]"): [
        "var x : [0, 3];",
        "var x : [0 , 3] init 0;",
    ],
    ("E105", "variables have a range [low..high] or type bool, not a type name"): [
        "var x : int;",
        "var x : double;",
        "var x : prob;",
    ],
    ("E106", "an outcome is written 'probability: updates;'"): [
        "action A in S { 0.5 goto B; }",
        "action A in S { p goto B; }",
    ],
    ("E107", "updates of one outcome are separated by ','"): [
        "action A in S { 0.5: goto B x := 1; }",
        "action A in S { goto B x := 1; }",
    ],
    _E120: [
        "action A in S weight 1 when x > 1 { skip; }",
        "action A in * weight x when x > 1 { skip; }",
    ],
    ("E108", "an action needs its modes: 'action NAME in MODE { ... }'"): [
        "action A { skip; }",
        "action A when x > 1 { skip; }",
    ],
    ("E109", "an action's body is a block in braces"): [
        "action A in S goto B;",
        "action A in S weight 1 goto B;",
    ],
}


# How deeply an expression may nest: each operator of a chain `a + b + c ...` (or `- - x`,
# `!!b`, ...) is one level. Every stage walks expressions recursively; afsmc.stack gives them
# the stack for this (E113 beyond it).
MAX_DEPTH = 5000
# The grammar's expression rules (the ones that build an operator node).
_EXPR_RULES = frozenset({"arith", "compare", "and_", "or_", "implies", "ite", "neg", "not_",
                         "call", "mode_in"})

# The grammar's start rules: a whole file, and one property (`verify --formula`).
_STARTS = ["start", "prop"]
_CLOSERS = {"{": ("}", "RBRACE"), "(": (")", "RPAR"), "[": ("]", "RSQB")}
_DECL_KEYWORDS = frozenset({"machine", "const", "param", "var", "mode", "action", "hazard",
                            "formula", "label", "rewards", "property"})


@cache
def _parser() -> lark.Lark:
    text = resources.files("afsmc.syntax").joinpath("afsm.lark").read_text(encoding="utf-8")
    # cache=True: lark keeps the LALR tables in the temp directory, keyed by the grammar's
    # hash, which saves ~0.15 s at every start of afsmc (lark rebuilds if the file is bad).
    keywords = re.findall(r'"([A-Za-z]+)"', text)
    callbacks = {kw.upper(): _glued for kw in keywords}
    return lark.Lark(text, parser="lalr", propagate_positions=True, maybe_placeholders=False,
                     cache=True, start=_STARTS, lexer_callbacks=callbacks)


# The text being lexed, for _glued.
_LEXING: contextvars.ContextVar[str] = contextvars.ContextVar("afsmc_lexing", default="")


class _Glued(Exception):
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
        raise _Glued(tok)
    return tok


def grammar_text() -> str:
    return resources.files("afsmc.syntax").joinpath("afsm.lark").read_text(encoding="utf-8")


def parse(text: str, path: str = "<input>") -> ast.Module:
    """Parse one file. Raises CompileError with a single syntax diagnostic on failure."""
    return _parse_module(text, path)


# The AST is immutable, and a sweep loads one text at every value of a constant (0.2 s of
# the UAV's 0.25 s load is parsing): the last few parses are kept.
@lru_cache(maxsize=4)
def _parse_module(text: str, path: str) -> ast.Module:
    return cast(ast.Module, _parse(text, path, "start"))


def parse_property(text: str, path: str = "--formula") -> ast.PQuery | ast.RQuery:
    """Parse one property formula on its own (`P=? [ F "done" ]`), so that a syntax error
    speaks only of the formula. Raises CompileError like :func:`parse`."""
    return cast("ast.PQuery | ast.RQuery", _parse(text, path, "prop"))


def _parse(text: str, path: str, start: str) -> Any:
    source = Source(path, text)
    reporter = Reporter()
    try:
        # A leading byte-order mark lexes as a blank, which keeps every offset as in `text`.
        lexed = " " + text[1:] if text.startswith(BOM) else text
        reset = _LEXING.set(lexed)
        try:
            tree = _parser().parse(lexed, start=start)
        finally:
            _LEXING.reset(reset)
    except _Glued as exc:
        tok = exc.token
        end = tok.end_pos or 0
        word = re.match(r"\w*", text[end:])
        rest = word.group() if word else ""
        reporter.error("E122", f"'{tok}{rest}' is not a keyword, and no name may stand here",
                       Span.at_offset(source, tok.start_pos or 0, end + len(rest)),
                       hint=f"if the keyword '{tok}' is meant, put a space after it: "
                            f"'{tok} {rest}'; else check the spelling")
        raise CompileError(reporter.diagnostics) from None
    except UnexpectedInput as exc:
        _report_syntax_error(exc, source, reporter, formula=start == "prop")
        raise CompileError(reporter.diagnostics) from None
    if _too_deep(tree, source, reporter):
        raise CompileError(reporter.diagnostics)
    builder = _Builder(source, reporter)
    try:
        node = builder.transform(tree)
    except lark.exceptions.VisitError as exc:
        if isinstance(exc.orig_exc, CompileError):
            raise exc.orig_exc from None
        raise
    if reporter.has_errors:
        raise CompileError(reporter.diagnostics)
    return node


def _too_deep(tree: lark.Tree[Token], source: Source, reporter: Reporter) -> bool:
    """E113 for each expression nested deeper than MAX_DEPTH (iterative, before the
    recursive tree-to-AST step would fail on it)."""
    # (node, its depth within the outermost expression around it, that expression)
    stack: list[tuple[lark.Tree[Token], int, lark.Tree[Token] | None]] = [(tree, 0, None)]
    reported: set[int] = set()
    while stack:
        node, depth, top = stack.pop()
        if node.data in _EXPR_RULES:
            top = top or node
            depth += 1
        if depth > MAX_DEPTH and top is not None:
            if id(top) not in reported:
                reported.add(id(top))
                reporter.error(
                    "E113", f"this expression nests more than {MAX_DEPTH} levels deep",
                    Span.at_offset(source, top.meta.start_pos),
                    hint=f"afsmc supports expressions up to {MAX_DEPTH} levels: each operator "
                    "of a chain like 'a + b + c' or '- - x' is one; shorten it (e.g. "
                    "'x * 0.1 + x * 0.1' is 'x * 0.2')")
            continue
        stack.extend((c, depth, top) for c in node.children if isinstance(c, lark.Tree))
    return bool(reported)


@dataclass
class _Scan:
    """What precedes an offset: the end of the last token, the brackets still open
    (innermost last) and the first token of every line."""

    last_end: int = 0
    open: list[tuple[str, int]] = field(default_factory=list)
    line_heads: dict[int, tuple[int, str]] = field(default_factory=dict)  # line -> (offset, text)


def tokens(text: str, start: int = 0, end: int | None = None) -> Iterator[tuple[int, int]]:
    """(start, end) of each token of text[start:end], skipping whitespace and comments.
    Only positions and brackets matter to its users: `<=` may come out as two tokens.
    Not the grammar's lexer (which fmt uses): this one must go on through text that does not
    lex, as it scans the input of a syntax error."""
    end = len(text) if end is None else end
    i = start
    while i < end:
        c = text[i]
        if c.isspace() or c == BOM:
            i += 1
            continue
        if text.startswith("//", i):
            j = text.find("\n", i)
            i = end if j < 0 else j
            continue
        if text.startswith("/*", i):
            j = text.find("*/", i + 2)
            i = end if j < 0 else j + 2
            continue
        j = i + 1
        if c == '"':
            j = _string_end(text, i, end) + 1
        elif c.isalnum() or c == "_":
            while j < end and (text[j].isalnum() or text[j] == "_"):
                j += 1
        j = min(j, end)
        yield i, j
        i = j


def _string_end(text: str, start: int, end: int | None = None) -> int:
    """Where the label name opened by the '"' at `start` closes: the offset of its closing
    '"', or of the newline or end that comes first (a quoted name does not span lines)."""
    end = len(text) if end is None else end
    j = start + 1
    while j < end and text[j] not in '"\n':
        j += 2 if text[j] == "\\" else 1
    return j


def flat_text(text: str, start: int, end: int,
              site: tuple[int, int] | None = None) -> tuple[str, tuple[int, int] | None]:
    """text[start:end] on one line as written, comments dropped and each gap between tokens
    one space; and where the region `site` (source offsets) ends up in it."""
    out = ""
    prev = None
    at: list[int] = []
    for i, j in tokens(text, start, end):
        if site is not None and not at and i >= site[0]:
            at.append(len(out))
        if site is not None and len(at) == 1 and i >= site[1]:
            at.append(len(out))
        if prev is not None and prev < i:
            out += " "
        out += text[i:j]
        prev = j
    if site is not None:
        at += [len(out)] * (2 - len(at))
        return out, (at[0], at[1])
    return out, None


def _scan(text: str, upto: int) -> _Scan:
    # lark's lexer state at an error only has the token that failed, not the ones before it.
    out = _Scan()
    line, counted = 1, 0
    for i, j in tokens(text, 0, upto):
        newlines = text.count("\n", counted, i)
        line, counted = line + newlines, i
        if newlines or not out.line_heads:
            out.line_heads.setdefault(line, (i, text[i:j]))
        c = text[i]
        if c in _CLOSERS:
            out.open.append((c, i))
        elif out.open and c == _CLOSERS[out.open[-1][0]][0]:
            out.open.pop()
        out.last_end = j
    return out


# A temporal operator (F, G, X, possibly step-bounded) right before a position
_TEMPORAL_BEFORE = re.compile(r"\b[FGX](?:\s*<=\s*[\w.]+)?\s*$")
# ... in brackets at the start of a path formula: `[ (F` (`F (F` is a nested one)
# ... right after another one, or after U (`F F mode == B`, `a U F true`): the inner
# operator lexes as a name when no label follows it, and the parser fails on what follows
_NESTED_TEMPORAL = re.compile(r"\b[FGXU](?:\s*<=\s*[\w.]+)?\s+[FGX](?:\s*<=\s*[\w.]+)?\s*$")
_BRACKETED_TEMPORAL = re.compile(r"\[\s*(?:\(\s*)+[FGX](?:\s*<=\s*[\w.]+)?\s*$")


def _report_syntax_error(exc: UnexpectedInput, source: Source, reporter: Reporter,
                         formula: bool = False) -> None:
    text = source.text
    the_end = "end of the formula" if formula else "end of file"
    where = exc.token.start_pos if isinstance(exc, UnexpectedToken) else exc.pos_in_stream
    if where is not None and _unterminated(text, where, source, reporter):
        return
    if isinstance(exc, UnexpectedCharacters):
        pos = len(text) if exc.pos_in_stream is None else exc.pos_in_stream
        char = text[pos] if pos < len(text) else "?"
        if char == "%":
            reporter.error("E123", "'%' is not an operator in afsm: write 'mod(a, b)'",
                           Span.at_offset(source, pos), hint=_mod_hint(text, pos, pos + 1))
            return
        reporter.error("E101", f"unexpected character {char!r}", Span.at_offset(source, pos),
                       hint=_expected_hint(exc.allowed, the_end) if exc.allowed else None)
        return
    if not isinstance(exc, UnexpectedToken):  # UnexpectedEOF: lark's LALR does not raise it
        scan = _scan(text, len(text))
        reporter.error("E101", "the file ends in the middle of a declaration",
                       Span.at_offset(source, scan.last_end),
                       hint=_expected_hint(set(getattr(exc, "expected", ())), the_end))
        return
    tok = exc.token
    at_end = tok.type == "$END"
    # lark gives $END the position of the last token; the end is after it
    pos = len(text) if at_end else (tok.start_pos or 0)
    scan = _scan(text, pos)
    after_last = Span.at_offset(source, scan.last_end)
    span = after_last if at_end else Span.at_offset(source, pos, max(tok.end_pos or 0, pos + 1))
    accepts = set(exc.accepts or exc.expected)

    if scan.open and _unclosed(exc, source, reporter, scan, accepts, formula):
        return
    bound = _BOUND_EXPRESSION.search(text, 0, pos)
    if bound is not None and (bound.group(3) or str(tok) in ("+", "-", "*", "/")):
        # `F<=K-1 "l"`: the bound is one number or name; the operator started the target
        op, value = re.sub(r"\s+", "", bound.group(1)), bound.group(2)
        rest = re.sub(r"\s*([-+*/])\s*", r" \1 ", bound.group(3)).strip() \
            if bound.group(3) else f"{tok} ..."
        reporter.error("E121", "a step bound that is an expression is written in brackets",
                       Span.at_offset(source, bound.start(1), max(pos, bound.end(2))),
                       hint=f"write '{op}({value} {rest})'")
        return
    matched = _match_example(exc)
    line_start = text.rfind("\n", 0, pos) + 1
    if (str(tok) in _DECL_KEYWORDS and not scan.open and not text[line_start:pos].strip()
            and ("SEMICOLON" in accepts or matched in _MISSING_SEMICOLON)):
        # A declaration starts its line where the one before has not ended: its ';' is
        # missing, whatever the parser state says (`... clamp`, a label, a property).
        reporter.error("E102", "missing ';' at the end of the declaration", after_last,
                       hint=f"add ';' here; the next line starts with {str(tok)!r}")
        return
    header = _HAZARD_BOTH.search(text, 0, pos) if str(tok) in ("when", "with") else None
    if header is not None and re.search(r"\b(?:when|with)\b", header.group(0)):
        reporter.error("E124", "a hazard is either preemptive ('when GUARD') or probabilistic "
                       "('with probability P'), not both", span,
                       hint=_hazard_hint(text, header.start(), pos))
        return
    owner = _body_owner(text, scan)
    body = owner in ("action", "hazard")  # in outcomes, where updates are
    amp = re.search(r"&\s*(?:[\w.]+\s*)?$", text[:pos]) if body else None
    # (the contextual lexer may cut a ':=' it does not expect to ':')
    assigns = str(tok) in (":=", "+=", "-=") or text.startswith(":=", pos)
    if body and (str(tok) == "&" or (assigns and amp is not None)):
        # PRISM's `x'=1 & y'=2`: after `goto B` the '&' fails, after `x := 1` the next ':='
        at = span if str(tok) == "&" or amp is None else Span.at_offset(source, amp.start())
        reporter.error("E107", "updates of one outcome are separated by ','", at,
                       hint="write ',' instead of '&' (PRISM joins updates with '&')")
        return
    foreign = _foreign(text, pos, str(tok), tok.type, body)
    if foreign is not None:
        message, hint, word = foreign
        reporter.error("E123", message,
                       span if word is None else Span.at_offset(source, *word), hint=hint)
        return
    if str(tok) == "when":
        # Whatever expression the weight is (`weight (b > 3 ? 1 : 0) when ...`): the parser
        # state after it is the one every expression ends in, which the examples cannot tell;
        # a header that has its guard already has a second one here, not a swapped one.
        matched = _E120 if _WEIGHT_BEFORE_GUARD.search(text, 0, pos) else \
            None if matched == _E120 else matched
    if scan.open and scan.open[-1][0] == "[" and _NESTED_TEMPORAL.search(text, 0, pos):
        matched = _E115
    if matched is not None and matched[0] == "E115" and not _TEMPORAL_BEFORE.search(
            text, 0, pos):
        # The parser state is the one after any operand (`label a = x "l";`): only a
        # temporal operator just before the failing token makes it a nested one.
        matched = None
    if matched is not None and matched[0] == "E115" and _BRACKETED_TEMPORAL.search(
            text, 0, pos):
        # `P=? [ (F "done") ]`: nothing is nested, the operator is in brackets
        matched = ("E115", "a temporal operator (F, G, X, U) cannot stand in brackets: it "
                   "applies to the whole path formula, 'P=? [ F \"done\" ]'")
    if matched is not None and str(tok) == "}" and matched[0] in ("E102", "E103", "E116"):
        # A '}' right after an expression: the parser state is shared by every context an
        # expression ends in, so the brace that is open decides what is missing.
        matched = _missing_before_brace(text, scan)
    if matched is not None and matched[0] == "E116" and owner is None:
        # the state after an expression, shared by labels, formulas and properties: a ';'
        # is missing only where the text ends (a keyword on the next line: E102 above)
        matched = _MISSING_SEMICOLON[0] if at_end else None
    if matched is not None and matched[0] == "E103" and str(tok) != "=":
        matched = None  # only a '=' is taken for a comparison
    if matched is not None and not (formula and matched[0] == "E102"):
        code, message = matched
        if code in ("E102", "E116"):
            # The mistake is before the token that revealed it: point just after the
            # previous token, where the ';' belongs.
            if at_end:
                hint = "add ';' here; the file ends after this declaration"
            elif text.count("\n", scan.last_end, pos):
                hint = f"add ';' here; the next line starts with {str(tok)!r}"
            else:
                hint = f"add ';' here, before {str(tok)!r}"
            reporter.error(code, message, after_last, hint=hint)
            return
        reporter.error(code, message, span, hint=f"found {_found(tok, the_end)}")
        return
    before = _OPERAND_BEFORE.search(text, 0, pos)
    if "PLUS" in accepts and tok.type in _OPERANDS and before is not None:
        # `x 2`: an operator could follow the first operand. lark's list of what it expects
        # there starts with '(' (a call), which is no help.
        end = " or end the declaration with ';'" if "SEMICOLON" in accepts else ""
        reporter.error("E101", f"missing operator between {before.group(1)!r} and "
                       f"{str(tok)!r}", span,
                       hint=f"join them with an operator ('+', '==', '&&', ...){end}")
        return
    reporter.error("E101", f"unexpected {_found(tok, the_end)}", span,
                   hint=_expected_hint(accepts, the_end))


# Operands (a name, a number, a quoted label), and one that ends right before a position.
_OPERANDS = ("NAME", "NUMBER", "ESCAPED_STRING")
_OPERAND_BEFORE = re.compile(r'([A-Za-z_][\w.]*|\d[\w.]*|"[^"]*"|\))\s*\Z')


# An action's or hazard's header with its weight, right before a failing `when`
_WEIGHT_BEFORE_GUARD = re.compile(
    r"\b(?:action|hazard)\b(?:(?!\bwhen\b)[^{};])*\bweight\b[^{};]*$")
_QUERY_BEFORE = re.compile(r"\b(?:P|Pmin|Pmax|R|Rmin|Rmax)\s*(?:\{[^{}]*\})?\s*$")


def _foreign(text: str, pos: int, tok: str, kind: str,
             body: bool = False) -> tuple[str, str, tuple[int, int] | None] | None:
    """(message, hint, the offending word's offsets if not the failing token) for a spelling
    from another language (Python's `and`, `not`, `if ... then`, `x = 1`; an infix `mod`;
    PRISM's `&` between updates and `P>=0.5` thresholds) where the parser fails on it or
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
                _mod_hint(text, pos, pos + 3), None)
    if body and tok == "=" and (target := _UPDATE_TARGET.search(text, 0, pos)):
        name = target.group(1)
        return ("'=' does not assign in afsm: an update is written 'x := value'",
                f"write '{name} := ...' (or '{name} += ...', '{name} -= ...')", None)
    if before == "not" and kind != "LPAR":
        return NOT_OPERATOR, OPERATORS, at
    if before == "if" or (kind == "NAME" and tok in ("if", "then", "elif")):
        return ("afsm has no 'if ... then ... else': write a conditional as 'COND ? A : B'",
                (_conditional_update(text, pos) if body and tok == "if" else None)
                or "for example 'weight (b > 3 ? 1 : 0)'", at if before == "if" else None)
    if tok in ("<", "<=", ">", ">=") and _QUERY_BEFORE.search(text, 0, pos):
        return ("a property asks for a value, 'P=? [ ... ]', not a threshold",
                "write 'P=? [ ... ]' (or Pmin=?, Pmax=?, R=?) and compare the value it gives; "
                "afsm has no bounded P>=p or R<r queries", None)
    return None


# An update's target right before a failing '=': at the start of an outcome or after ','
_UPDATE_TARGET = re.compile(r"(?:[{;,]|:(?!=))\s*([A-Za-z_][\w.]*)\s*$")
# A hazard's header up to the failing token, with one trigger already
_HAZARD_BOTH = re.compile(r"\bhazard\b(?:[^{};]|\{[^{}]*\})*$")


def _hazard_hint(text: str, start: int, pos: int) -> str:
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
    upd = re.search(r"([A-Za-z_][\w.]*)\s*(:=|\+=|-=)\s*([^;{},:=]+?)\s*$", text[:pos])
    cond = re.match(r"if\s+([^;{},]+?)\s*(?:[;},]|$)", text[pos:])
    if upd is None or cond is None:
        return None
    x, op, e = upd.groups()
    other = x if op == ":=" else "0"
    return f"write '{x} {op} ({cond.group(1)} ? {e} : {other})'"


def _mod_hint(text: str, start: int, end: int) -> str:
    """'write mod(a, b)' with the operands around an infix `mod` or '%' where they are
    single names or numbers."""
    a = re.search(r"([\w.]+)\s*$", text[:start])
    b = re.match(r"\s*([\w.]+)", text[end:])
    if a and b:
        return f"write 'mod({a.group(1)}, {b.group(1)})'"
    return "mod(a, b) is the remainder of a divided by b"


# A step bound (`F<=`, `G<=`, `U<=`, `C<=`, `I=`) of one number or name right before the
# failing token, and (group 2) an operator with its operand that the parser took as the
# start of the target: `F<=K -1` parses `-1` as the target and fails at the label after it.
_BOUND_EXPRESSION = re.compile(
    r"(\b(?:[FGUC]\s*<=|I\s*=))\s*([\w.]+)\s*((?:[-+*/]\s*[\w.]+\s*)+)?$")
_BODY_OWNER = re.compile(r"\b(action|hazard|rewards)\b")


def _body_owner(text: str, scan: _Scan) -> str | None:
    """'action', 'hazard' or 'rewards' where the innermost open bracket is the '{' of such a
    body (outcomes, reward items); None anywhere else."""
    if not scan.open or scan.open[-1][0] != "{":
        return None
    owners = list(_BODY_OWNER.finditer(text, 0, scan.open[-1][1]))
    return owners[-1].group(1) if owners else None


def _missing_before_brace(text: str, scan: _Scan) -> tuple[str, str] | None:
    """E116 where the innermost open bracket is the '{' of a body (an action's or hazard's
    outcomes, a reward structure's items); None (unexpected '}') anywhere else."""
    owner = _body_owner(text, scan)
    if owner is None:
        return None
    if owner == "rewards":
        return "E116", "missing ';' at the end of the reward item"
    return "E116", "missing ';' at the end of the outcome"


def _unterminated(text: str, pos: int, source: Source, reporter: Reporter) -> bool:
    """E117 for a label name or block comment that is opened at `pos` and never closed:
    the lexer only sees an odd character there, and would say so."""
    if text.startswith("*", pos) and text.startswith("/*", pos - 1):
        pos -= 1  # '/' lexed as division, then '*' failed
    if text.startswith("/*", pos) and text.find("*/", pos + 2) < 0:
        reporter.error("E117", "this comment is not closed", Span.at_offset(source, pos, pos + 2),
                       hint="close it with '*/'; everything after '/*' is part of it until then")
        return True
    if text.startswith('"', pos):
        j = _string_end(text, pos)
        if j >= len(text) or text[j] == "\n":
            reporter.error("E117", "this label name is not closed",
                           Span.at_offset(source, pos, pos + 1),
                           hint="close it with '\"' on the same line; a quoted name does not "
                           "span lines")
            return True
    return False


def _found(tok: Token, the_end: str) -> str:
    return the_end if tok.type == "$END" else repr(str(tok))


def _unclosed(exc: UnexpectedToken, source: Source, reporter: Reporter, scan: _Scan,
              accepts: set[str], formula: bool) -> bool:
    """Report a bracket left open (E112), if that is what stopped the parser: the text
    ends where its closer is acceptable, or a '{' block runs into the next declaration."""
    char, at = scan.open[-1]
    closer, terminal = _CLOSERS[char]
    note = Related(f"the {char!r} that is not closed", Span.at_offset(source, at))
    tok = exc.token
    if tok.type == "$END":
        if terminal not in accepts:
            return False
        the_end = "the formula" if formula else "the file"
        reporter.error("E112", f"missing {closer!r}", Span.at_offset(source, scan.last_end),
                       hint=f"add {closer!r} here; {the_end} ends before it", related=[note])
        return True
    if char != "{" or formula:
        return False
    # `action A in S { ...` followed by `action B ...`: the body runs into the next
    # declaration, whose keyword the parser took for a name; it stops on it or just after.
    line, _ = source.position(tok.start_pos or 0)
    head = scan.line_heads.get(line)
    if head is None or head[1] not in _DECL_KEYWORDS or head[0] <= at:
        return False
    between = source.text[head[0]:tok.start_pos].split()
    if len(between) > 1:
        return False
    before = _scan(source.text, head[0]).last_end
    reporter.error("E112", "missing '}' before the next declaration",
                   Span.at_offset(source, before),
                   hint=f"add '}}' here; the next line starts a new declaration ({head[1]!r})",
                   related=[note])
    return True


def _state_of(exc: UnexpectedInput) -> object:
    state = getattr(exc, "state", None)
    return getattr(state, "position", state)


@cache
def _example_states() -> list[tuple[object, str, tuple[str, str]]]:
    """(LALR state, token type, mistake) of every example, computed once."""
    out = []
    for mistake, examples in _EXAMPLES.items():
        for text in examples:
            try:
                _parser().parse(text, start="start")
            except UnexpectedToken as exc:
                out.append((_state_of(exc), exc.token.type, mistake))
            except UnexpectedInput:
                continue
    return out


def _match_example(exc: UnexpectedInput) -> tuple[str, str] | None:
    """The mistake whose example fails in the same parser state (lark's match_examples
    idea; its own implementation trips over lark 1.3's parser-state objects)."""
    if not isinstance(exc, UnexpectedToken):
        return None
    state = _state_of(exc)
    candidates = [(tok, mistake) for st, tok, mistake in _example_states() if st == state]
    for tok, mistake in candidates:
        if tok == exc.token.type:
            return mistake
    return candidates[0][1] if candidates else None


def _expected_hint(expected: set[str] | frozenset[str], the_end: str = "end of file") -> str:
    names = sorted({the_end if t == "$END" else _TOKEN_NAMES.get(t, _literal_name(t))
                    for t in expected})
    if len(names) > 8:
        names = [*names[:8], "..."]
    return "expected " + ", ".join(names)


def _literal_name(terminal: str) -> str:
    try:
        pattern = _parser().get_terminal(terminal).pattern
    except KeyError:
        return terminal
    if isinstance(pattern, lark.lexer.PatternStr):
        return repr(pattern.value)
    return terminal.lower()


# ---- tree -> AST -------------------------------------------------------------


def _span(source: Source, meta_or_tok: Any) -> Span:
    if isinstance(meta_or_tok, Token):
        return Span.at_offset(source, meta_or_tok.start_pos or 0, meta_or_tok.end_pos)
    if getattr(meta_or_tok, "empty", True):
        return Span.at_offset(source, 0, 0)
    return Span.at_offset(source, meta_or_tok.start_pos, meta_or_tok.end_pos)


@v_args(meta=True)
class _Builder(Transformer[Token, Any]):
    """Builds AST nodes; children arrive already transformed."""

    def __init__(self, source: Source, reporter: Reporter):
        super().__init__()
        self.source = source
        self.reporter = reporter

    def _s(self, meta: Any) -> Span:
        return _span(self.source, meta)

    def _id(self, tok: Token) -> ast.Ident:
        return ast.Ident(str(tok), _span(self.source, tok))

    # -- module
    def start(self, meta: Any, children: list[Any]) -> ast.Module:
        machine = None
        decls = []
        for child in children:
            if isinstance(child, ast.MachineDecl):
                machine = child
            else:
                decls.append(child)
        return ast.Module(machine, tuple(decls), Span.at_offset(self.source, 0, len(self.source.text)))

    def machine_decl(self, meta: Any, c: list[Any]) -> ast.MachineDecl:
        return ast.MachineDecl(self._id(c[0]), self._s(meta))

    # -- constants
    def type_name(self, meta: Any, c: list[Token]) -> str:
        return str(c[0])

    def const_decl(self, meta: Any, c: list[Any]) -> ast.ConstDecl:
        source = c[3] if len(c) > 3 else None
        return ast.ConstDecl(c[0], self._id(c[1]), c[2], source, self._s(meta))

    def interval(self, meta: Any, c: list[Any]) -> ast.Interval:
        return ast.Interval(c[0], c[1], self._s(meta))

    def sim_source(self, meta: Any, c: list[Any]) -> ast.SimSource:
        policy = c[1] if len(c) > 1 else ()
        return ast.SimSource(c[0], policy, self._s(meta))

    def sim_policy(self, meta: Any, c: list[Any]) -> tuple[tuple[ast.Ident, float], ...]:
        return tuple(c)

    def policy_item(self, meta: Any, c: list[Any]) -> tuple[ast.Ident, float]:
        return (self._id(c[0]), c[1])

    def signed_number(self, meta: Any, c: list[Token]) -> float:
        # The minus is an anonymous token; comments and line breaks may stand between it and
        # the number, so only the number's own text is converted.
        value = float(c[-1])
        return -value if self.source.text[meta.start_pos:meta.end_pos].startswith("-") else value

    def dotted_name(self, meta: Any, c: list[Token]) -> ast.Ident:
        return ast.Ident(".".join(str(t) for t in c), self._s(meta))

    def param_decl(self, meta: Any, c: list[Any]) -> ast.ParamDecl:
        default = c[2] if len(c) > 2 else None
        return ast.ParamDecl(c[0], self._id(c[1]), default, self._s(meta))

    # -- variables
    def var_decl(self, meta: Any, c: list[Any]) -> ast.VarDecl:
        name, vtype, rest = c[0], c[1], c[2:]
        init = None
        clamp = False
        for item in rest:
            if item == "clamp":
                clamp = True
            else:
                init = item
        return ast.VarDecl(self._id(name), vtype, init, clamp, self._s(meta))

    def clamp(self, meta: Any, c: list[Any]) -> str:
        return "clamp"

    def range_type(self, meta: Any, c: list[Any]) -> ast.RangeType:
        return ast.RangeType(c[0], c[1], self._s(meta))

    def bool_type(self, meta: Any, c: list[Any]) -> ast.BoolType:
        return ast.BoolType(self._s(meta))

    def tuple_type(self, meta: Any, c: list[Any]) -> ast.TupleType:
        return ast.TupleType(tuple(c), self._s(meta))

    def field(self, meta: Any, c: list[Any]) -> ast.FieldDecl:
        return ast.FieldDecl(self._id(c[0]), c[1], self._s(meta))

    def var_init(self, meta: Any, c: list[Any]) -> Any:
        return c[0]

    def tuple_init(self, meta: Any, c: list[Any]) -> ast.TupleLit:
        return ast.TupleLit(tuple(c), self._s(meta))

    # -- modes
    def mode_decl(self, meta: Any, c: list[Any]) -> ast.ModeDecl:
        name = self._id(c[0])
        number = None
        number_span = None
        attrs = []
        for item in c[1:]:
            if isinstance(item, Token) and item.type == "NUMBER":
                number_span = _span(self.source, item)
                number = self._int(item)
            else:
                if item in attrs:
                    self.reporter.error("E118", f"'{item!s}' is given twice for mode {name.text}",
                                        _span(self.source, item),
                                        hint=f"write '{item!s}' once")
                attrs.append(item)
        return ast.ModeDecl(name, number, number_span, "initial" in attrs, "final" in attrs,
                            self._s(meta))

    def mode_attr(self, meta: Any, c: list[Token]) -> Token:
        return c[0]  # a Token (a str) keeps its position for E118

    def _int(self, tok: Token) -> int:
        text = str(tok)
        if not text.isdigit():
            self.reporter.error("E110", f"a mode number must be a whole number, not {text}",
                                _span(self.source, tok))
            return 0
        return int(text)

    # -- mode sets
    def mode_set(self, meta: Any, c: list[Any]) -> ast.ModeSet:
        return ast.ModeSet(tuple(c), False, self._s(meta))

    def all_modes(self, meta: Any, c: list[Any]) -> ast.ModeSet:
        return ast.ModeSet((), True, self._s(meta))

    def all_modes_except(self, meta: Any, c: list[Any]) -> ast.ModeSet:
        return ast.ModeSet(tuple(c), True, self._s(meta))

    def mode_name(self, meta: Any, c: list[Token]) -> ast.ModeName:
        return ast.ModeName(self._id(c[0]), self._s(meta))

    def mode_number(self, meta: Any, c: list[Token]) -> ast.ModeNumber:
        return ast.ModeNumber(self._int(c[0]), self._s(meta))

    def mode_range(self, meta: Any, c: list[Token]) -> ast.ModeRange:
        return ast.ModeRange(self._int(c[0]), self._int(c[1]), self._s(meta))

    # -- actions and hazards
    def action_decl(self, meta: Any, c: list[Any]) -> ast.ActionDecl:
        guard = weight = None
        for item in c[2:-1]:
            if item[0] == "guard":
                guard = item[1]
            else:
                weight = item[1]
        return ast.ActionDecl(self._id(c[0]), c[1], guard, weight, c[-1], self._s(meta))

    def guard(self, meta: Any, c: list[Any]) -> tuple[str, Any]:
        return ("guard", c[0])

    def weight(self, meta: Any, c: list[Any]) -> tuple[str, Any]:
        return ("weight", c[0])

    def hazard_decl(self, meta: Any, c: list[Any]) -> ast.HazardDecl:
        kind, trigger = c[2]
        weight = c[3][1] if len(c) > 4 else None
        return ast.HazardDecl(self._id(c[0]), c[1], kind, trigger, weight, c[-1], self._s(meta))

    def probabilistic(self, meta: Any, c: list[Any]) -> tuple[str, Any]:
        return ("probabilistic", c[0])

    def preemptive(self, meta: Any, c: list[Any]) -> tuple[str, Any]:
        return ("preemptive", c[0])

    def body(self, meta: Any, c: list[Any]) -> ast.Body:
        if not c:
            # `{ }` read as `{ skip; }` would hide a body left unwritten
            self.reporter.error("E119", "an empty body: say what the action does",
                                self._s(meta), hint="write '{ skip; }' for an action that "
                                "changes nothing")
        outcomes = [x for x in c if x.prob is not None]
        plain = [x for x in c if x.prob is None]
        if outcomes and plain:
            self.reporter.error(
                "E111", "a body has either outcomes 'p: updates;' or plain updates, not both",
                plain[0].span,
                hint="give this line a probability, or move it into every outcome")
        if plain and not outcomes:
            # `goto A; t += 1;` -- several statements of one certain outcome
            updates = tuple(u for stmt in plain for u in stmt.updates)
            return ast.Body((ast.Outcome(None, updates, self._s(meta)),), self._s(meta))
        return ast.Body(tuple(c), self._s(meta))

    def outcome(self, meta: Any, c: list[Any]) -> ast.Outcome:
        return ast.Outcome(c[0], c[1], self._s(meta))

    def update_stmt(self, meta: Any, c: list[Any]) -> ast.Outcome:
        return ast.Outcome(None, c[0], self._s(meta))

    def updates(self, meta: Any, c: list[Any]) -> tuple[ast.Update, ...]:
        return tuple(c)

    def no_update(self, meta: Any, c: list[Any]) -> tuple[ast.Update, ...]:
        return ()

    def goto(self, meta: Any, c: list[Token]) -> ast.Goto:
        return ast.Goto(self._id(c[0]), self._s(meta))

    def _assign(self, meta: Any, c: list[Any], op: Any) -> ast.Assign:
        return ast.Assign(c[0], op, c[1], self._s(meta))

    def assign(self, meta: Any, c: list[Any]) -> ast.Assign:
        return self._assign(meta, c, ":=")

    def add_assign(self, meta: Any, c: list[Any]) -> ast.Assign:
        return self._assign(meta, c, "+=")

    def sub_assign(self, meta: Any, c: list[Any]) -> ast.Assign:
        return self._assign(meta, c, "-=")

    def lvalue(self, meta: Any, c: list[Token]) -> ast.LValue:
        return ast.LValue(self._id(c[0]), self._id(c[1]) if len(c) > 1 else None, self._s(meta))

    # -- formulas, labels, rewards, properties
    def formula_decl(self, meta: Any, c: list[Any]) -> ast.FormulaDecl:
        return ast.FormulaDecl(self._id(c[0]), c[1], self._s(meta))

    def label_decl(self, meta: Any, c: list[Any]) -> ast.LabelDecl:
        return ast.LabelDecl(self._id(c[0]), c[1], self._s(meta))

    def rewards_decl(self, meta: Any, c: list[Any]) -> ast.RewardsDecl:
        return ast.RewardsDecl(self._id(c[0]), tuple(c[1:]), self._s(meta))

    def action_reward(self, meta: Any, c: list[Any]) -> ast.RewardItem:
        return ast.RewardItem(self._id(c[0]), c[1], c[2], self._s(meta))

    def state_reward(self, meta: Any, c: list[Any]) -> ast.RewardItem:
        return ast.RewardItem(None, c[0], c[1], self._s(meta))

    def property_decl(self, meta: Any, c: list[Any]) -> ast.PropertyDecl:
        return ast.PropertyDecl(self._id(c[0]), c[1], self._s(meta))

    def p_op(self, meta: Any, c: list[Token]) -> str:
        return str(c[0])

    def minmax(self, meta: Any, c: list[Token]) -> str:
        return str(c[0])

    def p_query(self, meta: Any, c: list[Any]) -> ast.PQuery:
        return ast.PQuery(c[0], c[1], self._s(meta))

    def r_query(self, meta: Any, c: list[Any]) -> ast.RQuery:
        reward = reward_span = None
        opt = ""
        for item in c[:-1]:
            if isinstance(item, Token):
                reward = str(item)[1:-1]
                reward_span = _span(self.source, item)
            else:
                opt = item
        return ast.RQuery(reward, reward_span, cast(Any, opt), c[-1], self._s(meta))

    def time_bound(self, meta: Any, c: list[Any]) -> Any:
        return ("bound", c[0])

    def _bounded(self, c: list[Any]) -> tuple[Any, list[Any]]:
        bound = None
        rest = []
        for item in c:
            if isinstance(item, tuple) and item and item[0] == "bound":
                bound = item[1]
            else:
                rest.append(item)
        return bound, rest

    def eventually(self, meta: Any, c: list[Any]) -> ast.Eventually:
        bound, rest = self._bounded(c)
        return ast.Eventually(bound, rest[0], self._s(meta))

    def globally(self, meta: Any, c: list[Any]) -> ast.Globally:
        bound, rest = self._bounded(c)
        return ast.Globally(bound, rest[0], self._s(meta))

    def until(self, meta: Any, c: list[Any]) -> ast.Until:
        bound, rest = self._bounded(c)
        return ast.Until(rest[0], bound, rest[1], self._s(meta))

    def next(self, meta: Any, c: list[Any]) -> ast.Next:
        return ast.Next(c[0], self._s(meta))

    def reach_reward(self, meta: Any, c: list[Any]) -> ast.ReachReward:
        return ast.ReachReward(c[0], self._s(meta))

    def cumulative_reward(self, meta: Any, c: list[Any]) -> ast.CumulativeReward:
        bound, _ = self._bounded(c)
        return ast.CumulativeReward(bound, self._s(meta))

    def instant_reward(self, meta: Any, c: list[Any]) -> ast.InstantReward:
        return ast.InstantReward(c[0], self._s(meta))

    # -- expressions
    def number(self, meta: Any, c: list[Token]) -> ast.Num:
        text = str(c[0])
        value: int | float = int(text) if text.isdigit() else float(text)
        return ast.Num(value, text, self._s(meta))

    def true(self, meta: Any, c: list[Any]) -> ast.BoolLit:
        return ast.BoolLit(True, self._s(meta))

    def false(self, meta: Any, c: list[Any]) -> ast.BoolLit:
        return ast.BoolLit(False, self._s(meta))

    def name(self, meta: Any, c: list[Token]) -> ast.Name:
        return ast.Name(self._id(c[0]), self._s(meta))

    def field_ref(self, meta: Any, c: list[Token]) -> ast.FieldRef:
        return ast.FieldRef(self._id(c[0]), self._id(c[1]), self._s(meta))

    def mode_ref(self, meta: Any, c: list[Any]) -> ast.ModeRef:
        return ast.ModeRef(self._s(meta))

    def label_ref(self, meta: Any, c: list[Token]) -> ast.LabelRef:
        return ast.LabelRef(str(c[0])[1:-1], self._s(meta))

    def call(self, meta: Any, c: list[Any]) -> ast.Call:
        func = c[0]
        ident = self._id(func) if isinstance(func, Token) else ast.Ident(func, self._s(meta))
        return ast.Call(ident, tuple(x for x in c[1:] if x is not None), self._s(meta))

    def neg(self, meta: Any, c: list[Any]) -> ast.Expr:
        operand = c[-1]
        if isinstance(operand, ast.Num):
            value = -operand.value
            return ast.Num(value, "-" + operand.text, self._s(meta))
        return ast.Unary("-", operand, self._s(meta))

    def not_(self, meta: Any, c: list[Any]) -> ast.Unary:
        return ast.Unary("!", c[-1], self._s(meta))

    def _binary(self, meta: Any, op: str, left: Any, right: Any) -> ast.Binary:
        return ast.Binary(cast(Any, op), left, right, self._s(meta))

    def arith(self, meta: Any, c: list[Any]) -> ast.Binary:
        return self._binary(meta, str(c[1]), c[0], c[2])

    def add_op(self, meta: Any, c: list[Token]) -> str:
        return str(c[0])

    mul_op = add_op
    comp_op = add_op

    def compare(self, meta: Any, c: list[Any]) -> ast.Binary:
        return self._binary(meta, c[1], c[0], c[2])

    def and_(self, meta: Any, c: list[Any]) -> ast.Binary:
        return self._binary(meta, "&&", c[0], c[-1])

    def or_(self, meta: Any, c: list[Any]) -> ast.Binary:
        return self._binary(meta, "||", c[0], c[-1])

    def implies(self, meta: Any, c: list[Any]) -> ast.Binary:
        return self._binary(meta, "=>", c[0], c[-1])

    def ite(self, meta: Any, c: list[Any]) -> ast.Ite:
        return ast.Ite(c[0], c[1], c[2], self._s(meta))

    def mode_in(self, meta: Any, c: list[Any]) -> ast.ModeIn:
        return ast.ModeIn(c[0], self._s(meta))
