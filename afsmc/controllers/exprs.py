"""IR expressions as Python or C text, computing what :mod:`afsmc.model.kernel` computes:

- `+ - *` of integers are integers (Python's exact ints; C's int64_t: the checks proved
  that no integer expression leaves 64 bits, E307), `/` is real division of doubles;
- `==` and `!=` treat doubles within 1e-12 as equal, integers exactly (`_eq` / `afsm_eq`);
- `mod(a, b)` is Storm's: the truncated remainder, plus `b` where `a` is negative;
- `pow` of integers is an integer for an exponent >= 0 and the C library's real `pow`
  otherwise; `floor` and `ceil` give integers; `min`/`max` with a double give a double;
- `&&`, `||`, `=>` short-circuit, as the kernel's evaluation skips the right side.

The generated code carries the helpers these names call (emitted by each target).
A name is printed by the callbacks the target gives: a variable, a constant, a formula,
a weight reference and the current mode are read differently in Python and in C.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

from afsmc.model import expr as E
from afsmc.model import ir
from afsmc.model.bounds import bounds
from afsmc.model.expr import Type

INT64_MIN = -(2**63)


@dataclass
class Names:
    """How a target reads the names of an expression."""

    var: Callable[[str], str]
    const: Callable[[str], str]
    formula: Callable[[str], str]
    weight: Callable[[str], str]
    mode: str


class Printer:
    """Prints expressions of `model` for `lang` ("python" or "c")."""

    def __init__(self, model: ir.Model, lang: str, names: Names) -> None:
        self.model = model
        self.lang = lang
        self.names = names
        self._real: dict[int, tuple[E.Expr, bool]] = {}

    # ---- which values are doubles (C needs it: Python's numbers know their type) ----

    def real(self, e: E.Expr) -> bool:
        """`e` may be a double: its type is, or it reads an integer `pow` whose exponent
        may be negative (a fraction, as the kernel computes it)."""
        hit = self._real.get(id(e))
        if hit is not None and hit[0] is e:
            return hit[1]
        out = self._is_real(e)
        self._real[id(e)] = (e, out)
        return out

    def _is_real(self, e: E.Expr) -> bool:
        if e.type is Type.DOUBLE:
            return True
        if e.type is not Type.INT:
            return False
        if isinstance(e, E.Call):
            if e.func == "pow":
                return any(self.real(a) for a in e.args) or self._may_be_negative(e.args[1])
            if e.func in ("floor", "ceil"):
                return False
            return any(self.real(a) for a in e.args)
        if isinstance(e, E.FormulaRef):
            return self.real(self.model.formula(e.name).value)
        if isinstance(e, (E.Unary, E.Binary)):
            return any(self.real(a) for a in E.children(e))
        if isinstance(e, E.Ite):
            return self.real(e.then) or self.real(e.other)
        return False

    def _may_be_negative(self, e: E.Expr) -> bool:
        return bounds(e, self.model)[0] < 0

    # ---- printing ----

    def text(self, e: E.Expr) -> str:
        py = self.lang == "python"
        n = self.names
        if isinstance(e, E.Lit):
            return self._literal(e.value)
        if isinstance(e, E.VarRef):
            return n.var(e.name)
        if isinstance(e, E.ConstRef):
            return n.const(e.name)
        if isinstance(e, E.ModeVal):
            return str(e.number) if py else f"INT64_C({e.number})"
        if isinstance(e, E.CurrentMode):
            return n.mode
        if isinstance(e, E.FormulaRef):
            return n.formula(e.name)
        if isinstance(e, E.WeightRef):
            return n.weight(e.action)
        if isinstance(e, E.LabelRef):  # labels are read only by properties
            raise ValueError(f"label {e.name} in a controller expression")
        if isinstance(e, E.Unary):
            inner = self.text(e.operand)
            if e.op == "!":
                return f"(not {inner})" if py else f"(!{inner})"
            return f"(-{inner})"
        if isinstance(e, E.Binary):
            return self._binary(e)
        if isinstance(e, E.Ite):
            c, a, b = self.text(e.cond), self.text(e.then), self.text(e.other)
            if not py and self.real(e) and not (self.real(e.then) and self.real(e.other)):
                a, b = f"(double)({a})", f"(double)({b})"
            return f"({a} if {c} else {b})" if py else f"({c} ? {a} : {b})"
        return self._call(e)

    def _literal(self, v: int | float | bool) -> str:
        py = self.lang == "python"
        if isinstance(v, bool):
            return ("True" if v else "False") if py else ("true" if v else "false")
        if isinstance(v, int):
            if py:
                return str(v)
            if v == INT64_MIN:
                return "(-INT64_C(9223372036854775807) - 1)"
            return f"INT64_C({v})" if v >= 0 else f"(-INT64_C({-v}))"
        text = repr(float(v))
        return text if py or "e" in text or "." in text else text + ".0"

    def _binary(self, e: E.Binary) -> str:
        py = self.lang == "python"
        a, b = self.text(e.left), self.text(e.right)
        op = e.op
        if op in ("==", "!="):
            if e.left.type in (Type.INT, Type.DOUBLE) and (
                    py or self.real(e.left) or self.real(e.right)):
                # Python decides by the values' types at run time, as the kernel does
                eq = f"_eq({a}, {b})" if py else f"afsm_eq((double)({a}), (double)({b}))"
                return eq if op == "==" else (f"(not {eq})" if py else f"(!{eq})")
            return f"({a} {op} {b})"
        if op == "/":
            return f"_div({a}, {b})" if py else f"((double)({a}) / (double)({b}))"
        if op in ("&&", "||"):
            word = {"&&": "and", "||": "or"}[op] if py else op
            return f"({a} {word} {b})"
        if op == "=>":
            return f"((not {a}) or {b})" if py else f"(!{a} || {b})"
        return f"({a} {op} {b})"

    def _call(self, e: E.Call) -> str:
        py = self.lang == "python"
        args = [self.text(a) for a in e.args]
        f = e.func
        if f in ("floor", "ceil"):
            return f"_{f}({args[0]})" if py else f"((int64_t){f}((double)({args[0]})))"
        if f == "mod":
            if py:
                return f"_mod({args[0]}, {args[1]})"
            real = any(self.real(a) for a in e.args)
            return (f"afsm_fmod((double)({args[0]}), (double)({args[1]}))" if real
                    else f"afsm_mod({args[0]}, {args[1]})")
        if f == "pow":
            if py:
                return f"_ipow({args[0]}, {args[1]})" if e.type is Type.INT \
                    else f"_pow({args[0]}, {args[1]})"
            if self.real(e):
                return f"afsm_pow((double)({args[0]}), (double)({args[1]}))"
            return f"afsm_ipow({args[0]}, {args[1]})"
        # min / max, folded left to right
        if py:
            return f"_{f}({', '.join(args)})"
        real = self.real(e)
        fn = f"afsm_{f}{'f' if real else 'i'}"
        out = f"(double)({args[0]})" if real else args[0]
        for a in args[1:]:
            out = f"{fn}({out}, {'(double)(' + a + ')' if real else a})"
        return out
