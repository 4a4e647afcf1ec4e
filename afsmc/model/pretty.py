"""Print IR expressions back in .afsm syntax (messages, diagrams, hover text).

Backends with other syntaxes (PRISM) reuse :class:`Printer` with their own tables.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping
from typing import ClassVar

from afsmc.model import expr as E

# Binding strength: larger binds tighter.
PREC = {"ite": 1, "=>": 2, "||": 3, "&&": 4, "!": 5, "==": 6, "!=": 6, "<": 6, "<=": 6,
        ">": 6, ">=": 6, "+": 7, "-": 7, "*": 8, "/": 8, "neg": 9, "atom": 10}


def number(v: int | float | bool) -> str:
    """A literal as the IR printer writes it for PRISM and JANI: a whole double keeps its
    `.0` (`2.0`, never `2`), so the backends see its type; afsmc.text's helpers are for
    wording in messages and tables, where `2` reads better."""
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, int):
        return str(v)
    if not math.isfinite(v):  # never valid in a model (resolve rejects it), but printable
        return repr(float(v))
    if v == int(v) and abs(v) < 1e15:
        return f"{int(v)}.0"
    return repr(float(v))


class Printer:
    ops: ClassVar[dict[str, str]] = {"&&": "&&", "||": "||", "=>": "=>", "==": "==", "!=": "!="}

    def __init__(self, name: Callable[[E.Expr], str | None] | None = None):
        self.custom = name

    def __call__(self, e: E.Expr) -> str:
        return self.show(e, 0)

    def atom(self, e: E.Expr) -> str:
        if isinstance(e, E.Lit):
            return number(e.value)
        if isinstance(e, (E.VarRef, E.ConstRef, E.FormulaRef)):
            return e.name
        if isinstance(e, E.ModeVal):
            return e.name
        if isinstance(e, E.CurrentMode):
            return "mode"
        if isinstance(e, E.LabelRef):
            return f'"{e.name}"'
        if isinstance(e, E.WeightRef):
            return f"w({e.action})"
        raise TypeError(type(e).__name__)

    def show(self, e: E.Expr, ctx: int) -> str:
        if self.custom is not None:
            text = self.custom(e)
            if text is not None:
                return text
        if isinstance(e, E.Unary):
            if e.op == "!":
                # Storm binds `!` tighter than PRISM does: parenthesise anything but an atom.
                return self.wrap(f"!{self.show(e.operand, PREC['atom'])}", PREC["!"], ctx)
            if isinstance(e.operand, E.Lit):
                return self.wrap(f"-{self.show(e.operand, PREC['neg'])}", PREC["neg"], ctx)
            return self.wrap(f"-{self.show(e.operand, PREC['neg'] + 1)}", PREC["neg"], ctx)
        if isinstance(e, E.Binary):
            p = PREC[e.op]
            op = self.ops.get(e.op, e.op)
            # left-associative: the right operand needs parentheses at equal strength
            right_ctx = p + 1 if e.op in ("-", "/", "+", "*", "=>") or p == 6 else p
            if e.op == "=>":
                # afsm groups `=>` to the right, Storm to the left: parenthesise both sides.
                left, right = self.show(e.left, p + 1), self.show(e.right, p + 1)
                return self.wrap(f"{left} {op} {right}", p, ctx)
            left = self.show(e.left, p if p != 6 else p + 1)
            return self.wrap(f"{left} {op} {self.show(e.right, right_ctx)}", p, ctx)
        if isinstance(e, E.Ite):
            text = f"{self.show(e.cond, 2)} ? {self.show(e.then, 2)} : {self.show(e.other, 1)}"
            return self.wrap(text, PREC["ite"], ctx)
        if isinstance(e, E.Call):
            return f"{e.func}({', '.join(self.show(a, 0) for a in e.args)})"
        return self.atom(e)

    @staticmethod
    def wrap(text: str, p: int, ctx: int) -> str:
        return f"({text})" if p < ctx else text


show = Printer()


def with_names(display: Mapping[str, str]) -> Printer:
    """A printer for messages: variables as the author writes them (`pos.x`, not the flat
    `pos_x` of the IR). `display` maps flat names to written ones."""
    return Printer(lambda e: display.get(e.name) if isinstance(e, E.VarRef) else None)
