"""AST -> IR: resolve names, type-check, number modes, instantiate constants.

Everything wrong is reported (not just the first problem): a failed sub-expression
becomes a placeholder of the expected type so that checking can go on.
"""

from __future__ import annotations

import math
import re
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

from afsmc.diagnostics import CompileError, Diagnostic, Related, Reporter, Severity, Span
from afsmc.model import expr as E
from afsmc.model import ir
from afsmc.model.evaluate import EvalError, RangeError, scalar
from afsmc.model.expr import Type
from afsmc.model.names import (
    LABEL_RESERVED,
    QUOTED_RESERVED,
    RESERVED,
    did_you_mean,
    safe_identifier,
)
from afsmc.syntax import ast
from afsmc.syntax.errors.messages import NESTED_TEMPORAL, NOT_OPERATOR, OPERATORS
from afsmc.syntax.parser import MAX_DEPTH
from afsmc.syntax.scan import flat_text, tokens

# How deeply a formula may nest once the formulas it uses are inlined (E246): the checks
# and the JANI backend inline them, recursively (see afsmc.stack).
MAX_INLINED_DEPTH = 2 * MAX_DEPTH


@dataclass(frozen=True)
class Ctx:
    """Where an expression stands decides what it may mention."""

    what: str  # for messages: "a guard", "a weight", ...
    state: bool = True  # variables and `mode`
    intervals: bool = False  # interval constants (only in updates)
    weights: bool = False  # w(Action)
    labels: bool = False  # "label" (only in properties)
    constant_only: bool = False


CONST_CTX = Ctx("a constant", state=False, constant_only=True)


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


INT64 = (-(2**63), 2**63 - 1)
_NUMBER = re.compile(r"[+-]?(?:[0-9]+(?:\.[0-9]*)?|\.[0-9]+)(?:[eE][+-]?[0-9]+)?")
_NUMBERS_HINT = "PRISM and Storm compute with 64-bit integers and finite doubles"
# What a variable (the mode included) may hold: Storm's explicit builder stored values
# beyond this wrongly (x : [0..2^49] init 2^49 started elsewhere, so P [F x = 2^49] was 0),
# and larger magnitudes were wrong even in small ranges (at 2^58).
STATE_INT = (-(2**48), 2**48 - 1)
_STATE_INT_HINT = "Storm's state encoding holds these wrongly; rescale the variable"
_BEYOND_STATE_INT = (f"goes beyond what Storm stores in a state ({STATE_INT[0]}..{STATE_INT[1]}, "
                     "±2^48)")


def unrepresentable(v: Any) -> str | None:
    """What keeps the value `v` from PRISM and Storm ("is infinite", ...), or None."""
    if isinstance(v, bool):
        return None
    if isinstance(v, int) and not INT64[0] <= v <= INT64[1]:
        return f"does not fit in a 64-bit integer ({INT64[0]} to {INT64[1]})"
    if isinstance(v, float) and not math.isfinite(v):
        return "is not a number (NaN)" if math.isnan(v) else "is infinite"
    return None


def _shown(v: int) -> str:
    """A huge integer, short: 1.00e300."""
    digits = str(abs(v))
    if len(digits) <= 24:
        return str(v)
    return f"{'-' if v < 0 else ''}{digits[0]}.{digits[1:3]}e{len(digits) - 1}"


def resolve(module: ast.Module, overrides: Mapping[str, str] | None = None, *,
            open_params: bool = False) -> ir.Model:
    """`open_params`: a param with no value is no error but a stand-in (for sim-check, which
    needs only the values of the simulated constants): `model.cache["open_params"]` maps
    each such param to the E206 it would have been, and `model.cache["open_reads"]` each
    constant whose value reads them (through other constants too) to their names."""
    r = _Resolver(module, dict(overrides or {}), open_params)
    model = r.run()
    if r.rep.has_errors:
        raise CompileError(r.rep.sorted())
    model.cache["warnings"] = [d for d in r.rep.sorted() if not d.is_error]
    model.cache["used_names"] = frozenset(r.used)
    model.cache["open_params"] = dict(r.open_errors)
    model.cache["open_reads"] = dict(r.open_reads)
    return model


class _Resolver:
    def __init__(self, module: ast.Module, overrides: dict[str, str], open_params: bool = False):
        self.m = module
        self.src = module.span.source
        self.rep = Reporter()
        self.overrides = overrides
        self.consts: dict[str, ir.Constant] = {}
        self.vars: dict[str, ir.Variable] = {}
        self.tuples: dict[str, tuple[str, ...]] = {}  # tuple var -> its field names
        # fields left out after their own E201 (`pos.x` clashing with `pos_x`): no E223 on use
        self.dropped_fields: set[tuple[str, str]] = set()
        # _placeholder's stand-ins by id (held here, so no other object takes their id)
        self.placeholders: dict[int, E.Expr] = {}
        # Constants whose value stands in for one that was reported (E206, E228, ...), and
        # whether the last _const_value read one: a range over them is not also "empty".
        self.poisoned: set[str] = set()
        self.tainted = False
        self.open_params = open_params  # see resolve()
        self.open_errors: dict[str, Diagnostic] = {}  # the E206 of each param it stood in for
        self.open_reads: dict[str, frozenset[str]] = {}  # constant -> open params it reads
        self.reading_open: set[str] = set()  # those of the declaration being resolved
        self.modes: dict[str, ir.Mode] = {}
        self.formulas: dict[str, ir.Formula] = {}
        self.formula_decls: dict[str, ast.FormulaDecl] = {}
        self.formula_stack: list[str] = []
        self.formula_depth: dict[str, int] = {}  # inlined (E246)
        self.reward_structs: dict[str, ir.RewardStruct] = {}
        self.action_names: dict[str, Span] = {}
        # probabilistic hazards: a branch of each action of their modes, not an action with
        # a weight or a PRISM command of its own (E248)
        self.branch_hazards: set[str] = set()
        self.label_names: dict[str, Span] = {}
        self.reward_names: dict[str, Span] = {}
        # one namespace for everything an expression can name
        self.value_names: dict[str, tuple[str, Span]] = {}
        self.used: set[str] = set()  # constants and formulas referenced anywhere
        self._free: dict[int, tuple[E.Expr, bool]] = {}  # id -> (node, state-free)

    # ---- driver ------------------------------------------------------------------
    def run(self) -> ir.Model:
        decls = self.m.decls
        self._declare_names(decls)
        for d in decls:
            if isinstance(d, (ast.ConstDecl, ast.ParamDecl)):
                self._constant(d)
        self._check_overrides()
        self._modes([d for d in decls if isinstance(d, ast.ModeDecl)])
        for d in decls:
            if isinstance(d, ast.VarDecl):
                self._variable(d)
        self._check_action_vs_variable()
        self.formula_decls = {d.name.text: d for d in decls if isinstance(d, ast.FormulaDecl)}
        for d in decls:
            if isinstance(d, ast.FormulaDecl):
                self._formula(d.name.text)
        actions = [self._action(d) for d in decls if isinstance(d, ast.ActionDecl)]
        hazards: list[ir.Hazard] = []
        for d in decls:
            if isinstance(d, ast.HazardDecl):
                if d.kind == "preemptive":
                    actions.append(self._preemptive(d))
                else:
                    hazards.append(self._hazard(d))
        labels = [ir.Label(d.name.text, self._bool(d.value, Ctx("a label")), d.span)
                  for d in decls if isinstance(d, ast.LabelDecl)]
        rewards = [self._rewards(d) for d in decls if isinstance(d, ast.RewardsDecl)]
        self.reward_structs = {r.name: r for r in rewards}
        props = [self._property(d) for d in decls if isinstance(d, ast.PropertyDecl)]
        self._check_query_names(props)
        self._check_weight_cycles(actions)
        name = self.m.machine.name.text if self.m.machine else _stem(self.src.path)
        return ir.Model(
            name=name, source=self.src, constants=tuple(self.consts.values()),
            variables=tuple(self.vars.values()),
            modes=tuple(sorted(self.modes.values(), key=lambda m: m.number)),
            actions=tuple(actions), hazards=tuple(hazards),
            formulas=tuple(self.formulas[n] for n in self.formula_decls if n in self.formulas),
            labels=tuple(labels), rewards=tuple(rewards), properties=tuple(props))

    # ---- names -------------------------------------------------------------------
    def _declare_names(self, decls: tuple[ast.Decl, ...]) -> None:
        if self.m.machine is not None:  # PRISM's module
            self._check_reserved(self.m.machine.name, "machine")
        for d in decls:
            if isinstance(d, (ast.ConstDecl, ast.ParamDecl)):
                self._declare_value(d.name, "constant")
            elif isinstance(d, ast.VarDecl):
                self._declare_value(d.name, "variable")
            elif isinstance(d, ast.ModeDecl):
                self._declare_value(d.name, "mode")
            elif isinstance(d, ast.FormulaDecl):
                self._declare_value(d.name, "formula")
            elif isinstance(d, (ast.ActionDecl, ast.HazardDecl)):
                self._declare_in(self.action_names, d.name, "action")
                if isinstance(d, ast.HazardDecl) and d.kind == "probabilistic":
                    self.branch_hazards.add(d.name.text)
            elif isinstance(d, ast.LabelDecl):
                self._declare_in(self.label_names, d.name, "label")
            elif isinstance(d, ast.RewardsDecl):
                self._declare_in(self.reward_names, d.name, "reward structure")
        props: dict[str, Span] = {}
        for d in decls:
            if isinstance(d, ast.PropertyDecl):
                self._declare_in(props, d.name, "property")

    def _declare_value(self, name: ast.Ident, kind: str) -> None:
        if name.text in self.value_names:
            other_kind, other = self.value_names[name.text]
            self.rep.error("E201", f"'{name.text}' is already declared as {_a(other_kind)}", name.span,
                           related=[Related("first declared here", other)])
            return
        if kind != "mode":  # modes compile to numbers, never to identifiers
            self._check_reserved(name, kind)
        self.value_names[name.text] = (kind, name.span)

    def _declare_in(self, table: dict[str, Span], name: ast.Ident, kind: str) -> None:
        if name.text in table:
            self.rep.error("E201", f"{kind} '{name.text}' is declared twice", name.span,
                           related=[Related("first declared here", table[name.text])])
            return
        reserved = {"action": RESERVED, "label": LABEL_RESERVED,
                    "reward structure": QUOTED_RESERVED}.get(kind, frozenset())
        self._check_reserved(name, kind, reserved)
        table[name.text] = name.span

    def _check_internal(self, name: ast.Ident, kind: str) -> None:
        # __afsmc...: the queries and names afsmc generates; any other __ name: Storm's
        # parsers refuse it ("illegal identifier").
        if name.text.startswith("__"):
            self.rep.error("E202", f"'{name.text}' cannot name {_a(kind)}: names that start "
                           "with __ are reserved for Storm and afsmc", name.span,
                           hint=f"choose another name, e.g. '{name.text.lstrip('_')}'"
                           if name.text.strip("_") else "choose another name")

    def _check_action_vs_variable(self) -> None:
        """An action (or hazard) named like a variable: PRISM takes it, but Storm's symbolic
        engines (hybrid, dd; `auto` on a large model) cannot build it ("a meta variable
        already exists"), so the sparse engine would be the only one left."""
        for name, span in self.action_names.items():
            var = self.vars.get(name)
            if var is not None:
                self.rep.error("E201", f"'{name}' names both an action and the variable "
                               f"{var.display}: Storm's symbolic engines need them distinct",
                               span, hint=f"rename the action, e.g. '{name}_act'",
                               related=[Related(f"{var.display} is declared here", var.span)])

    def _check_reserved(self, name: ast.Ident, kind: str, reserved: frozenset[str] = RESERVED) -> None:
        self._check_internal(name, kind)
        if name.text in reserved:
            self.rep.error(
                "E202", f"'{name.text}' cannot name {_a(kind)}: it is reserved in PRISM or Storm",
                name.span, hint=f"choose another name, e.g. '{name.text}_{kind.split()[0]}'")

    def _undefined(self, name: ast.Ident, ctx: Ctx) -> None:
        candidates = list(self.value_names)
        self.rep.error("E203", f"'{name.text}' is not declared", name.span,
                       hint=did_you_mean(name.text, candidates))

    # ---- constants ------------------------------------------------------------------
    def _type(self, t: str) -> Type:
        return {"int": Type.INT, "double": Type.DOUBLE, "prob": Type.DOUBLE, "bool": Type.BOOL}[t]

    def _constant(self, d: ast.ConstDecl | ast.ParamDecl) -> None:
        name = d.name.text
        if name in self.consts or self.value_names.get(name, ("", None))[1] != d.name.span:
            return  # a duplicate, already reported
        t = self._type(d.type)
        interval = None
        source = None
        is_param = isinstance(d, ast.ParamDecl)
        value: Any
        errors = len(self.rep.diagnostics)
        self.tainted = False
        self.reading_open = set()
        if isinstance(d, ast.ConstDecl) and isinstance(d.value, ast.Interval):
            lo = self._const_value(d.value.lo, Type.INT)
            lo_tainted = self.tainted
            hi = self._const_value(d.value.hi, Type.INT)
            self.tainted = self.tainted or lo_tainted
            if t is not Type.INT:
                self.rep.error("E204", f"interval constant '{name}' must be an int",
                               d.span, hint="timing and battery figures are whole numbers; "
                               "write 'const int' (the paper's floor and ceiling)")
            elif isinstance(lo, int) and isinstance(hi, int) and lo > hi and not self.tainted:
                self.rep.error("E205", f"interval [{lo}, {hi}] of '{name}' is empty",
                               d.value.span, hint="write [low, high] with low <= high")
            interval = (int(lo), int(hi))
            value = int(lo)
        else:
            expr = d.value if isinstance(d, ast.ConstDecl) else d.default
            if is_param and name in self.overrides:
                value = self._parse_override(name, self.overrides[name], t, d.name.span)
            elif expr is None:
                missing = Diagnostic("E206", Severity.ERROR,
                                     f"open constant '{name}' has no value", d.name.span,
                                     hint=f"pass --const {name}=VALUE, or give it a default")
                if self.open_params:
                    self.tainted = True  # a stand-in, as after E206
                    self.open_errors[name] = missing
                    self.reading_open.add(name)
                else:
                    self.rep.extend([missing])
                value = {Type.INT: 0, Type.DOUBLE: 0.0, Type.BOOL: False}[t]
            else:
                assert not isinstance(expr, ast.Interval)
                value = self._const_value(expr, t)
        if isinstance(d, ast.ConstDecl) and d.source is not None:
            source = ir.SimSource(d.source.ref.text,
                                  tuple((k.text, v) for k, v in d.source.policy), d.source.span,
                                  tuple(k.span for k, _ in d.source.policy))
        if self.reading_open:
            self.open_reads[name] = frozenset(self.reading_open)
        if self.tainted or len(self.rep.diagnostics) > errors:
            self.poisoned.add(name)
        elif d.type == "prob" and not (0.0 <= float(value) <= 1.0):
            self.rep.error("E207", f"probability '{name}' = {value} is not in [0, 1]", d.span)
        self.consts[name] = ir.Constant(name, t, value, interval, is_param, source, d.span, d.type)

    def _parse_override(self, name: str, text: str, t: Type, span: Span) -> Any:
        placeholder = {Type.INT: 0, Type.DOUBLE: 0.0, Type.BOOL: False}[t]
        try:
            if t is Type.BOOL:
                if text not in ("true", "false"):
                    raise ValueError
                return text == "true"
            # Python also reads 1_0, ١٢ and " 3 "; the command line takes numbers as the
            # language writes them (ASCII digits, no separators).
            if not _NUMBER.fullmatch(text) and text.lower().lstrip("+-") not in ("inf", "nan",
                                                                                 "infinity"):
                raise ValueError
            value: int | float = int(text) if t is Type.INT else float(text)
        except ValueError:
            self.rep.error("E208", f"--const {name}={text}: not {_a(t.value)}", span)
            return placeholder
        why = unrepresentable(value)
        if why is not None:
            self.rep.error("E208", f"--const {name}={text}: "
                           + (why if t is Type.INT else "not a finite double"), span,
                           hint=_NUMBERS_HINT)
            return placeholder
        return value

    def _check_overrides(self) -> None:
        for name in self.overrides:
            c = self.consts.get(name)
            if c is None:
                params = sorted(n for n, k in self.consts.items() if k.is_param)
                self.rep.error("E209", f"--const {name}: no open constant named '{name}'", None,
                               hint=(did_you_mean(name, params) or
                                     ("open constants: " + ", ".join(params) if params
                                      else "this file declares no 'param'")))
            elif not c.is_param:
                self.rep.error("E209", f"--const {name}: '{name}' is a fixed constant", c.span,
                               hint="declare it with 'param' to let the command line set it")

    def _const_value(self, e: ast.Expr, want: Type) -> Any:
        x = self._expr(e, CONST_CTX)
        nodes = list(E.walk(x))
        refs = [n.name for n in nodes if isinstance(n, E.ConstRef)]
        self.tainted = any(id(n) in self.placeholders for n in nodes) or any(
            r in self.poisoned for r in refs)
        self.reading_open |= {p for r in refs for p in self.open_reads.get(r, ())}
        if (want.numeric and not x.type.numeric) or (want is Type.BOOL and x.type is not Type.BOOL):
            self.rep.error("E210", f"expected {_a(want.value)} value, found {_a(x.type.value)}", e.span)
        if want is Type.INT and x.type is Type.DOUBLE:
            self.rep.error("E210", "expected an int value, found a double", e.span,
                           hint="use floor(...) or ceil(...)")
        try:
            v = scalar(x, self._const_env())
        except (EvalError, ZeroDivisionError, OverflowError) as exc:
            if not self.tainted:  # not 100 / N after N's own E206: a stand-in's consequence
                self.rep.error("E211", f"cannot evaluate this constant: {exc}", e.span)
            return 0
        if want is Type.DOUBLE and isinstance(v, int) and not isinstance(v, bool):
            v = float(v)
        return v

    def _const_env(self) -> dict[str, Any]:
        return {n: c.value for n, c in self.consts.items()}

    # ---- modes ----------------------------------------------------------------------
    def _modes(self, decls: list[ast.ModeDecl]) -> None:
        used: dict[int, ast.ModeDecl] = {}
        for d in decls:
            if d.number is not None:
                why = unrepresentable(d.number)
                if why is not None or not STATE_INT[0] <= d.number <= STATE_INT[1]:
                    self.rep.error(
                        "E245" if why is not None else "E249", f"mode number {d.number} " + (
                            why or _BEYOND_STATE_INT), d.number_span or d.span,
                        hint=_NUMBERS_HINT if why is not None else "number the modes with "
                        "smaller numbers")
                    continue  # numbered as if it had no number
                if d.number in used:
                    self.rep.error("E212", f"mode number {d.number} is used twice",
                                   d.number_span or d.span,
                                   related=[Related(f"{used[d.number].name.text} has it",
                                                    used[d.number].name.span)])
                else:
                    used[d.number] = d
        nxt = 0
        for d in decls:
            if self.value_names.get(d.name.text, ("", None))[1] != d.name.span:
                continue
            number = d.number
            if number is None or used.get(number) is not d:
                while nxt in used:
                    nxt += 1
                number = nxt
                used[number] = d
            self.modes[d.name.text] = ir.Mode(d.name.text, number, d.initial, d.final, d.span)
        initial = [d for d in decls if d.initial]
        if not decls:
            self.rep.error("E213", "the machine declares no modes", Span.whole_file(self.src),
                           hint="add e.g. 'mode Idle = 0 initial;'")
        elif not initial:
            self.rep.error("E213", "no mode is marked initial", decls[0].span,
                           hint=f"write 'mode {decls[0].name.text}"
                           + (f" = {decls[0].number}" if decls[0].number is not None else "")
                           + " initial;'")
        elif len(initial) > 1:
            self.rep.error("E214", "more than one mode is marked initial", initial[1].span,
                           related=[Related("also initial", initial[0].span)])

    def _mode_set(self, ms: ast.ModeSet, for_what: str) -> tuple[int, ...]:
        by_number = {m.number: m for m in self.modes.values()}
        chosen: set[int] = set()
        for item in ms.items:
            if isinstance(item, ast.ModeName):
                mode = self.modes.get(item.name.text)
                if mode is None:
                    self.rep.error("E215", f"'{item.name.text}' is not a mode", item.span,
                                   hint=did_you_mean(item.name.text, self.modes))
                else:
                    chosen.add(mode.number)
            elif isinstance(item, ast.ModeNumber):
                if item.number not in by_number:
                    self.rep.error("E215", f"no mode has number {item.number}", item.span)
                else:
                    chosen.add(item.number)
            else:
                hit = {n for n in by_number if item.lo <= n <= item.hi}
                if item.lo > item.hi or not hit:
                    self.rep.error("E215", f"no mode has a number in {item.lo}..{item.hi}",
                                   item.span)
                chosen |= hit
        if ms.every:
            # `*` means every mode that can act: final modes are absorbing.
            everything = {m.number for m in self.modes.values() if not m.final}
            chosen = everything - chosen
            if not chosen:
                self.rep.warning("W603", f"{for_what} can never fire: its mode set is empty "
                                 "('*' leaves out the final modes)", ms.span,
                                 hint="name the modes it acts in, or remove it")
        else:
            for n in sorted(chosen):
                if by_number[n].final:
                    self.rep.error("E216", f"mode {by_number[n].name} is final: {for_what} "
                                   "cannot act in it", ms.span,
                                   hint="final modes are absorbing; remove it from the set")
        return tuple(sorted(chosen))

    # ---- variables -------------------------------------------------------------------
    def _variable(self, d: ast.VarDecl) -> None:
        if self.value_names.get(d.name.text, ("", None))[1] != d.name.span:
            return
        if isinstance(d.type, ast.TupleType):
            inits: list[ast.Expr | None]
            if d.init is None:
                inits = [None] * len(d.type.fields)
            elif isinstance(d.init, ast.TupleLit) and len(d.init.items) == len(d.type.fields):
                inits = list(d.init.items)
            elif len(d.type.fields) == 1 and not isinstance(d.init, ast.TupleLit):
                inits = [d.init]  # `(1)` is the number 1: one field takes a plain value
            else:
                self.rep.error("E217", f"'{d.name.text}' has {len(d.type.fields)} fields; "
                               "give one initial value per field", d.init.span)
                inits = [None] * len(d.type.fields)
            names = []
            for f, init in zip(d.type.fields, inits, strict=True):
                flat = f"{d.name.text}_{f.name.text}"
                if flat in self.value_names:
                    self.rep.error("E201", f"field {d.name.text}.{f.name.text} would be named "
                                   f"'{flat}' in PRISM, which is already declared", f.span,
                                   hint=f"rename the field or the other '{flat}'",
                                   related=[Related(f"'{flat}' is declared here",
                                                    self.value_names[flat][1])])
                    self.dropped_fields.add((d.name.text, f.name.text))
                    continue
                if f.name.text in names:
                    self.rep.error("E201", f"field '{f.name.text}' is declared twice", f.span)
                    continue
                names.append(f.name.text)
                self._one_var(flat, f"{d.name.text}.{f.name.text}", f.type, init, d.clamp, f.span)
            self.tuples[d.name.text] = tuple(names)
        else:
            if isinstance(d.init, ast.TupleLit):
                self.rep.error("E217", f"'{d.name.text}' is not a tuple", d.init.span)
                init = None
            else:
                init = d.init
            self._one_var(d.name.text, d.name.text, d.type, init, d.clamp, d.span)

    def _one_var(self, flat: str, display: str, t: ast.RangeType | ast.BoolType,
                 init: ast.Expr | None, clamp: bool, span: Span) -> None:
        if isinstance(t, ast.BoolType):
            if clamp:
                self.rep.error("E218", f"'{display}' is a bool; only integers can clamp", span)
            value = False if init is None else bool(self._const_value(init, Type.BOOL))
            self.vars[flat] = ir.Variable(flat, display, Type.BOOL, 0, 1, value, False, span)
            return
        lo = self._const_value(t.lo, Type.INT)
        tainted = self.tainted
        hi = self._const_value(t.hi, Type.INT)
        tainted = tainted or self.tainted
        broken = False  # the range is reported: no E220 against a range never written
        if not (isinstance(lo, int) and isinstance(hi, int)):
            lo, hi, broken = 0, 0, True
        elif tainted and lo > hi:  # a stand-in value of a reported constant: not also E219
            hi, broken = lo, True
        if lo > hi:
            self.rep.error("E219", f"range [{lo}..{hi}] of '{display}' is empty", t.span)
            hi, broken = lo, True
        if broken:
            init = None
        if not (STATE_INT[0] <= lo and hi <= STATE_INT[1]):
            self.rep.error("E249", f"range [{lo}..{hi}] of '{display}' {_BEYOND_STATE_INT}",
                           t.span, hint=_STATE_INT_HINT)
            # go on with a range Storm holds, and no second error about the initial value
            lo, hi = (min(max(v, STATE_INT[0]), STATE_INT[1]) for v in (lo, hi))
            init = None
        iv = lo if init is None else self._const_value(init, Type.INT)
        if not isinstance(iv, int) or not lo <= iv <= hi:
            self.rep.error("E220", f"initial value {iv} of '{display}' is outside [{lo}..{hi}]",
                           init.span if init is not None else span)
            iv = lo
        self.vars[flat] = ir.Variable(flat, display, Type.INT, lo, hi, iv, clamp, span)

    # ---- formulas ------------------------------------------------------------------
    def _formula(self, name: str) -> ir.Formula | None:
        if name in self.formulas:
            return self.formulas[name]
        d = self.formula_decls[name]
        if name in self.formula_stack:
            self.rep.error("E221", f"formula '{name}' refers to itself",
                           d.name.span, hint=" -> ".join([*self.formula_stack, name]))
            return None
        self.formula_stack.append(name)
        value = self._expr(d.value, Ctx("a formula"))
        self.formula_stack.pop()
        depth = E.depth(value, lambda n: self.formula_depth.get(n, 1))
        self.formula_depth[name] = depth
        if depth > MAX_INLINED_DEPTH:
            self.rep.error("E246", f"formula '{name}' nests {depth} levels deep once the "
                           f"formulas it uses are inlined; afsmc supports {MAX_INLINED_DEPTH}",
                           d.name.span, hint="shorten it or the formulas it uses (each "
                           "operator of a chain like 'a + b + c' is one level)")
            if value.type.numeric or value.type is Type.BOOL:  # no more inlining of it
                value = E.Lit(False if value.type is Type.BOOL else 0, value.type, d.value.span)
        f = ir.Formula(name, value, d.span)
        self.formulas[name] = f
        return f

    # ---- expressions ---------------------------------------------------------------
    def _placeholder(self, s: Span) -> E.Expr:
        """What an expression that was just reported stands for: no type error follows
        from it (a missing field in `F p.z` is E223, not also E222)."""
        x = E.Lit(0, Type.INT, s)
        self.placeholders[id(x)] = x
        return x

    def _bool(self, e: ast.Expr, ctx: Ctx) -> E.Expr:
        x = self._expr(e, ctx)
        if id(x) in self.placeholders:
            return E.TRUE
        if x.type is not Type.BOOL:
            self.rep.error("E222", f"{ctx.what} must be true or false, not {_a(x.type.value)}", e.span,
                           hint="compare it, e.g. 'x > 0'")
            return E.TRUE
        return x

    def _num(self, e: ast.Expr, ctx: Ctx) -> E.Expr:
        x = self._expr(e, ctx)
        if not x.type.numeric and id(x) not in self.placeholders:
            self.rep.error("E222", f"{ctx.what} must be a number, not {_a(x.type.value)}", e.span)
            return E.Lit(0, Type.INT, e.span)
        return x

    def _expr(self, e: ast.Expr, ctx: Ctx) -> E.Expr:
        x = self._build(e, ctx)
        if isinstance(x, (E.Unary, E.Binary, E.Call)) and x.type.numeric and self._state_free(x):
            # Storm folds such parts itself, and fails on an infinite or too large result.
            why: str | None
            try:
                v = scalar(x, self._const_env())
                why = unrepresentable(v)
                if why is not None:
                    why = f"its value {_shown(v) + ' ' if isinstance(v, int) else ''}{why}"
            except RangeError as exc:
                why = str(exc)
            except (EvalError, ArithmeticError):
                return x  # e.g. 1/0 under a `?:` that never takes it
            if why is not None:
                self.rep.error("E245", f"this expression cannot be compiled: {why}", e.span,
                               hint=_NUMBERS_HINT)
                return E.Lit(0 if x.type is Type.INT else 0.0, x.type, e.span)
        return x

    def _state_free(self, x: E.Expr) -> bool:
        """E.state_free, remembered for the nodes built so far: each node of a long chain
        asks it, and walking the chain below every node would take quadratic time."""
        known = self._free.get(id(x))
        if known is not None and known[0] is x:
            return known[1]
        free = isinstance(x, (E.Lit, E.ConstRef, E.Unary, E.Binary, E.Ite, E.Call)) and all(
            self._state_free(c) if id(c) in self._free else E.state_free(c)
            for c in E.children(x))
        self._free[id(x)] = (x, free)
        return free

    def _build(self, e: ast.Expr, ctx: Ctx) -> E.Expr:
        s = e.span
        if isinstance(e, ast.Num):
            t = Type.INT if isinstance(e.value, int) else Type.DOUBLE
            why = unrepresentable(e.value)
            if why is not None:
                self.rep.error("E245", f"{e.text} " + (why if t is Type.INT else "is too large for a "
                                                       "double: it would be infinite"),
                               s, hint=_NUMBERS_HINT)
                return E.Lit(0 if t is Type.INT else 0.0, t, s)
            return E.Lit(e.value, t, s)
        if isinstance(e, ast.BoolLit):
            return E.Lit(e.value, Type.BOOL, s)
        if isinstance(e, ast.Name):
            return self._name(e.name, ctx, s)
        if isinstance(e, ast.FieldRef):
            if not ctx.state and self.value_names.get(e.base.text, (None,))[0] == "variable":
                # a constant: the tuples are not resolved yet, and no field could be used
                return self._stateless(ctx, s, f"{e.base.text}.{e.field.text}")
            if e.base.text not in self.tuples:
                if e.base.text in self.value_names:
                    self.rep.error("E223", f"'{e.base.text}' has no fields", e.span)
                else:
                    self._undefined(e.base, ctx)
                return self._placeholder(s)
            if e.field.text not in self.tuples[e.base.text]:
                if (e.base.text, e.field.text) in self.dropped_fields:
                    return self._placeholder(s)
                self.rep.error("E223", f"'{e.base.text}' has no field '{e.field.text}'", e.field.span,
                               hint=did_you_mean(e.field.text, self.tuples[e.base.text]))
                return self._placeholder(s)
            return self._var(f"{e.base.text}_{e.field.text}", ctx, s,
                             f"{e.base.text}.{e.field.text}")
        if isinstance(e, ast.ModeRef):
            if not ctx.state:
                self.rep.error("E224", f"{ctx.what} cannot depend on the mode", s)
                return E.Lit(0, Type.MODE, s)
            return E.CurrentMode(s)
        if isinstance(e, ast.ModeIn):
            if not ctx.state:
                self.rep.error("E224", f"{ctx.what} cannot depend on the mode", s)
                return E.FALSE
            return E.mode_in(set(self._mode_set_any(e.modes)),
                             {m.number: m.name for m in self.modes.values()})
        if isinstance(e, ast.LabelRef):
            if not ctx.labels:
                self.rep.error("E225", f"labels like \"{e.name}\" can only be used in properties", s,
                               hint="use a formula to share an expression")
                return E.FALSE
            if e.name not in self.label_names:
                self.rep.error("E203", f"label \"{e.name}\" is not declared", s,
                               hint=did_you_mean(e.name, self.label_names))
                return E.FALSE
            return E.LabelRef(e.name, s)
        if isinstance(e, ast.Call):
            return self._call(e, ctx)
        if isinstance(e, ast.Unary):
            if e.op == "!":
                return E.Unary("!", self._bool(e.operand, ctx), Type.BOOL, s)
            x = self._num(e.operand, ctx)
            return E.Unary("-", x, x.type, s)
        if isinstance(e, ast.Ite):
            c = self._bool(e.cond, ctx)
            a = self._expr(e.then, ctx)
            b = self._expr(e.other, ctx)
            return E.Ite(c, a, b, self._unify(a, b, e, "the two branches of '?:'"), s)
        assert isinstance(e, ast.Binary)
        op = e.op
        if op in ("&&", "||", "=>"):
            return E.Binary(op, self._bool(e.left, ctx), self._bool(e.right, ctx), Type.BOOL, s)
        if op in ("+", "-", "*", "/"):
            a = self._num(e.left, ctx)
            b = self._num(e.right, ctx)
            t = Type.DOUBLE if op == "/" else self._unify(a, b, e, f"the operands of '{op}'")
            return E.Binary(op, a, b, t, s)
        a = self._expr(e.left, ctx)
        b = self._expr(e.right, ctx)
        if id(a) in self.placeholders or id(b) in self.placeholders:
            # an operand that has had its error (undeclared, no such field): no type error
            # that follows from its stand-in's type (`mode == Alpa` is not mode against int)
            return E.Binary(op, a, b, Type.BOOL, s)
        if op in ("==", "!="):
            if a.type.numeric != b.type.numeric or (not a.type.numeric and a.type is not b.type):
                self.rep.error("E226", f"cannot compare {_a(a.type.value)} with {_a(b.type.value)}", s,
                               hint="modes compare with modes: 'mode == Search'"
                               if Type.MODE in (a.type, b.type) else None)
            return E.Binary(op, a, b, Type.BOOL, s)
        if not (a.type.numeric and b.type.numeric):
            bad = a if not a.type.numeric else b
            self.rep.error("E226", f"'{op}' compares numbers, not {_a(bad.type.value)}", bad.span or s)
        return E.Binary(op, a, b, Type.BOOL, s)

    def _unify(self, a: E.Expr, b: E.Expr, e: Any, what: str) -> Type:
        if a.type is b.type:
            return a.type
        if id(a) in self.placeholders or id(b) in self.placeholders:
            return b.type if id(a) in self.placeholders else a.type
        if a.type.numeric and b.type.numeric:
            return Type.DOUBLE
        self.rep.error("E226", f"{what} have different types ({a.type.value}, {b.type.value})",
                       e.span)
        return a.type

    def _mode_set_any(self, ms: ast.ModeSet) -> tuple[int, ...]:
        # In expressions final modes are fine: `mode in {Done, Crashed}`.
        by_name = {m.name: m.number for m in self.modes.values()}
        out: set[int] = set()
        for item in ms.items:
            if isinstance(item, ast.ModeName):
                if item.name.text in by_name:
                    out.add(by_name[item.name.text])
                else:
                    self.rep.error("E215", f"'{item.name.text}' is not a mode", item.span,
                                   hint=did_you_mean(item.name.text, by_name))
            elif isinstance(item, ast.ModeNumber):
                # as in an action's mode set: a number no mode has is a typo, not `false`
                if item.number in by_name.values():
                    out.add(item.number)
                else:
                    self.rep.error("E215", f"no mode has number {item.number}", item.span)
            else:
                hit = {n for n in by_name.values() if item.lo <= n <= item.hi}
                if not hit:
                    self.rep.error("E215", f"no mode has a number in {item.lo}..{item.hi}",
                                   item.span)
                out |= hit
        numbers = set(by_name.values())
        return tuple(sorted((numbers - out) if ms.every else (out & numbers)))

    def _name(self, ident: ast.Ident, ctx: Ctx, s: Span) -> E.Expr:
        n = ident.text
        kind = self.value_names.get(n, (None, None))[0]
        if kind is None:
            if n in self.action_names:
                self.rep.error("E227", f"'{n}' is an action, not a value", s,
                               hint=f"its weight is written w({n})" if ctx.weights else None)
            else:
                self._undefined(ident, ctx)
            return self._placeholder(s)
        if kind in ("constant", "formula"):
            self.used.add(n)
        if kind == "constant":
            c = self.consts.get(n)
            if c is None:
                self.rep.error("E228", f"constant '{n}' is used before its declaration", s)
                return self._placeholder(s)
            if c.is_interval and not ctx.intervals:
                self.rep.error(
                    "E229", f"interval constant '{n}' can only be used in updates, not in {ctx.what}",
                    s, hint="the floor/ceil choice is made per action; use a plain constant here")
            return E.ConstRef(n, c.type, s)
        if kind == "variable":
            if n in self.tuples:
                self.rep.error("E230", f"'{n}' is a tuple; name a field, e.g. {n}.{self.tuples[n][0]}",
                               s)
                return self._placeholder(s)
            return self._var(n, ctx, s, n)
        if kind == "mode":
            mode = self.modes.get(n)
            return E.ModeVal(n, mode.number if mode else 0, s)
        # formula
        if ctx.constant_only:
            self.rep.error("E231", f"{ctx.what} cannot use formula '{n}'", s)
            return self._placeholder(s)
        f = self._formula(n) if n in self.formula_decls else None
        if f is None:
            return self._placeholder(s)
        return E.FormulaRef(n, f.value.type, s)

    def _stateless(self, ctx: Ctx, s: Span, display: str) -> E.Expr:
        """E224: a variable where only constants may stand."""
        self.rep.error("E224", f"{ctx.what} cannot depend on variable '{display}'", s)
        return self._placeholder(s)

    def _var(self, flat: str, ctx: Ctx, s: Span, display: str) -> E.Expr:
        # Before the variables are resolved (constants come first), and for a variable with
        # errors, `self.vars` lacks it: E224 must not depend on that.
        if not ctx.state:
            return self._stateless(ctx, s, display)
        v = self.vars.get(flat)
        if v is None:  # a variable with errors
            return self._placeholder(s)
        return E.VarRef(flat, v.type, s)

    def _call(self, e: ast.Call, ctx: Ctx) -> E.Expr:
        f = e.func.text
        s = e.span
        if f == "w":
            if len(e.args) != 1 or not isinstance(e.args[0], ast.Name):
                self.rep.error("E232", "w(...) takes one action name", s)
                return self._placeholder(s)
            target = e.args[0].name
            if not ctx.weights:
                self.rep.error("E232", f"w({target.text}) can only be used in a weight", s)
                return self._placeholder(s)
            if target.text not in self.action_names:
                self.rep.error("E203", f"'{target.text}' is not an action", target.span,
                               hint=did_you_mean(target.text, self.action_names))
                return self._placeholder(s)
            if target.text in self.branch_hazards:
                self.rep.error("E248", f"'{target.text}' is a probabilistic hazard: it has no "
                               "weight, it is a branch of every action of its modes", target.span,
                               hint="w(...) names an action or a hazard with a condition (when)")
                return self._placeholder(s)
            return E.WeightRef(target.text, s)
        if f in ("F", "G", "X") and ctx.labels:
            # `P=? [ F F (x == 1) ]`: the inner operator reads as a call
            self.rep.error("E115", NESTED_TEMPORAL, e.func.span,
                           hint=f"the {f} here stands inside another temporal operator's "
                                "formula; write one operator per property")
            return self._placeholder(s)
        if f == "not":  # `not (x == 1)` reads as a call
            self.rep.error("E123", NOT_OPERATOR, e.func.span, hint=OPERATORS)
            return self._placeholder(s)
        if f not in E.FUNCTIONS:
            self.rep.error("E233", f"unknown function '{f}'", e.func.span,
                           hint=did_you_mean(f, [*E.FUNCTIONS, "w"]) or
                           "functions: " + ", ".join(sorted(E.FUNCTIONS)) + ", w(Action)")
            return self._placeholder(s)
        args = tuple(self._num(a, ctx) for a in e.args)
        arity = {"floor": 1, "ceil": 1, "pow": 2, "mod": 2}.get(f)
        if (arity is not None and len(args) != arity) or (arity is None and len(args) < 2):
            want = f"{arity}" if arity else "at least 2"
            self.rep.error("E234", f"{f} takes {want} argument(s), not {len(args)}", s)
            return self._placeholder(s)
        if f in ("floor", "ceil"):
            t = Type.INT
        elif f == "mod":
            for a, ae in zip(args, e.args, strict=True):
                if a.type is not Type.INT:
                    self.rep.error("E234", "mod takes integers", ae.span)
            t = Type.INT
        else:
            t = Type.INT if all(a.type is Type.INT for a in args) else Type.DOUBLE
        return E.Call(f, args, t, s)

    # ---- actions --------------------------------------------------------------------
    def _action(self, d: ast.ActionDecl) -> ir.Action:
        modes = self._mode_set(d.modes, f"action {d.name.text}")
        guard = self._bool(d.guard, Ctx("a guard")) if d.guard else E.TRUE
        weight = (self._num(d.weight, Ctx("a weight", weights=True)) if d.weight
                  else E.Lit(1, Type.INT, None))
        outcomes = self._outcomes(d.body, f"action {d.name.text}")
        return ir.Action(d.name.text, modes, guard, weight, outcomes, d.span, d.name.span,
                         d.weight.span if d.weight else None, d.guard.span if d.guard else None)

    def _preemptive(self, d: ast.HazardDecl) -> ir.Action:
        modes = self._mode_set(d.modes, f"hazard {d.name.text}")
        cond = self._bool(d.trigger, Ctx("a hazard's condition"))
        weight = (self._num(d.weight, Ctx("a weight", weights=True)) if d.weight
                  else E.Lit(1, Type.INT, None))
        outcomes = self._outcomes(d.body, f"hazard {d.name.text}")
        return ir.Action(d.name.text, modes, cond, weight, outcomes, d.span, d.name.span,
                         d.weight.span if d.weight else None, d.trigger.span, kind="preemptive")

    def _hazard(self, d: ast.HazardDecl) -> ir.Hazard:
        modes = self._mode_set(d.modes, f"hazard {d.name.text}")
        prob = self._num(d.trigger, Ctx("a hazard's probability"))
        if d.weight is not None:
            self.rep.error("E235", "a probabilistic hazard has no weight: it can happen "
                           "during any action", d.weight.span)
        outcomes = self._outcomes(d.body, f"hazard {d.name.text}")
        return ir.Hazard(d.name.text, modes, prob, outcomes, d.span, d.name.span)

    def _outcomes(self, body: ast.Body, owner: str) -> tuple[ir.Outcome, ...]:
        out = []
        for o in body.outcomes:
            if o.prob is None:
                prob: E.Expr = E.Lit(1, Type.INT, None)
            else:
                prob = self._num(o.prob, Ctx("a probability"))
            out.append(ir.Outcome(prob, self._updates(o.updates), o.span))
        if not out:  # `{}`: stay where you are
            out.append(ir.Outcome(E.Lit(1, Type.INT, None), (), body.span))
        return tuple(out)

    def _updates(self, updates: tuple[ast.Update, ...]) -> tuple[ir.Update, ...]:
        out: list[ir.Update] = []
        seen: dict[str, Span] = {}

        def add(var: str, value: E.Expr, span: Span, display: str) -> None:
            if var in seen:
                self.rep.error("E236", f"'{display}' is assigned twice in one outcome", span,
                               related=[Related("first assigned here", seen[var])])
                return
            seen[var] = span
            out.append(ir.Update(var, value, span))

        uctx = Ctx("an update", intervals=True)
        for u in updates:
            if isinstance(u, ast.Goto):
                mode = self.modes.get(u.mode.text)
                if mode is None:
                    self.rep.error("E215", f"'{u.mode.text}' is not a mode", u.mode.span,
                                   hint=did_you_mean(u.mode.text, self.modes))
                    continue
                add("mode", E.ModeVal(mode.name, mode.number, u.mode.span), u.span, "mode")
                continue
            t = u.target
            if t.field is None and t.name.text in self.tuples:
                fields = self.tuples[t.name.text]
                if any(base == t.name.text for base, _ in self.dropped_fields):
                    continue  # its shape is unknown after an E201 on one of its fields
                if u.op != ":=":
                    self.rep.error("E237", f"'{u.op}' needs a number; '{t.name.text}' is a tuple",
                                   u.span)
                    continue
                values = self._tuple_value(u.value, fields, uctx)
                if values is None:
                    self.rep.error("E237", f"assign '{t.name.text}' a tuple of {len(fields)} values "
                                   f"or another tuple with fields {', '.join(fields)}", u.value.span)
                    continue
                for fname, v in zip(fields, values, strict=True):
                    self._add_assign(add, f"{t.name.text}_{fname}", f"{t.name.text}.{fname}", v,
                                     u.span, u.value.span)
                continue
            flat = t.name.text if t.field is None else f"{t.name.text}_{t.field.text}"
            if flat not in self.vars:
                kind = self.value_names.get(t.name.text, (None, None))[0]
                if kind is None or (t.field is not None and t.name.text not in self.tuples):
                    self._undefined(t.name, uctx)
                elif t.field is not None and (t.name.text, t.field.text) in self.dropped_fields:
                    pass
                elif t.field is not None:
                    self.rep.error("E223", f"'{t.name.text}' has no field '{t.field.text}'",
                                   t.field.span)
                elif kind != "variable":
                    self.rep.error("E238", f"'{t.text}' is {_a(kind)}; only variables can be assigned",
                                   t.span)
                continue
            var = self.vars[flat]
            if isinstance(u.value, ast.TupleLit):
                self.rep.error("E237", f"'{var.display}' is not a tuple", u.value.span)
                continue
            value = self._expr(u.value, uctx)
            if u.op != ":=":
                if var.type is not Type.INT:
                    self.rep.error("E237", f"'{u.op}' needs an integer; '{var.display}' is a bool",
                                   u.span)
                    continue
                value = E.Binary(u.op[0], E.VarRef(flat, Type.INT, t.span), value,
                                 value.type if value.type.numeric else Type.INT, u.span)
            self._add_assign(add, flat, var.display, value, u.span, u.value.span)
        return tuple(out)

    def _add_assign(self, add: Any, flat: str, display: str, value: E.Expr, span: Span,
                    vspan: Span) -> None:
        var = self.vars[flat]
        if var.type is Type.BOOL and value.type is not Type.BOOL:
            self.rep.error("E239", f"'{display}' is a bool; cannot assign {_a(value.type.value)}", vspan)
            return
        if var.type is Type.INT and value.type is Type.DOUBLE:
            self.rep.error("E239", f"'{display}' is an int; cannot assign a double", vspan,
                           hint="round it with floor(...) or ceil(...)")
            return
        if var.type is Type.INT and not value.type.numeric:
            self.rep.error("E239", f"'{display}' is an int; cannot assign {_a(value.type.value)}", vspan)
            return
        add(flat, value, span, display)

    def _tuple_value(self, value: ast.Expr | ast.TupleLit, fields: tuple[str, ...],
                     ctx: Ctx) -> list[E.Expr] | None:
        if isinstance(value, ast.TupleLit):
            if len(value.items) != len(fields):
                return None
            return [self._expr(v, ctx) for v in value.items]
        if isinstance(value, ast.Name) and self.tuples.get(value.name.text) == fields:
            src = value.name.text
            return [E.VarRef(f"{src}_{f}", self.vars[f"{src}_{f}"].type, value.span)
                    for f in fields if f"{src}_{f}" in self.vars]
        if len(fields) == 1 and not (isinstance(value, ast.Name) and value.name.text in
                                     self.tuples):
            return [self._expr(value, ctx)]  # one field: `p := 2`, `p := (2)`
        return None

    def _check_weight_cycles(self, actions: list[ir.Action]) -> None:
        deps = {a.name: {n.action for n in E.walk(a.weight) if isinstance(n, E.WeightRef)}
                for a in actions}
        spans = {a.name: a.weight_span or a.name_span for a in actions}
        state: dict[str, int] = {}

        def visit(n: str, path: list[str]) -> None:
            state[n] = 1
            for m in sorted(deps.get(n, ())):
                if state.get(m) == 1:
                    cycle = [*path[path.index(m):], m] if m in path else [n, m]
                    self.rep.error("E240", "weights refer to each other in a cycle: "
                                   + " -> ".join(f"w({x})" for x in cycle), spans[n])
                elif m not in state:
                    visit(m, [*path, m])
            state[n] = 2

        for a in actions:
            if a.name not in state:
                visit(a.name, [a.name])

    # ---- rewards and properties ----------------------------------------------------
    def _rewards(self, d: ast.RewardsDecl) -> ir.RewardStruct:
        items = []
        for it in d.items:
            if it.action is not None and it.action.text not in self.action_names:
                self.rep.error("E203", f"'{it.action.text}' is not an action", it.action.span,
                               hint=did_you_mean(it.action.text, self.action_names))
            elif it.action is not None and it.action.text in self.branch_hazards:
                self.rep.error("E248", f"an action reward cannot name the probabilistic hazard "
                               f"'{it.action.text}': it is a branch of every action of its "
                               "modes, and an action reward counts whole actions",
                               it.action.span, hint="reward the hazard's target mode with a state "
                               "reward, e.g. 'mode == Target : 1'")
            guard = self._bool(it.guard, Ctx("a reward's condition"))
            value = self._num(it.value, Ctx("a reward"))
            items.append(ir.RewardItem(it.action.text if it.action else None, guard, value, it.span))
        return ir.RewardStruct(d.name.text, tuple(items), d.span)

    def _check_query_names(self, props: list[ir.Property]) -> None:
        """An MDP asks `P=? [...]` of property `a` as the queries `a_min` and `a_max`: a
        property of that name would share its query, and one of the two values be wrong."""
        asked = {f"{p.name}_{o}": p for p in props if not p.opt for o in ("min", "max")}
        for p in props:
            if p.name in asked:
                other = asked[p.name]
                self.rep.error(
                    "E244", f"property {p.name} has the name of a query of property "
                    f"{other.name}: with interval constants afsmc asks {other.name} as "
                    f"{other.name}_min and {other.name}_max", p.span,
                    hint="rename one of them", related=[Related(f"property {other.name}",
                                                                other.span)])

    def _property(self, d: ast.PropertyDecl) -> ir.Property:
        ctx = Ctx("a property", labels=True)
        q = d.query

        def bound(b: ast.Expr | None) -> E.Expr | None:
            if b is None:
                return None
            x = self._expr(b, Ctx("a step bound", state=False))
            if x.type is not Type.INT:
                self.rep.error("E241", "a step bound must be an int", b.span)
                return x
            try:
                k = scalar(x, self._const_env())
            except (EvalError, ArithmeticError):
                return x  # reported where it is computed (E245)
            if isinstance(k, int) and k < 0:
                self.rep.error("E241", f"a step bound must be an int >= 0, not {k}", b.span,
                               hint="it counts steps; Storm refuses a negative one")
            return x

        if isinstance(q, ast.PQuery):
            p = q.path
            path: ir.Path | ir.RewardPath
            if isinstance(p, ast.Eventually):
                path = ir.Path("F", self._bool(p.target, ctx), bound=bound(p.bound))
            elif isinstance(p, ast.Globally):
                # Storm has no step-bounded G; afsmc.verify asks 1 - P[F<=k !phi] for it.
                path = ir.Path("G", self._bool(p.target, ctx), bound=bound(p.bound))
            elif isinstance(p, ast.Until):
                path = ir.Path("U", self._bool(p.right, ctx), self._bool(p.left, ctx), bound(p.bound))
            else:
                path = ir.Path("X", self._bool(p.target, ctx))
            opt = {"P": "", "Pmin": "min", "Pmax": "max"}[q.op]
            return ir.Property(d.name.text, "P", opt, path, None, d.span,  # type: ignore[arg-type]
                               *_written(q))
        rp = q.path
        if q.reward is None:
            if len(self.reward_names) != 1:
                self.rep.error("E242", "name the reward structure: R{\"name\"}=? [...]", q.span,
                               hint=("reward structures: " + ", ".join(self.reward_names))
                               if self.reward_names else "declare one with 'rewards NAME { ... }'")
            reward = next(iter(self.reward_names), None)
        else:
            reward = q.reward
            if reward not in self.reward_names:
                self.rep.error("E203", f"reward structure \"{reward}\" is not declared",
                               q.reward_span or q.span, hint=did_you_mean(reward, self.reward_names))
        if isinstance(rp, ast.ReachReward):
            path = ir.RewardPath("F", self._bool(rp.target, ctx))
        elif isinstance(rp, ast.CumulativeReward):
            path = ir.RewardPath("C", bound=bound(rp.bound))
        else:
            path = ir.RewardPath("I", bound=bound(rp.at))
            rs = self.reward_structs.get(reward or "")
            if rs is not None and not any(it.action is None for it in rs.items):
                # Every Storm engine refuses it ("a reward model that does not define any
                # state-rewards"), and the whole Storm run with it.
                self.rep.error(
                    "E247", f"R{{\"{rs.name}\"}}[I=k] is always 0: \"{rs.name}\" has no "
                    "state rewards, and an instantaneous reward counts only those", q.span,
                    hint=f"Storm refuses it; add a state reward ('condition : value;') to "
                    f"\"{rs.name}\", or ask R{{\"{rs.name}\"}}=? [ C<=k ] for the action "
                    "rewards of the first k steps",
                    related=[Related(f"reward structure \"{rs.name}\"", rs.span)])
        return ir.Property(d.name.text, "R", q.opt, path, reward, d.span, *_written(q))


def _written(q: ast.PQuery | ast.RQuery) -> tuple[str, tuple[int, int] | None]:
    """The query's text as written and where its step bound stands (ir.Property.text)."""
    text = q.span.source.text
    p = q.path
    if isinstance(p, ast.Next | ast.ReachReward):
        return flat_text(text, q.span.start, q.span.end)
    if isinstance(p, ast.Until):
        op = next((i for i, j in tokens(text, p.left.span.end, p.right.span.start)
                   if text[i:j] == "U"), None)
        after = p.right.span.start
    else:  # F, G, C, I: the path starts at its letter
        op = p.span.start
        after = p.target.span.start if isinstance(p, ast.Eventually | ast.Globally) \
            else q.span.end - 1  # the closing ']'
    if op is None:
        return flat_text(text, q.span.start, q.span.end)
    site_end = max((j for _, j in tokens(text, op + 1, after)), default=op + 1)
    return flat_text(text, q.span.start, q.span.end, (op + 1, site_end))


def _a(word: str) -> str:
    """'a bool', 'an int', 'an action'."""
    return ("an " if word[:1] in "aeiou" else "a ") + word


def _stem(path: str) -> str:
    import os
    base = os.path.basename(path)
    return safe_identifier(base.rsplit(".", 1)[0] or "machine")
