"""What the state space is made of: modes and their numbers (E212-E216), variables and
tuples with their ranges and initial values (E217-E220, E249), and formulas (E221, E246).
"""

from __future__ import annotations

from afsmc.diagnostics import Related, Span, codes
from afsmc.model import expr as E
from afsmc.model import ir
from afsmc.model.expr import Type
from afsmc.model.limits import (
    BEYOND_STATE_INT,
    NUMBERS_HINT,
    STATE_INT,
    STATE_INT_HINT,
    unrepresentable,
)
from afsmc.model.names import did_you_mean
from afsmc.resolve.base import Ctx, ResolverBase
from afsmc.syntax import ast
from afsmc.syntax.limits import MAX_DEPTH, clip

# How deeply a formula may nest once the formulas it uses are inlined (E246): the checks
# and the JANI backend inline them, recursively (see afsmc.stack).
MAX_INLINED_DEPTH = 2 * MAX_DEPTH



def numbered(decls: list[ast.ModeDecl],
             used: dict[int, ast.ModeDecl]) -> list[tuple[ast.ModeDecl, int]]:
    """Each mode with its number: the number written, where `used` gives it to this mode;
    else the next number no mode uses, in order (`used` takes those in)."""
    out: list[tuple[ast.ModeDecl, int]] = []
    nxt = 0
    for d in decls:
        number = d.number
        if number is None or used.get(number) is not d:
            while nxt in used:
                nxt += 1
            number = nxt
            used[number] = d
        out.append((d, number))
    return out

class DeclarationsMixin(ResolverBase):
    # ---- modes -----------------------------------------------------------------------
    def _modes(self, decls: list[ast.ModeDecl]) -> None:
        used = self._mode_numbers(decls)
        declared = [d for d in decls
                    if self.value_names.get(d.name.text, ("", None))[1] == d.name.span]
        for d, number in numbered(declared, used):
            self.modes[d.name.text] = ir.Mode(d.name.text, number, d.initial, d.final, d.span)
        initial = [d for d in decls if d.initial]
        if not decls:
            self.rep.error(codes.E213, "the machine declares no modes", Span.whole_file(self.src),
                           hint="add e.g. 'mode Idle = 0 initial;'")
        elif not initial:
            self.rep.error(codes.E213, "no mode is marked initial", decls[0].span,
                           hint=f"write 'mode {decls[0].name.text}"
                           + (f" = {decls[0].number}" if decls[0].number is not None else "")
                           + " initial;'")
        elif len(initial) > 1:
            self.rep.error(codes.E214, "more than one mode is marked initial", initial[1].span,
                           related=[Related("also initial", initial[0].span)])

    def _mode_numbers(self, decls: list[ast.ModeDecl]) -> dict[int, ast.ModeDecl]:
        """The numbers written in the file, each kept by its first mode; a mode whose
        number is reported is numbered as if it had none."""
        used: dict[int, ast.ModeDecl] = {}
        for d in decls:
            if d.number is None:
                continue
            why = unrepresentable(d.number)
            if why is not None or not STATE_INT[0] <= d.number <= STATE_INT[1]:
                self.rep.error(
                    codes.E245 if why is not None else codes.E249, f"mode number {clip(str(d.number))} " + (
                        why or BEYOND_STATE_INT), d.number_span or d.span,
                    hint=NUMBERS_HINT if why is not None else "number the modes with "
                    "smaller numbers")
                continue
            if d.number in used:
                self.rep.error(codes.E212, f"mode number {d.number} is used twice",
                               d.number_span or d.span,
                               related=[Related(f"{used[d.number].name.text} has it",
                                                used[d.number].name.span)])
            else:
                used[d.number] = d
        return used

    def _mode_set(self, ms: ast.ModeSet, for_what: str) -> tuple[int, ...]:
        """The modes an action or hazard acts in: final modes cannot act (E216)."""
        if self._by_number[0] != len(self.modes):  # built again only when modes were added
            self._by_number = (len(self.modes), {m.number: m for m in self.modes.values()})
        by_number = self._by_number[1]
        chosen: set[int] = set()
        for item in ms.items:
            if isinstance(item, ast.ModeName):
                mode = self.modes.get(item.name.text)
                if mode is None:
                    self.rep.error(codes.E215, f"'{item.name.text}' is not a mode", item.span,
                                   hint=did_you_mean(item.name.text, self.modes))
                else:
                    chosen.add(mode.number)
            elif isinstance(item, ast.ModeNumber):
                if item.number not in by_number:
                    self.rep.error(codes.E215, f"no mode has number {item.number}", item.span)
                else:
                    chosen.add(item.number)
            else:
                hit = {n for n in by_number if item.lo <= n <= item.hi}
                if item.lo > item.hi or not hit:
                    self.rep.error(codes.E215, f"no mode has a number in {item.lo}..{item.hi}",
                                   item.span)
                chosen |= hit
        if ms.every:
            # `*` means every mode that can act: final modes are absorbing.
            everything = {m.number for m in self.modes.values() if not m.final}
            chosen = everything - chosen
            if not chosen:
                self.rep.warning(codes.W603, f"{for_what} can never fire: its mode set is empty "
                                 "('*' leaves out the final modes)", ms.span,
                                 hint="name the modes it acts in, or remove it")
        else:
            for n in sorted(chosen):
                if by_number[n].final:
                    self.rep.error(codes.E216, f"mode {by_number[n].name} is final: {for_what} "
                                   "cannot act in it", ms.span,
                                   hint="final modes are absorbing; remove it from the set")
        return tuple(sorted(chosen))

    # ---- variables -------------------------------------------------------------------
    def _variable(self, d: ast.VarDecl) -> None:
        if self.value_names.get(d.name.text, ("", None))[1] != d.name.span:
            return
        if isinstance(d.type, ast.TupleType):
            self._tuple_variable(d, d.type)
            return
        if isinstance(d.init, ast.TupleLit):
            self.rep.error(codes.E217, f"'{d.name.text}' is not a tuple", d.init.span)
            init = None
        else:
            init = d.init
        self._one_var(d.name.text, d.name.text, d.type, init, d.clamp, d.span)

    def _tuple_variable(self, d: ast.VarDecl, tt: ast.TupleType) -> None:
        """`var pos : (x : [0..9], y : [0..9])`: one variable `pos_x`, `pos_y` per field."""
        inits: list[ast.Expr | None]
        if d.init is None:
            inits = [None] * len(tt.fields)
        elif isinstance(d.init, ast.TupleLit) and len(d.init.items) == len(tt.fields):
            inits = list(d.init.items)
        elif len(tt.fields) == 1 and not isinstance(d.init, ast.TupleLit):
            inits = [d.init]  # `(1)` is the number 1: one field takes a plain value
        else:
            self.rep.error(codes.E217, f"'{d.name.text}' has {len(tt.fields)} fields; "
                           "give one initial value per field", d.init.span)
            inits = [None] * len(tt.fields)
        names = []
        for f, init in zip(tt.fields, inits, strict=True):
            flat = f"{d.name.text}_{f.name.text}"
            if flat in self.value_names:
                self.rep.error(codes.E201, f"field {d.name.text}.{f.name.text} would be named "
                               f"'{flat}' in PRISM, which is already declared", f.span,
                               hint=f"rename the field or the other '{flat}'",
                               related=[Related(f"'{flat}' is declared here",
                                                self.value_names[flat][1])])
                self.dropped_fields.add((d.name.text, f.name.text))
                continue
            if f.name.text in names:
                self.rep.error(codes.E201, f"field '{f.name.text}' is declared twice", f.span)
                continue
            names.append(f.name.text)
            self._one_var(flat, f"{d.name.text}.{f.name.text}", f.type, init, d.clamp, f.span)
        self.tuples[d.name.text] = tuple(names)

    def _one_var(self, flat: str, display: str, t: ast.RangeType | ast.BoolType,
                 init: ast.Expr | None, clamp: bool, span: Span) -> None:
        if isinstance(t, ast.BoolType):
            if clamp:
                self.rep.error(codes.E218, f"'{display}' is a bool; only integers can clamp", span)
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
            self.rep.error(codes.E219, f"range [{lo}..{hi}] of '{display}' is empty", t.span)
            hi, broken = lo, True
        if broken:
            init = None
        if not (STATE_INT[0] <= lo and hi <= STATE_INT[1]):
            self.rep.error(codes.E249, f"range [{lo}..{hi}] of '{display}' {BEYOND_STATE_INT}",
                           t.span, hint=STATE_INT_HINT)
            # go on with a range Storm holds, and no second error about the initial value
            lo, hi = (min(max(v, STATE_INT[0]), STATE_INT[1]) for v in (lo, hi))
            init = None
        iv = lo if init is None else self._const_value(init, Type.INT)
        if not isinstance(iv, int) or not lo <= iv <= hi:
            self.rep.error(codes.E220, f"initial value {iv} of '{display}' is outside [{lo}..{hi}]",
                           init.span if init is not None else span)
            iv = lo
        self.vars[flat] = ir.Variable(flat, display, Type.INT, lo, hi, iv, clamp, span)

    # ---- formulas --------------------------------------------------------------------
    def _formula(self, name: str) -> ir.Formula | None:
        """The formula, resolved on first use (a formula may use one declared after it)."""
        if name in self.formulas:
            return self.formulas[name]
        d = self.formula_decls[name]
        if name in self.formula_stack:
            self.rep.error(codes.E221, f"formula '{name}' refers to itself",
                           d.name.span, hint=" -> ".join([*self.formula_stack, name]))
            return None
        self.formula_stack.append(name)
        value = self._expr(d.value, Ctx("a formula"))
        self.formula_stack.pop()
        depth = E.depth(value, lambda n: self.formula_depth.get(n, 1))
        self.formula_depth[name] = depth
        if depth > MAX_INLINED_DEPTH:
            self.rep.error(codes.E246, f"formula '{name}' nests {depth} levels deep once the "
                           f"formulas it uses are inlined; afsmc supports {MAX_INLINED_DEPTH}",
                           d.name.span, hint="shorten it or the formulas it uses (each "
                           "operator of a chain like 'a + b + c' is one level)")
            if value.type.numeric or value.type is Type.BOOL:  # no more inlining of it
                value = E.Lit(False if value.type is Type.BOOL else 0, value.type, d.value.span)
        f = ir.Formula(name, value, d.span)
        self.formulas[name] = f
        return f
