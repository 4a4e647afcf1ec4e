"""The canonical layout of an .afsm file (`afsmc fmt`, and formatting in the language server).

The layout is printed from the AST, so it is the same whatever spacing the author used:
one declaration per line, blocks indented by four spaces, single spaces around binary
operators, at most one blank line kept where the author left one. Parentheses the
author wrote are kept (they are often there for the reader), every pair of them, also
inside a literal the parser folded a minus into (`-(-1.5)`); none are added or dropped.
Two minus signs are printed apart (`- -a`): `--` would read as a decrement.

Comments are not in the AST (the grammar ignores them), so they are found by lexing the
text again with the grammar's own terminals and placed back by position (fmt_layout): a
comment at the end of a line stays at the end of that line (aligned with its neighbours),
a comment on its own line stays before what follows it, and a comment in the middle of a
statement moves onto its own line just before that statement.

Safety net: the result is parsed again and must give the same AST (spans aside) and the
same comments; otherwise the file is reported, not rewritten.
"""

from __future__ import annotations

import bisect
import dataclasses
import re
from functools import cache
from typing import Any

import lark
from lark.exceptions import LarkError

from afsmc.diagnostics import BOM, CompileError, Diagnostic, Severity, Source, Span, codes
from afsmc.syntax import ast
from afsmc.syntax.fmt_layout import INDENT, Unit, lay_out
from afsmc.syntax.grammar import grammar_text
from afsmc.syntax.limits import MAX_SOURCE_CHARS
from afsmc.syntax.parser import parse

WIDTH = 100

# Binding strength, as in the grammar: larger binds tighter.
_ITE, _IMPLIES, _OR, _AND, _NOT, _CMP, _SUM, _PRODUCT, _NEG, _ATOM = range(1, 11)
_BINARY = {"=>": _IMPLIES, "||": _OR, "&&": _AND, "+": _SUM, "-": _SUM, "*": _PRODUCT,
           "/": _PRODUCT, "==": _CMP, "!=": _CMP, "<": _CMP, "<=": _CMP, ">": _CMP, ">=": _CMP}


@cache
def _lexer() -> lark.Lark:
    # The grammar's own terminals (COMMENT, ESCAPED_STRING, ...), lexed without parsing.
    return lark.Lark(grammar_text(), parser="lalr", lexer="basic")


def tokens(text: str) -> list[lark.Token]:
    """Every token of `text` but whitespace, comments included (raises LarkError)."""
    return [t for t in _lexer().lex(text, dont_ignore=True) if t.type != "WS"]


def format_text(text: str, path: str = "<input>") -> str:
    """The canonical layout of `text`. Raises CompileError if it does not parse."""
    if text.startswith(BOM):  # kept, and left out of the layout
        return BOM + format_text(text[1:], path)
    module = parse(text, path)
    try:
        toks = tokens(text)
    except LarkError:  # the parser accepted it, so this would be a lexer disagreement
        raise CompileError([_internal(path, "cannot find the comments of this file")]) from None
    out = _Formatter(text, module, toks).run()
    if len(out) > MAX_SOURCE_CHARS:
        raise CompileError([_too_large(text, out, path)])
    _verify(text, out, module, toks, path)
    return out


def _too_large(text: str, out: str, path: str) -> Diagnostic:
    """E004 for a layout longer than afsmc reads: one declaration a line and bodies on
    lines of their own add a few per cent to a dense file, and a file written past the
    limit could no longer be checked (its parse would refuse it: the formatter reported
    that as its own fault, E190)."""
    return Diagnostic(
        codes.E004, Severity.ERROR, f"{path}: formatted, the text would have {len(out):,} "
        f"characters, more than the {MAX_SOURCE_CHARS:,} afsmc reads; the file is left "
        "unchanged", Span.at_offset(Source(path, text), 0, 0),
        hint="split the model, or generate it in afsmc's layout (`afsmc fmt` of a smaller "
        "part shows it)")


def _internal(path: str, why: str) -> Diagnostic:
    return Diagnostic(codes.E190, Severity.ERROR, f"{path}: the formatter {why}; the file is left "
                      "unchanged", None, hint="please report this with the file")


def _verify(text: str, out: str, module: ast.Module, toks: list[lark.Token], path: str) -> None:
    try:
        again = parse(out, path)
        comments_after = [_comment_key(t) for t in tokens(out) if t.type == "COMMENT"]
    except (CompileError, LarkError):
        raise CompileError([_internal(path, "produced text that does not parse")]) from None
    if _shape(again) != _shape(module):
        raise CompileError([_internal(path, "would change the meaning of this file")])
    if comments_after != [_comment_key(t) for t in toks if t.type == "COMMENT"]:
        raise CompileError([_internal(path, "would lose or reorder a comment")])


def _comment_key(t: lark.Token) -> str:
    # The layout drops trailing blanks on every line, inside a `/* ... */` too.
    return "\n".join(line.rstrip() for line in str(t).split("\n")).rstrip()


def _shape(node: Any) -> Any:
    """The AST without positions, for comparing meaning."""
    if isinstance(node, ast.Ident):
        return node.text
    if dataclasses.is_dataclass(node) and not isinstance(node, type):
        return (type(node).__name__, *(
            _shape(getattr(node, f.name)) for f in dataclasses.fields(node)
            if not isinstance(getattr(node, f.name), Span)))
    if isinstance(node, tuple):
        return tuple(_shape(x) for x in node)
    return node


# ---- the AST printed as layout units ---------------------------------------------


class _Formatter:
    """Prints a module's declarations and statements as layout units (fmt_layout.Unit)."""

    def __init__(self, text: str, module: ast.Module, toks: list[lark.Token]):
        self.text = text
        self.module = module
        self.toks = toks
        self.code = [t for t in toks if t.type != "COMMENT"]
        self.code_starts = [t.start_pos or 0 for t in self.code]
        # Parenthesis depth before each code token, and a sparse table of its range minima:
        # whether an expression's tokens are balanced is then O(1), not a scan per node
        # (quadratic on deeply nested expressions).
        depth = [0]
        for t in self.code:
            depth.append(depth[-1] + {"LPAR": 1, "RPAR": -1}.get(t.type, 0))
        self.depth = depth
        self.minima = [depth]
        k = 1
        while 2 * k <= len(depth):
            last = self.minima[-1]
            self.minima.append([min(last[a], last[a + k]) for a in range(len(depth) - 2 * k + 1)])
            k *= 2

    def _min_depth(self, lo: int, hi: int) -> int:
        """The least depth over depth[lo..hi] (inclusive)."""
        level = (hi - lo + 1).bit_length() - 1
        row = self.minima[level]
        return min(row[lo], row[hi - (1 << level) + 1])

    # -- tokens
    def _index_at(self, offset: int) -> int:
        """Index of the first code token starting at or after `offset`."""
        return bisect.bisect_left(self.code_starts, offset)

    def _next(self, offset: int, kind: str) -> lark.Token:
        # (by index: a slice would copy the rest of the tokens at every call, N^2 in all)
        for k in range(self._index_at(offset), len(self.code)):
            if self.code[k].type == kind:
                return self.code[k]
        raise CompileError([_internal(self.module.span.source.path, f"found no {kind}")])

    def _wraps(self, span: Span) -> int:
        """How many pairs of parentheses the author put around this expression (`((a))`: 2);
        the parentheses of a call are not the expression's."""
        i = self._index_at(span.start)
        j = self._index_at(span.end)  # the first token after the expression
        # `(a) + (b)` dips below its start: the parentheses around it are not one pair
        if self.depth[j] != self.depth[i] or (j > i and self._min_depth(i, j) < self.depth[i]):
            return 0
        n = 0
        while (i - n >= 1 and j + n < len(self.code) and self.code[i - n - 1].type == "LPAR"
               and self.code[j + n].type == "RPAR"):
            if i - n >= 2 and self.code[i - n - 2].type in ("NAME", "MIN", "MAX"):
                break  # the parentheses of a call
            n += 1
        return n

    def _wrapped(self, span: Span) -> bool:
        """Did the author put this expression in its own parentheses?"""
        return self._wraps(span) > 0

    def _src(self, span: Span) -> str:
        return self.text[span.start:span.end]

    # -- expressions
    def expr(self, e: ast.Expr, ctx: int = 0) -> str:
        """`e` with every pair of parentheses the author put around it, and one pair where
        the context needs it and the author wrote none."""
        text, prec = self._core(e)
        n = self._wraps(e.span)
        if n == 0 and prec < ctx:
            n = 1
        return "(" * n + text + ")" * n

    def _number(self, e: ast.Num) -> str:
        """A literal as written. The parser folds a minus into the literal (`-(-1.5)` is the
        literal -(-1.5), text "--1.5"), so a folded one is printed from its tokens, keeping its
        parentheses, and with a space between two minus signs (never `--1.5`)."""
        i, j = self._index_at(e.span.start), self._index_at(e.span.end)
        if j - i <= 1:
            return e.text
        out = ""
        for t in self.code[i:j]:
            out += (" " if out.endswith("-") and str(t) == "-" else "") + str(t)
        return out

    def _core(self, e: ast.Expr) -> tuple[str, int]:
        if isinstance(e, ast.Num):
            return self._number(e), _NEG if e.text.startswith("-") else _ATOM
        if isinstance(e, ast.BoolLit):
            return ("true" if e.value else "false"), _ATOM
        if isinstance(e, ast.Name):
            return e.name.text, _ATOM
        if isinstance(e, ast.FieldRef):
            return f"{e.base.text}.{e.field.text}", _ATOM
        if isinstance(e, ast.ModeRef):
            return "mode", _ATOM
        if isinstance(e, ast.LabelRef):
            return f'"{e.name}"', _ATOM
        if isinstance(e, ast.Call):
            return f"{e.func.text}({', '.join(self.expr(a) for a in e.args)})", _ATOM
        if isinstance(e, ast.Unary):
            if e.op == "!":
                return "!" + self.expr(e.operand, _NOT), _NOT
            operand = self.expr(e.operand, _NEG)
            return ("- " if operand.startswith("-") else "-") + operand, _NEG  # not `--a`
        if isinstance(e, ast.Binary):
            p = _BINARY[e.op]
            if e.op == "=>":  # right-associative
                left, right = self.expr(e.left, p + 1), self.expr(e.right, p)
            elif p == _CMP:  # not associative
                left, right = self.expr(e.left, p + 1), self.expr(e.right, p + 1)
            else:
                left, right = self.expr(e.left, p), self.expr(e.right, p + 1)
            return f"{left} {e.op} {right}", p
        if isinstance(e, ast.Ite):
            return (f"{self.expr(e.cond, _IMPLIES)} ? {self.expr(e.then)} : "
                    f"{self.expr(e.other)}"), _ITE
        if isinstance(e, ast.ModeIn):
            agent = f"{e.agent.text}." if e.agent is not None else ""
            return f"{agent}mode in " + self.mode_set(e.modes), _CMP
        raise TypeError(type(e).__name__)

    def bound(self, e: ast.Expr) -> str:
        """A step bound: a number or a name as it is, anything else in parentheses (the
        grammar's), with any further pairs the author wrote."""
        n = self._wraps(e.span)
        if n == 0 and not isinstance(e, (ast.Num, ast.Name)):
            n = 1
        return "(" * n + self._core(e)[0] + ")" * n

    def mode_set(self, ms: ast.ModeSet) -> str:
        items = ", ".join(self._mode_item(i) for i in ms.items)
        if ms.every:
            return f"* except {{{items}}}" if ms.items else "*"
        if self.text[ms.span.start:ms.span.start + 1] == "{" or len(ms.items) != 1:
            return f"{{{items}}}"
        return items

    @staticmethod
    def _mode_item(item: ast.ModeItem) -> str:
        if isinstance(item, ast.ModeName):
            return item.name.text
        if isinstance(item, ast.ModeNumber):
            return str(item.number)
        return f"{item.lo}..{item.hi}"

    def value(self, v: ast.Expr | ast.TupleLit) -> str:
        if isinstance(v, ast.TupleLit):
            return "(" + ", ".join(self.expr(x) for x in v.items) + ")"
        return self.expr(v)

    def update(self, u: ast.Update) -> str:
        if isinstance(u, ast.Goto):
            return f"goto {u.mode.text}"
        return f"{u.target.text} {u.op} {self.value(u.value)}"

    # -- declarations
    def simple(self, d: Any) -> list[str]:
        """The declaration as columns (joined by spaces; neighbours align them)."""
        if isinstance(d, ast.MachineDecl):
            return [f"machine {d.name.text};"]
        if isinstance(d, ast.ConstDecl):
            if isinstance(d.value, ast.Interval):
                value = f"= [{self.expr(d.value.lo)}, {self.expr(d.value.hi)}]"
            else:
                value = "= " + self.expr(d.value)
            head = f"const {d.type} {d.name.text}"
            if d.source is None:
                return [head, value + ";"]
            src = f"from sim {d.source.ref.text}" if d.source.column is None else \
                f'from data "{d.source.ref.text}" column {_column(d.source.column.text)}'
            if d.source.policy:
                src += " with " + ", ".join(f"{name.text} = {self._signed_after(name.span.end)}"
                                            for name, _ in d.source.policy)
            return [head, value, src + ";"]
        if isinstance(d, ast.ParamDecl):
            head = f"param {d.type} {d.name.text}"
            return [head + ";"] if d.default is None else [head, f"= {self.expr(d.default)};"]
        if isinstance(d, ast.VarDecl):
            text = f": {self.var_type(d.type)}"
            if d.init is not None:
                text += f" init {self.value(d.init)}"
            text += " clamp" if d.clamp else ""
            if d.writers is not None:
                text += " written by " + ", ".join(w.text for w in d.writers)
            return [f"var {d.name.text}", text + ";"]
        if isinstance(d, ast.ComposeDecl):
            ties = f" ties {d.ties.text}" if d.ties is not None else ""
            how = f" {d.scheduler.text}" if d.scheduler is not None else ""
            return [f"compose {d.kind.text}{how}{ties};"]
        if isinstance(d, ast.ModeDecl):
            attrs = " initial" * d.initial + " final" * d.final + ";"
            if d.number_span is None:
                return [f"mode {d.name.text}{attrs}"]
            return [f"mode {d.name.text}", f"= {self._src(d.number_span)}{attrs}"]
        if isinstance(d, ast.FormulaDecl):
            return [f"formula {d.name.text}", f"= {self.expr(d.value)};"]
        if isinstance(d, ast.LabelDecl):
            return [f"label {d.name.text}", f"= {self.expr(d.value)};"]
        if isinstance(d, ast.PropertyDecl):
            return [f"property {d.name.text}", f"= {self.query(d.query)};"]
        raise TypeError(type(d).__name__)

    def _signed_after(self, offset: int) -> str:
        i = self._index_at(offset)
        out = ""
        for k in range(i + 1, len(self.code)):  # skip '='
            t = self.code[k]
            out += str(t)
            if t.type == "NUMBER":
                break
        return out

    def var_type(self, t: ast.RangeType | ast.BoolType | ast.TupleType) -> str:
        if isinstance(t, ast.BoolType):
            return "bool"
        if isinstance(t, ast.RangeType):
            return f"[{self.expr(t.lo)}..{self.expr(t.hi)}]"
        return "(" + ", ".join(f"{f.name.text}: {self.var_type(f.type)}" for f in t.fields) + ")"

    def query(self, q: ast.PQuery | ast.RQuery) -> str:
        asks = "=?" if q.threshold is None else q.threshold.op + self.bound(q.threshold.value)
        if isinstance(q, ast.PQuery):
            return f"{q.op}{asks} [ {self.path(q.path)} ]"
        head = "R"
        if q.reward_span is not None:
            head += "{" + self._src(q.reward_span) + "}"
        return f"{head}{q.opt}{asks} [ {self.path(q.path)} ]"

    def path(self, p: Any) -> str:
        def b(x: ast.Expr | None) -> str:
            return "" if x is None else "<=" + self.bound(x)

        if isinstance(p, ast.Eventually):
            return f"F{b(p.bound)} {self.expr(p.target)}"
        if isinstance(p, ast.Globally):
            return f"G{b(p.bound)} {self.expr(p.target)}"
        if isinstance(p, ast.Until):
            return f"{self.expr(p.left)} U{b(p.bound)} {self.expr(p.right)}"
        if isinstance(p, ast.Next):
            return f"X {self.expr(p.target)}"
        if isinstance(p, ast.ReachReward):
            return f"F {self.expr(p.target)}"
        if isinstance(p, ast.CumulativeReward):
            return f"C{b(p.bound)}"
        if isinstance(p, ast.InstantReward):
            return f"I={self.bound(p.at)}"
        raise TypeError(type(p).__name__)

    # -- blocks
    def header(self, d: ast.ActionDecl | ast.HazardDecl, depth: int) -> list[str]:
        pad = INDENT * depth
        if isinstance(d, ast.ActionDecl):
            base = ("sync " if d.sync else "") + f"action {d.name.text} in {self.mode_set(d.modes)}"
            extras = []
            if d.guard is not None:
                extras.append(f"when {self.expr(d.guard)}")
        else:
            base = f"hazard {d.name.text} from {self.mode_set(d.modes)}"
            trigger = "with probability" if d.kind == "probabilistic" else "when"
            extras = [f"{trigger} {self.expr(d.trigger)}"]
        if d.weight is not None:
            extras.append(f"weight {self.expr(d.weight)}")
        one = " ".join([pad + base, *extras, "{"])
        if len(one) <= WIDTH:
            return [one]
        lines = [pad + base] + [pad + INDENT + x for x in extras]
        lines[-1] += " {"
        return lines

    def fill(self, prefix: str, parts: list[str], depth: int) -> list[str]:
        """`prefix` then `parts` joined by ', ' and a ';', wrapped at commas past WIDTH."""
        first = INDENT * depth + prefix
        if not parts:
            return [first + "skip;"]
        one = first + ", ".join(parts) + ";"
        if len(one) <= WIDTH:
            return [one]
        cont = " " * len(first)
        lines, cur = [], first + parts[0]
        for p in parts[1:]:
            if len(cur) + 2 + len(p) + 1 > WIDTH:
                lines.append(cur + ",")
                cur = cont + p
            else:
                cur += ", " + p
        return [*lines, cur + ";"]

    def body_units(self, body: ast.Body, depth: int) -> list[Unit]:
        units = []
        # the updates of a body's outcomes start in one column
        width = max((len(self.expr(o.prob)) + 1 for o in body.outcomes if o.prob is not None),
                    default=0)
        for o in body.outcomes:
            if o.prob is not None:
                prefix = f"{self.expr(o.prob)}:".ljust(width) + " "
                lines = self.fill(prefix, [self.update(u) for u in o.updates], depth)
                units.append(Unit(o.span.start, o.span.end, depth, lines))
                continue
            # A plain body: the parser merged its statements; keep the author's grouping.
            groups: list[list[ast.Update]] = []
            for u in o.updates:
                if groups and (self._next(groups[-1][-1].span.end, "SEMICOLON").start_pos
                               or 0) > u.span.start:
                    groups[-1].append(u)
                else:
                    groups.append([u])
            if not groups:  # `skip;`
                skip = self._next(body.span.start, "SKIP")
                end = self._next(skip.end_pos or 0, "SEMICOLON").end_pos or 0
                units.append(Unit(skip.start_pos or 0, end, depth, [INDENT * depth + "skip;"]))
            for g in groups:
                end = self._next(g[-1].span.end, "SEMICOLON").end_pos or g[-1].span.end
                units.append(Unit(g[0].span.start, end, depth,
                                  self.fill("", [self.update(u) for u in g], depth)))
        return units

    def units(self) -> list[Unit]:
        out: list[Unit] = []
        m = self.module
        if m.machine is not None:
            out.append(Unit(m.machine.span.start, m.machine.span.end, 0,
                            [" ".join(self.simple(m.machine))]))
        for d in m.decls:
            out.extend(self.decl_units(d, 0))
        return out

    def decl_units(self, d: ast.Decl, depth: int) -> list[Unit]:
        out: list[Unit] = []
        pad = INDENT * depth
        if isinstance(d, (ast.ActionDecl, ast.HazardDecl)):
            out.append(Unit(d.span.start, d.body.span.start + 1, depth, self.header(d, depth),
                            "open"))
            out.extend(self.body_units(d.body, depth + 1))
            out.append(Unit(d.span.end - 1, d.span.end, depth, [pad + "}"], "close"))
        elif isinstance(d, ast.AgentDecl):
            brace = self._next((d.clock or d.name).span.end, "LBRACE")
            clock = f" clock {d.clock.text}" if d.clock is not None else ""
            params = "" if d.params is None else f"({', '.join(p.text for p in d.params)})"
            out.append(Unit(d.span.start, brace.end_pos or 0, depth,
                            [f"{pad}agent {d.name.text}{params}{clock} {{"], "open"))
            for x in d.decls:
                out.extend(self.decl_units(x, depth + 1))
            out.append(Unit(d.span.end - 1, d.span.end, depth, [pad + "}"], "close"))
        elif isinstance(d, ast.FamilyDecl):
            out.append(Unit(d.span.start, d.span.end, depth, [
                f"{pad}agent {d.name.text}[{self.expr(d.lo)}..{self.expr(d.hi)}] : "
                f"{d.template.text};"]))
        elif isinstance(d, ast.AgentsDecl):
            parts = [f"{i.name.text} = {i.template.text}({', '.join(self.expr(a) for a in i.args)})"
                     for i in d.instances]
            out.append(Unit(d.span.start, d.span.end, depth, self.fill("agents ", parts, depth)))
        elif isinstance(d, ast.RewardsDecl):
            brace = self._next(d.name.span.end, "LBRACE")
            out.append(Unit(d.span.start, brace.end_pos or 0, depth,
                            [f"{pad}rewards {d.name.text} {{"], "open"))
            for item in d.items:
                head = f"[{item.action.text}] " if item.action is not None else ""
                if item.agent is not None and item.action is not None:
                    head = f"[{item.agent.text}.{item.action.text}] "
                out.append(Unit(item.span.start, item.span.end, depth + 1, [
                    f"{pad}{INDENT}{head}{self.expr(item.guard)} : {self.expr(item.value)};"]))
            out.append(Unit(d.span.end - 1, d.span.end, depth, [pad + "}"], "close"))
        else:
            cols = self.simple(d)
            cols[0] = pad + cols[0]
            out.append(Unit(d.span.start, d.span.end, depth, [" ".join(cols)], cols=cols,
                            group=type(d).__name__))
        return out

    def run(self) -> str:
        """The formatted text: the units laid out with the file's comments."""
        return lay_out(self.text, self.toks, self.units())


def line_ending(raw: str) -> str:
    """A text's line ending: the one most of its lines end with (CRLF, CR or LF)."""
    crlf = raw.count("\r\n")
    counts = {"\r\n": crlf, "\r": raw.count("\r") - crlf, "\n": raw.count("\n") - crlf}
    return max(("\n", "\r\n", "\r"), key=lambda e: counts[e])  # ties: LF first


def _column(name: str) -> str:
    """A data column as written: bare if it is a name, else quoted."""
    return name if re.fullmatch(r"[A-Za-z_][A-Za-z0-9_]*", name) else f'"{name}"'
