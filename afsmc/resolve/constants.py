"""Constants and intervals: each constant's value computed once, in declaration order;
interval constants (`const int T = [2, 5]`, E204/E205), interval probabilities
(`const prob P = [0.01, 0.02]`, E205/E207); params set from the command line
(`--const NAME=VALUE`, E208/E209); a param with no value (E206).

A constant whose value stands in for one that was reported is *poisoned*: what follows only
from the stand-in (an empty range, a division by zero) is not reported again.
"""

from __future__ import annotations

import re
from typing import Any

from afsmc.diagnostics import Diagnostic, Severity, Span, codes
from afsmc.model import expr as E
from afsmc.model import ir
from afsmc.model.evaluate import EvalError, scalar
from afsmc.model.expr import Type
from afsmc.model.limits import INT64, NUMBERS_HINT, unrepresentable
from afsmc.model.names import did_you_mean
from afsmc.resolve.base import CONST_CTX, ResolverBase, a
from afsmc.syntax import ast
from afsmc.syntax.limits import clip

# A number as the language writes it (ASCII digits, no separators). Python's int() and
# float() also read 1_0, ١٢ and " 3 ", which the command line does not take.
_NUMBER = re.compile(r"[+-]?(?:[0-9]+(?:\.[0-9]*)?|\.[0-9]+)(?:[eE][+-]?[0-9]+)?")

# The digits of the largest 64-bit integer: a longer integer does not fit.
_INT64_DIGITS = len(str(INT64[1]))
_TYPES = {"int": Type.INT, "double": Type.DOUBLE, "prob": Type.DOUBLE, "bool": Type.BOOL}
_STAND_IN: dict[Type, Any] = {Type.INT: 0, Type.DOUBLE: 0.0, Type.BOOL: False}


def parse_override(text: str) -> tuple[str, str]:
    """`NAME=VALUE` from the command line."""
    if "=" not in text:
        raise ValueError(f"expected NAME=VALUE, got {text!r}")
    name, value = text.split("=", 1)
    if not name.strip():
        raise ValueError(f"expected NAME=VALUE, got {text!r} (no name)")
    if not value.strip():
        raise ValueError(f"expected NAME=VALUE, got {text!r} (no value)")
    return name.strip(), value.strip()


class ConstantsMixin(ResolverBase):
    def _constant(self, d: ast.ConstDecl | ast.ParamDecl) -> None:
        name = d.name.text
        if name in self.consts or self.value_names.get(name, ("", None))[1] != d.name.span:
            return  # a duplicate, already reported
        t = _TYPES[d.type]
        interval = None
        source = None
        is_param = isinstance(d, ast.ParamDecl)
        value: Any
        errors = len(self.rep.diagnostics)
        self.tainted = False
        self.reading_open = set()
        prob_interval = None
        if isinstance(d, ast.ConstDecl) and isinstance(d.value, ast.Interval) and d.type == "prob":
            prob_interval = self._prob_interval(d, d.value)
            value = (prob_interval[0] + prob_interval[1]) / 2
        elif isinstance(d, ast.ConstDecl) and isinstance(d.value, ast.Interval):
            interval = self._interval(d, d.value, t)
            value = interval[0]
        else:
            value = self._plain_value(d, t)
        if isinstance(d, ast.ConstDecl) and d.source is not None:
            source = ir.SimSource(d.source.ref.text,
                                  tuple((k.text, v) for k, v in d.source.policy), d.source.span,
                                  tuple(k.span for k, _ in d.source.policy),
                                  d.source.column.text if d.source.column else None)
        if self.reading_open:
            self.open_reads[name] = frozenset(self.reading_open)
        if self.tainted or len(self.rep.diagnostics) > errors:
            self.poisoned.add(name)
        elif d.type == "prob" and not (0.0 <= float(value) <= 1.0):
            self.rep.error(codes.E207, f"probability '{name}' = {value} is not in [0, 1]", d.span)
        self.consts[name] = ir.Constant(name, t, value, interval, is_param, source, d.span, d.type,
                                        prob_interval)

    def _prob_interval(self, d: ast.ConstDecl, iv: ast.Interval) -> tuple[float, float]:
        """`const prob P = [lo, hi]`: one unknown p with 0 <= lo <= p <= hi <= 1."""
        name = d.name.text
        lo = self._const_value(iv.lo, Type.DOUBLE)
        lo_tainted = self.tainted
        hi = self._const_value(iv.hi, Type.DOUBLE)
        self.tainted = self.tainted or lo_tainted
        lo, hi = float(lo), float(hi)
        if self.tainted:
            return lo, hi
        if lo > hi:
            self.rep.error(codes.E205, f"interval [{lo:g}, {hi:g}] of '{name}' is empty",
                           iv.span, hint="write [low, high] with low <= high")
        elif not (lo >= 0.0 and hi <= 1.0):
            self.rep.error(codes.E207, f"interval probability '{name}' = [{lo:g}, {hi:g}] is "
                           "not within [0, 1]", iv.span,
                           hint="both ends of a probability interval lie in [0, 1]")
        return lo, hi

    def _interval(self, d: ast.ConstDecl, iv: ast.Interval, t: Type) -> tuple[int, int]:
        """`const int T = [lo, hi]`: the two ends, reported if they make no interval."""
        name = d.name.text
        lo = self._const_value(iv.lo, Type.INT)
        lo_tainted = self.tainted
        hi = self._const_value(iv.hi, Type.INT)
        self.tainted = self.tainted or lo_tainted
        if t is not Type.INT:
            self.rep.error(codes.E204, f"interval constant '{name}' must be an int or a prob",
                           d.span, hint="timing and battery figures are whole numbers; "
                           "write 'const int' (the paper's floor and ceiling), or "
                           "'const prob' for an uncertain probability")
        elif isinstance(lo, int) and isinstance(hi, int) and lo > hi and not self.tainted:
            self.rep.error(codes.E205, f"interval [{lo}, {hi}] of '{name}' is empty",
                           iv.span, hint="write [low, high] with low <= high")
        return int(lo), int(hi)

    def _plain_value(self, d: ast.ConstDecl | ast.ParamDecl, t: Type) -> Any:
        """The value of a constant that is no interval: the command line's, the declared
        one, or a stand-in for a param with neither (E206)."""
        name = d.name.text
        expr = d.value if isinstance(d, ast.ConstDecl) else d.default
        if isinstance(d, ast.ParamDecl) and name in self.overrides:
            return self._parse_override(name, self.overrides[name], t, d.name.span)
        if expr is None:
            missing = Diagnostic(codes.E206, Severity.ERROR,
                                 f"open constant '{name}' has no value", d.name.span,
                                 hint=f"pass --const {name}=VALUE, or give it a default")
            if self.open_params:
                self.tainted = True  # a stand-in, as after E206
                self.open_errors[name] = missing
                self.reading_open.add(name)
            else:
                self.rep.extend([missing])
            return _STAND_IN[t]
        assert not isinstance(expr, ast.Interval)
        return self._const_value(expr, t)

    def _parse_override(self, name: str, text: str, t: Type, span: Span) -> Any:
        placeholder = _STAND_IN[t]
        try:
            if t is Type.BOOL:
                if text not in ("true", "false"):
                    raise ValueError
                return text == "true"
            if not _NUMBER.fullmatch(text) and text.lower().lstrip("+-") not in ("inf", "nan",
                                                                                 "infinity"):
                raise ValueError
            if t is Type.INT and text.isascii() and text.lstrip("+-").isdigit() and len(
                    text.lstrip("+-").lstrip("0")) > _INT64_DIGITS:
                # beyond 64 bits, and perhaps beyond what int() converts (4,300 digits)
                self.rep.error(codes.E208, f"--const {name}={clip(text)}: "
                               f"{unrepresentable(INT64[1] + 1)}", span, hint=NUMBERS_HINT)
                return placeholder
            value: int | float = int(text) if t is Type.INT else float(text)
        except ValueError:
            self.rep.error(codes.E208, f"--const {name}={clip(text)}: not {a(t.value)}", span)
            return placeholder
        why = unrepresentable(value)
        if why is not None:
            self.rep.error(codes.E208, f"--const {name}={clip(text)}: "
                           + (why if t is Type.INT else "not a finite double"), span,
                           hint=NUMBERS_HINT)
            return placeholder
        return value

    def _check_overrides(self) -> None:
        for name in self.overrides:
            c = self.consts.get(name)
            if c is None:
                params = sorted(n for n, k in self.consts.items() if k.is_param)
                self.rep.error(codes.E209, f"--const {name}: no open constant named '{name}'", None,
                               hint=(did_you_mean(name, params) or
                                     ("open constants: " + ", ".join(params) if params
                                      else "this file declares no 'param'")))
            elif not c.is_param:
                self.rep.error(codes.E209, f"--const {name}: '{name}' is a fixed constant", c.span,
                               hint="declare it with 'param' to let the command line set it")

    def _const_value(self, e: ast.Expr, want: Type) -> Any:
        """The value of `e`, of type `want`, from the constants declared so far. Sets
        `tainted` when it reads a stand-in, and notes the open params it reads."""
        x = self._expr(e, CONST_CTX)
        nodes = list(E.walk(x))
        refs = [n.name for n in nodes if isinstance(n, E.ConstRef)]
        self.tainted = any(id(n) in self.placeholders for n in nodes) or any(
            r in self.poisoned for r in refs)
        self.reading_open |= {p for r in refs for p in self.open_reads.get(r, ())}
        if (want.numeric and not x.type.numeric) or (want is Type.BOOL and x.type is not Type.BOOL):
            self.rep.error(codes.E210, f"expected {a(want.value)} value, found {a(x.type.value)}", e.span)
        if want is Type.INT and x.type is Type.DOUBLE:
            self.rep.error(codes.E210, "expected an int value, found a double", e.span,
                           hint="use floor(...) or ceil(...)")
        try:
            v = scalar(x, self._const_env())
        except (EvalError, ZeroDivisionError, OverflowError) as exc:
            if not self.tainted:  # not 100 / N after N's own E206: a stand-in's consequence
                self.rep.error(codes.E211, f"cannot evaluate this constant: {exc}", e.span)
            return 0
        if want is Type.DOUBLE and isinstance(v, int) and not isinstance(v, bool):
            v = float(v)
        return v
