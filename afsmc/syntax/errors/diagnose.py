"""report_syntax_error: one diagnostic for the place where lark stopped.

lark says only which token failed and what it would have accepted. The explanations are
tried from the most specific to the least: a comment or label name never closed, a bad
character, a bracket left open, a step bound written as an expression, a missing ';', a
spelling from another language, a mistake recognised from its examples, a missing
operator; and last "unexpected X, expected ...".
"""

from __future__ import annotations

import re
from dataclasses import dataclass

from lark import Token
from lark.exceptions import UnexpectedCharacters, UnexpectedInput, UnexpectedToken

from afsmc.diagnostics import Related, Reporter, Source, Span, codes
from afsmc.syntax.errors.before import hazard_header, operand_before, weight_before_guard
from afsmc.syntax.errors.examples import E115, E120, MISSING_SEMICOLON, Mistake, match_example
from afsmc.syntax.errors.hints import foreign, hazard_hint, mod_hint
from afsmc.syntax.errors.messages import expected_hint, found
from afsmc.syntax.limits import clip
from afsmc.syntax.scan import CLOSERS, Scan, scan, string_end

_DECL_KEYWORDS = frozenset({"machine", "const", "param", "var", "mode", "action", "hazard",
                            "formula", "label", "rewards", "property"})

# A temporal operator (F, G, X, possibly step-bounded) right before a position
_TEMPORAL_BEFORE = re.compile(r"\b[FGX](?:\s*<=\s*[\w.]+)?\s*$")
# ... right after another one, or after U (`F F mode == B`, `a U F true`): the inner
# operator lexes as a name when no label follows it, and the parser fails on what follows
_NESTED_TEMPORAL = re.compile(r"\b[FGXU](?:\s*<=\s*[\w.]+)?\s+[FGX](?:\s*<=\s*[\w.]+)?\s*$")
# ... in brackets at the start of a path formula: `[ (F` (`F (F` is a nested one)
_BRACKETED_TEMPORAL = re.compile(r"\[\s*(?:\(\s*)+[FGX](?:\s*<=\s*[\w.]+)?\s*$")

# Operands (a name, a number, a quoted label).
_OPERANDS = ("NAME", "NUMBER", "ESCAPED_STRING")
# A step bound (`F<=`, `G<=`, `U<=`, `C<=`, `I=`) of one number or name right before the
# failing token, and (group 3) an operator with its operand that the parser took as the
# start of the target: `F<=K -1` parses `-1` as the target and fails at the label after it.
_BOUND_EXPRESSION = re.compile(
    r"(\b(?:[FGUC]\s*<=|I\s*=))\s*([\w.]+)\s*((?:[-+*/]\s*[\w.]+\s*)+)?$")
_BODY_OWNER = re.compile(r"\b(action|hazard|rewards)\b")
_TRIGGER = re.compile(r"\b(?:when|with)\b")
_WORD = re.compile(r"\w*")


def report_glued_keyword(tok: Token, source: Source, reporter: Reporter) -> None:
    """E122 for a keyword run into a name (`modeA`), which lexed as the keyword."""
    text = source.text
    end = tok.end_pos or 0
    word = _WORD.match(text, end)
    rest = clip(word.group()) if word else ""
    reporter.error(codes.E122, f"'{tok}{rest}' is not a keyword, and no name may stand here",
                   Span.at_offset(source, tok.start_pos or 0, end + len(rest)),
                   hint=f"if the keyword '{tok}' is meant, put a space after it: "
                        f"'{tok} {rest}'; else check the spelling")


def report_syntax_error(exc: UnexpectedInput, source: Source, reporter: Reporter,
                        formula: bool = False) -> None:
    """Report the syntax error `exc` of `source`. `formula`: the text is one property
    (`verify --formula`), not a file."""
    text = source.text
    the_end = "end of the formula" if formula else "end of file"
    where = exc.token.start_pos if isinstance(exc, UnexpectedToken) else exc.pos_in_stream
    if where is not None and _unterminated(text, where, source, reporter):
        return
    if isinstance(exc, UnexpectedCharacters):
        _report_character(exc, source, reporter, the_end)
    elif isinstance(exc, UnexpectedToken):
        _report_token(_failure(exc, source, formula), reporter)
    else:  # UnexpectedEOF: lark's LALR does not raise it
        reporter.error(codes.E101, "the file ends in the middle of a declaration",
                       Span.at_offset(source, scan(text, len(text)).last_end),
                       hint=expected_hint(set(getattr(exc, "expected", ())), the_end))


def _unterminated(text: str, pos: int, source: Source, reporter: Reporter) -> bool:
    """E117 for a label name or block comment that is opened at `pos` and never closed:
    the lexer only sees an odd character there, and would say so."""
    if text.startswith("*", pos) and text.startswith("/*", pos - 1):
        pos -= 1  # '/' lexed as division, then '*' failed
    if text.startswith("/*", pos) and text.find("*/", pos + 2) < 0:
        reporter.error(codes.E117, "this comment is not closed", Span.at_offset(source, pos, pos + 2),
                       hint="close it with '*/'; everything after '/*' is part of it until then")
        return True
    if text.startswith('"', pos):
        j = string_end(text, pos)
        if j >= len(text) or text[j] == "\n":
            reporter.error(codes.E117, "this label name is not closed",
                           Span.at_offset(source, pos, pos + 1),
                           hint="close it with '\"' on the same line; a quoted name does not "
                           "span lines")
            return True
    return False


def _report_character(exc: UnexpectedCharacters, source: Source, reporter: Reporter,
                      the_end: str) -> None:
    """A character no token starts with (E123 for Python's '%', else E101)."""
    text = source.text
    pos = len(text) if exc.pos_in_stream is None else exc.pos_in_stream
    char = text[pos] if pos < len(text) else "?"
    if char == "%":
        reporter.error(codes.E123, "'%' is not an operator in afsm: write 'mod(a, b)'",
                       Span.at_offset(source, pos), hint=mod_hint(text, pos, pos + 1))
        return
    reporter.error(codes.E101, f"unexpected character {char!r}", Span.at_offset(source, pos),
                   hint=expected_hint(exc.allowed, the_end) if exc.allowed else None)


@dataclass(frozen=True)
class _Failure:
    """Where the parser stopped on a token, and what precedes it."""

    source: Source
    exc: UnexpectedToken
    formula: bool
    tok: Token  # the failing token (type "$END" at the end of the text)
    at_end: bool
    pos: int  # where the failing token starts (the end of the text at its end)
    scan: Scan  # the text before `pos`
    span: Span  # the failing token; at the end, just after the last token
    after_last: Span  # just after the last token before the failing one
    accepts: frozenset[str]  # the terminals the parser would have taken

    @property
    def text(self) -> str:
        return self.source.text

    @property
    def word(self) -> str:
        return str(self.tok)

    @property
    def the_end(self) -> str:
        return "end of the formula" if self.formula else "end of file"


def _failure(exc: UnexpectedToken, source: Source, formula: bool) -> _Failure:
    tok = exc.token
    at_end = tok.type == "$END"
    # lark gives $END the position of the last token; the end is after it
    pos = len(source.text) if at_end else (tok.start_pos or 0)
    before = scan(source.text, pos)
    after_last = Span.at_offset(source, before.last_end)
    span = after_last if at_end else Span.at_offset(source, pos, max(tok.end_pos or 0, pos + 1))
    return _Failure(source, exc, formula, tok, at_end, pos, before, span, after_last,
                    frozenset(exc.accepts or exc.expected))


def _report_token(f: _Failure, reporter: Reporter) -> None:
    """A token the parser cannot take here: each explanation in turn, most specific first."""
    if f.scan.open and _unclosed(f, reporter):
        return
    if _step_bound(f, reporter):
        return
    matched = match_example(f.exc)
    if _next_declaration(f, matched, reporter) or _hazard_with_both(f, reporter):
        return
    owner = _body_owner(f.text, f.scan)
    body = owner in ("action", "hazard")  # in outcomes, where updates are
    if _prism_updates(f, body, reporter) or _foreign_spelling(f, body, reporter):
        return
    matched = _refine(f, matched, owner)
    if matched is not None and not (f.formula and matched[0] == codes.E102):
        _report_mistake(f, matched, reporter)
        return
    if _missing_operator(f, reporter):
        return
    reporter.error(codes.E101, f"unexpected {found(f.tok, f.the_end)}", f.span,
                   hint=expected_hint(f.accepts, f.the_end))


def _unclosed(f: _Failure, reporter: Reporter) -> bool:
    """Report a bracket left open (E112), if that is what stopped the parser: the text
    ends where its closer is acceptable, or a '{' block runs into the next declaration."""
    char, at = f.scan.open[-1]
    closer, terminal = CLOSERS[char]
    note = Related(f"the {char!r} that is not closed", Span.at_offset(f.source, at))
    if f.at_end:
        if terminal not in f.accepts:
            return False
        the_end = "the formula" if f.formula else "the file"
        reporter.error(codes.E112, f"missing {closer!r}", f.after_last,
                       hint=f"add {closer!r} here; {the_end} ends before it", related=[note])
        return True
    if char != "{" or f.formula:
        return False
    # `action A in S { ...` followed by `action B ...`: the body runs into the next
    # declaration, whose keyword the parser took for a name; it stops on it or just after.
    line, _ = f.source.position(f.tok.start_pos or 0)
    head = f.scan.line_heads.get(line)
    if head is None or head[1] not in _DECL_KEYWORDS or head[0] <= at:
        return False
    between = f.text[head[0]:f.tok.start_pos].split()
    if len(between) > 1:
        return False
    before = scan(f.text, head[0]).last_end
    reporter.error(codes.E112, "missing '}' before the next declaration",
                   Span.at_offset(f.source, before),
                   hint=f"add '}}' here; the next line starts a new declaration ({head[1]!r})",
                   related=[note])
    return True


def _step_bound(f: _Failure, reporter: Reporter) -> bool:
    """E121 for `F<=K-1 "l"`: the bound is one number or name; the operator after it
    started the target."""
    bound = _BOUND_EXPRESSION.search(f.text, 0, f.pos)
    if bound is None or not (bound.group(3) or f.word in ("+", "-", "*", "/")):
        return False
    op, value = re.sub(r"\s+", "", bound.group(1)), bound.group(2)
    rest = re.sub(r"\s*([-+*/])\s*", r" \1 ", bound.group(3)).strip() \
        if bound.group(3) else f"{f.tok} ..."
    reporter.error(codes.E121, "a step bound that is an expression is written in brackets",
                   Span.at_offset(f.source, bound.start(1), max(f.pos, bound.end(2))),
                   hint=f"write '{op}({value} {rest})'")
    return True


def _next_declaration(f: _Failure, matched: Mistake | None, reporter: Reporter) -> bool:
    """E102 where a declaration starts its line and the one before has not ended: its ';'
    is missing, whatever the parser state says (`... clamp`, a label, a property)."""
    line_start = f.text.rfind("\n", 0, f.pos) + 1
    if (f.word in _DECL_KEYWORDS and not f.scan.open and not f.text[line_start:f.pos].strip()
            and ("SEMICOLON" in f.accepts or matched in MISSING_SEMICOLON)):
        reporter.error(codes.E102, "missing ';' at the end of the declaration", f.after_last,
                       hint=f"add ';' here; the next line starts with {f.word!r}")
        return True
    return False


def _hazard_with_both(f: _Failure, reporter: Reporter) -> bool:
    """E124 for a hazard header with both a 'when' and a 'with probability' trigger."""
    start = hazard_header(f.text, f.pos) if f.word in ("when", "with") else None
    if start is None or not _TRIGGER.search(f.text, start, f.pos):
        return False
    reporter.error(codes.E124, "a hazard is either preemptive ('when GUARD') or probabilistic "
                   "('with probability P'), not both", f.span,
                   hint=hazard_hint(f.text, start, f.pos))
    return True


def _prism_updates(f: _Failure, body: bool, reporter: Reporter) -> bool:
    """E107 for PRISM's `x'=1 & y'=2` in an outcome: after `goto B` the '&' fails, after
    `x := 1` the next ':='."""
    amp = re.search(r"&\s*(?:[\w.]+\s*)?$", f.text[:f.pos]) if body else None
    # (the contextual lexer may cut a ':=' it does not expect to ':')
    assigns = f.word in (":=", "+=", "-=") or f.text.startswith(":=", f.pos)
    if not (body and (f.word == "&" or (assigns and amp is not None))):
        return False
    at = f.span if f.word == "&" or amp is None else Span.at_offset(f.source, amp.start())
    reporter.error(codes.E107, "updates of one outcome are separated by ','", at,
                   hint="write ',' instead of '&' (PRISM joins updates with '&')")
    return True


def _foreign_spelling(f: _Failure, body: bool, reporter: Reporter) -> bool:
    """E123 for a spelling from another language (see hints.foreign)."""
    spelled = foreign(f.text, f.pos, f.word, f.tok.type, body)
    if spelled is None:
        return False
    message, hint, word = spelled
    reporter.error(codes.E123, message,
                   f.span if word is None else Span.at_offset(f.source, *word), hint=hint)
    return True


def _refine(f: _Failure, matched: Mistake | None, owner: str | None) -> Mistake | None:
    """The mistake recognised from the examples, corrected where the parser state is shared
    by several contexts and the text before the failing token tells them apart."""
    text, pos = f.text, f.pos
    if f.word == "when":
        # Whatever expression the weight is (`weight (b > 3 ? 1 : 0) when ...`): the parser
        # state after it is the one every expression ends in, which the examples cannot tell;
        # a header that has its guard already has a second one here, not a swapped one.
        matched = E120 if weight_before_guard(text, pos) else \
            None if matched == E120 else matched
    if f.scan.open and f.scan.open[-1][0] == "[" and _NESTED_TEMPORAL.search(text, 0, pos):
        matched = E115
    if matched is not None and matched[0] == codes.E115 and not _TEMPORAL_BEFORE.search(
            text, 0, pos):
        # The parser state is the one after any operand (`label a = x "l";`): only a
        # temporal operator just before the failing token makes it a nested one.
        matched = None
    if matched is not None and matched[0] == codes.E115 and _BRACKETED_TEMPORAL.search(
            text, 0, pos):
        # `P=? [ (F "done") ]`: nothing is nested, the operator is in brackets
        matched = (codes.E115, "a temporal operator (F, G, X, U) cannot stand in brackets: it "
                   "applies to the whole path formula, 'P=? [ F \"done\" ]'")
    if matched is not None and f.word == "}" and matched[0] in (codes.E102, codes.E103, codes.E116):
        # A '}' right after an expression: the parser state is shared by every context an
        # expression ends in, so the brace that is open decides what is missing.
        matched = _missing_before_brace(text, f.scan)
    if matched is not None and matched[0] == codes.E116 and owner is None:
        # the state after an expression, shared by labels, formulas and properties: a ';'
        # is missing only where the text ends (a keyword on the next line: E102 above)
        matched = MISSING_SEMICOLON[0] if f.at_end else None
    if matched is not None and matched[0] == codes.E103 and f.word != "=":
        matched = None  # only a '=' is taken for a comparison
    return matched


def _report_mistake(f: _Failure, mistake: Mistake, reporter: Reporter) -> None:
    code, message = mistake
    if code not in (codes.E102, codes.E116):
        reporter.error(code, message, f.span, hint=f"found {found(f.tok, f.the_end)}")
        return
    # The mistake is before the token that revealed it: point just after the previous
    # token, where the ';' belongs.
    if f.at_end:
        hint = "add ';' here; the file ends after this declaration"
    elif f.text.count("\n", f.scan.last_end, f.pos):
        hint = f"add ';' here; the next line starts with {clip(f.word)!r}"
    else:
        hint = f"add ';' here, before {clip(f.word)!r}"
    reporter.error(code, message, f.after_last, hint=hint)


def _missing_operator(f: _Failure, reporter: Reporter) -> bool:
    """E101 for two operands side by side (`x 2`), where an operator could follow the
    first. lark's list of what it expects there starts with '(' (a call), which is no help."""
    before = operand_before(f.text, f.pos)
    if "PLUS" not in f.accepts or f.tok.type not in _OPERANDS or before is None:
        return False
    end = " or end the declaration with ';'" if "SEMICOLON" in f.accepts else ""
    reporter.error(codes.E101, f"missing operator between {clip(before.group(1))!r} and "
                   f"{clip(f.word)!r}", f.span,
                   hint=f"join them with an operator ('+', '==', '&&', ...){end}")
    return True


def _body_owner(text: str, before: Scan) -> str | None:
    """'action', 'hazard' or 'rewards' where the innermost open bracket is the '{' of such a
    body (outcomes, reward items); None anywhere else."""
    if not before.open or before.open[-1][0] != "{":
        return None
    owners = list(_BODY_OWNER.finditer(text, 0, before.open[-1][1]))
    return owners[-1].group(1) if owners else None


def _missing_before_brace(text: str, before: Scan) -> Mistake | None:
    """E116 where the innermost open bracket is the '{' of a body (an action's or hazard's
    outcomes, a reward structure's items); None (unexpected '}') anywhere else."""
    owner = _body_owner(text, before)
    if owner is None:
        return None
    if owner == "rewards":
        return codes.E116, "missing ';' at the end of the reward item"
    return codes.E116, "missing ';' at the end of the outcome"
