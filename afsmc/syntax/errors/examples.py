"""Common syntax mistakes, each learnt from examples (in the manner of lark's
match_examples and its GRAMMAR_ERRORS table): the LALR state in which an example fails
identifies the mistake, whatever the names in it."""

from __future__ import annotations

from functools import cache

from lark.exceptions import UnexpectedInput, UnexpectedToken

from afsmc.diagnostics import codes
from afsmc.syntax.errors.messages import NESTED_TEMPORAL
from afsmc.syntax.grammar import lalr

# A mistake: its code and message.
Mistake = tuple[str, str]

E115: Mistake = (codes.E115, NESTED_TEMPORAL)
MISSING_SEMICOLON: tuple[Mistake, Mistake] = (
    (codes.E102, "missing ';' at the end of the declaration"),
    (codes.E116, "missing ';' at the end of the outcome"))
E120: Mistake = (codes.E120, "the guard comes before the weight: 'action NAME in MODES when GUARD "
                 "weight W { ... }'")

EXAMPLES: dict[Mistake, list[str]] = {
    (codes.E102, "missing ';' at the end of the declaration"): [
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
    (codes.E116, "missing ';' at the end of the outcome"): [
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
    (codes.E103, "'=' is not a comparison; write '==' to compare"): [
        "label a = x = 1;",
        "formula f = x = 1;",
        "action A in S when x = 1 { skip; }",
        "action A in S weight x = 1 { skip; }",
        "action A in S when mode = A { skip; }",  # PRISM's own spelling
        "label a = mode = A;",
    ],
    E115: [
        'property p = P=? [ F F "l" ];',
        'property p = P=? [ X X "l" ];',
        'property p = P=? [ G F "l" ];',
        'property p = P=? [ F G x > 1 ];',
    ],
    (codes.E104, "a bounded integer is written [low..high]"): [
        "var x : [0, 3];",
        "var x : [0 , 3] init 0;",
    ],
    (codes.E105, "variables have a range [low..high] or type bool, not a type name"): [
        "var x : int;",
        "var x : double;",
        "var x : prob;",
    ],
    (codes.E106, "an outcome is written 'probability: updates;'"): [
        "action A in S { 0.5 goto B; }",
        "action A in S { p goto B; }",
    ],
    (codes.E107, "updates of one outcome are separated by ','"): [
        "action A in S { 0.5: goto B x := 1; }",
        "action A in S { goto B x := 1; }",
    ],
    E120: [
        "action A in S weight 1 when x > 1 { skip; }",
        "action A in * weight x when x > 1 { skip; }",
    ],
    (codes.E108, "an action needs its modes: 'action NAME in MODE { ... }'"): [
        "action A { skip; }",
        "action A when x > 1 { skip; }",
    ],
    (codes.E109, "an action's body is a block in braces"): [
        "action A in S goto B;",
        "action A in S weight 1 goto B;",
    ],
}


def _state_of(exc: UnexpectedInput) -> object:
    state = getattr(exc, "state", None)
    return getattr(state, "position", state)


@cache
def _example_states() -> list[tuple[object, str, Mistake]]:
    """(LALR state, token type, mistake) of every example, computed once."""
    out = []
    for mistake, examples in EXAMPLES.items():
        for text in examples:
            try:
                lalr().parse(text, start="start")
            except UnexpectedToken as exc:
                out.append((_state_of(exc), exc.token.type, mistake))
            except UnexpectedInput:
                continue
    return out


def match_example(exc: UnexpectedInput) -> Mistake | None:
    """The mistake whose example fails in the same parser state (lark's match_examples
    idea; its own implementation trips over lark 1.3's parser-state objects). Among
    several, the one whose example fails on the same kind of token."""
    if not isinstance(exc, UnexpectedToken):
        return None
    state = _state_of(exc)
    candidates = [(tok, mistake) for st, tok, mistake in _example_states() if st == state]
    for tok, mistake in candidates:
        if tok == exc.token.type:
            return mistake
    return candidates[0][1] if candidates else None
