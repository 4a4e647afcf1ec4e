"""Parse tree -> AST: the lark Transformer that builds :mod:`afsmc.syntax.ast` nodes.

It also reports the few mistakes only visible once a rule is complete (E110 mode numbers,
E111 mixed bodies, E118 repeated mode attributes, E119 empty bodies), and a name, number or
label name longer than MAX_TOKEN_CHARS (E125) before any of them is converted.
"""

from __future__ import annotations

import inspect
from collections.abc import Callable
from functools import cache
from typing import Any, cast

from lark import Token, Transformer, Tree, v_args
from lark.visitors import _VArgsWrapper

from afsmc.diagnostics import BOM, Reporter, Source, Span, codes
from afsmc.syntax import ast
from afsmc.syntax.limits import MAX_TOKEN_CHARS, clip

# The tokens whose length the author chooses, and how E125 names them.
SIZED = {"NAME": "name", "NUMBER": "number", "ESCAPED_STRING": "label name"}


def span_of(source: Source, meta_or_tok: Any) -> Span:
    """The span of a token, or of a rule's meta (empty rules: the start of the file).
    Lines and columns are the lexer's (it counts lines at '\n' only, as Source does), so
    no search for them: only a byte-order mark, which Source leaves out of line 1's
    columns, moves them."""
    if not isinstance(meta_or_tok, Token) and getattr(meta_or_tok, "empty", True):
        return Span.at_offset(source, 0, 0)
    m = meta_or_tok
    start, end, line, col, end_line, end_col = (m.start_pos, m.end_pos, m.line, m.column,
                                                m.end_line, m.end_column)
    if start is None or end is None or line is None or end_line is None:
        return Span.at_offset(source, start or 0, end)
    if source.text.startswith(BOM):
        if line == 1 and start > 0:
            col -= 1
        if end_line == 1 and end > 0:
            end_col -= 1
    return Span(source, line, col, end_line, end_col, start, end)


def _span(source: Source, line: int, column: int, end_line: int, end_column: int,
          start: int, end: int) -> Span:
    """Span(source, line, column, end_line, end_column, start, end), without the frozen
    dataclass's __init__ (one object.__setattr__ per field: a parse makes a span for
    nearly every token)."""
    span: Span = object.__new__(Span)
    span.__dict__.update(source=source, line=line, column=column, end_line=end_line,
                         end_column=end_column, start=start, end=end)
    return span


# Where a node is: start offset, line, column, end offset, end line, end column (as lark's
# meta has them), and how deeply it nests (afsmc.syntax.drive counts it; 0 here).
Place = tuple[int, int, int, int, int, int, int]


def place(meta: Any) -> Place | None:
    """The place of a node of lark's tree (None for a rule that matched nothing)."""
    if meta is None or getattr(meta, "empty", True):
        return None
    return (meta.start_pos, meta.line, meta.column, meta.end_pos, meta.end_line,
            meta.end_column, 0)


@cache
def rule_methods(cls: type) -> dict[str, Callable[..., Any]]:
    """The rule methods of a Builder class by rule name, as plain functions of (self,
    meta, children)."""
    methods = {}
    for name in dir(cls):
        attr = inspect.getattr_static(cls, name)
        if isinstance(attr, _VArgsWrapper):
            methods[name] = attr.base_func
    return methods


@v_args(meta=True)
class Builder(Transformer[Token, Any]):
    """Builds AST nodes; children arrive already transformed."""

    def __init__(self, source: Source, reporter: Reporter):
        super().__init__()
        self.source = source
        self.reporter = reporter
        self.bom = source.text.startswith(BOM)

    def build(self, tree: Tree[Token]) -> Any:
        """What transform(tree) gives, children first and in order, in one frame per level
        rather than lark's three (a generator among them). Each method is given the node's
        place (see `place`) rather than lark's meta, as the parser's own loop gives it
        (afsmc.syntax.drive)."""
        methods = rule_methods(type(self))
        default_token = self.__default_token__

        def node(tree: Tree[Token]) -> Any:
            children = [node(c) if isinstance(c, Tree) else default_token(c)
                        if isinstance(c, Token) else c for c in tree.children]
            method = methods.get(tree.data)
            if method is None:
                return Tree(tree.data, children, tree.meta)  # as lark's __default__
            return method(self, place(tree.meta), children)

        return node(tree)

    def __default_token__(self, tok: Token) -> Token:
        """Each token, before the rule it is in is built: E125 for one too long to read
        (a number beyond it stands in as 0, so that nothing converts its digits)."""
        what = SIZED.get(tok.type)
        if what is None or len(tok) <= MAX_TOKEN_CHARS:
            return tok
        self.reporter.error(codes.E125, f"this {what} has {len(tok):,} characters; afsmc reads "
                            f"{what}s of up to {MAX_TOKEN_CHARS:,}", span_of(self.source, tok),
                            hint=f"shorten '{clip(str(tok))}'" if what != "number" else
                            "no 64-bit integer or double needs as many digits")
        return Token.new_borrow_pos(tok.type, "0", tok) if tok.type == "NUMBER" else tok

    def _s(self, place: Place | None) -> Span:
        """The span of a node at `place` (None: a rule that matched nothing, at the start
        of the file); columns as span_of gives them."""
        if place is None:
            return Span.at_offset(self.source, 0, 0)
        start, line, col, end, end_line, end_col, _ = place
        if self.bom:
            if line == 1 and start > 0:
                col -= 1
            if end_line == 1 and end > 0:
                end_col -= 1
        return _span(self.source, line, col, end_line, end_col, start, end)

    def _id(self, tok: Token) -> ast.Ident:
        t: Any = tok
        if self.bom or t.start_pos is None or t.end_pos is None:
            return ast.Ident(str(tok), span_of(self.source, tok))
        return ast.Ident(str(tok), _span(self.source, t.line, t.column, t.end_line,
                                         t.end_column, t.start_pos, t.end_pos))

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

    def data_source(self, meta: Any, c: list[Any]) -> ast.SimSource:
        """`from data "PATH" column NAME`: the path and a quoted column as written between
        their quotes (no escapes are read)."""
        path, column = c[0], c[1]
        policy = c[2] if len(c) > 2 else ()
        col = str(column)[1:-1] if column.type == "ESCAPED_STRING" else str(column)
        return ast.SimSource(ast.Ident(str(path)[1:-1], span_of(self.source, path)), policy,
                             self._s(meta), ast.Ident(col, span_of(self.source, column)))

    def sim_policy(self, meta: Any, c: list[Any]) -> tuple[tuple[ast.Ident, float], ...]:
        return tuple(c)

    def policy_item(self, meta: Any, c: list[Any]) -> tuple[ast.Ident, float]:
        return (self._id(c[0]), c[1])

    def signed_number(self, meta: Any, c: list[Token]) -> float:
        # The minus is an anonymous token; comments and line breaks may stand between it and
        # the number, so only the number's own text is converted.
        value = float(c[-1])
        return -value if self.source.text[meta[0]:meta[3]].startswith("-") else value

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
        writers = None
        for item in rest:
            if item == "clamp":
                clamp = True
            elif isinstance(item, tuple) and item and item[0] == "writers":
                writers = item[1]
            else:
                init = item
        return ast.VarDecl(self._id(name), vtype, init, clamp, self._s(meta), writers)

    def writers(self, meta: Any, c: list[Token]) -> tuple[str, tuple[ast.Ident, ...]]:
        return ("writers", tuple(self._id(t) for t in c))

    # -- composition
    def compose_decl(self, meta: Any, c: list[Any]) -> ast.ComposeDecl:
        words = dict(x for x in c[1:])
        return ast.ComposeDecl(self._id(c[0]), words.get("ties"), self._s(meta),
                               words.get("scheduler"))

    def scheduler(self, meta: Any, c: list[Token]) -> tuple[str, ast.Ident]:
        return ("scheduler", self._id(c[0]))

    def ties(self, meta: Any, c: list[Token]) -> tuple[str, ast.Ident]:
        return ("ties", self._id(c[0]))

    def agent_decl(self, meta: Any, c: list[Any]) -> ast.AgentDecl:
        params = None
        if len(c) > 1 and isinstance(c[1], tuple) and c[1] and c[1][0] == "params":
            params, c = c[1][1], [c[0], *c[2:]]
        clock = self._id(c[1]) if len(c) > 1 and isinstance(c[1], Token) else None
        decls = tuple(x for x in c[1:] if not isinstance(x, Token))
        return ast.AgentDecl(self._id(c[0]), clock, decls, self._s(meta), params)

    def agent_params(self, meta: Any, c: list[Token]) -> tuple[str, tuple[ast.Ident, ...]]:
        return ("params", tuple(self._id(t) for t in c))

    def agents_decl(self, meta: Any, c: list[ast.Instance]) -> ast.AgentsDecl:
        return ast.AgentsDecl(tuple(c), self._s(meta))

    def family_decl(self, meta: Any, c: list[Any]) -> ast.FamilyDecl:
        return ast.FamilyDecl(self._id(c[0]), c[1], c[2], self._id(c[3]), self._s(meta))

    def instance(self, meta: Any, c: list[Any]) -> ast.Instance:
        return ast.Instance(self._id(c[0]), self._id(c[1]), tuple(c[2:]), self._s(meta))

    def sync_action(self, meta: Any, c: list[Any]) -> ast.ActionDecl:
        a: ast.ActionDecl = c[0]
        return ast.ActionDecl(a.name, a.modes, a.guard, a.weight, a.body, self._s(meta), True)

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
                number_span = span_of(self.source, item)
                number = self._int(item)
            else:
                if item in attrs:
                    self.reporter.error(codes.E118, f"'{item!s}' is given twice for mode {name.text}",
                                        span_of(self.source, item),
                                        hint=f"write '{item!s}' once")
                attrs.append(item)
        return ast.ModeDecl(name, number, number_span, "initial" in attrs, "final" in attrs,
                            self._s(meta))

    def mode_attr(self, meta: Any, c: list[Token]) -> Token:
        return c[0]  # a Token (a str) keeps its position for E118

    def _int(self, tok: Token) -> int:
        text = str(tok)
        if not text.isdigit():
            self.reporter.error(codes.E110, f"a mode number must be a whole number, not {text}",
                                span_of(self.source, tok))
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
            self.reporter.error(codes.E119, "an empty body: say what the action does",
                                self._s(meta), hint="write '{ skip; }' for an action that "
                                "changes nothing")
        outcomes = [x for x in c if x.prob is not None]
        plain = [x for x in c if x.prob is None]
        if outcomes and plain:
            self.reporter.error(
                codes.E111, "a body has either outcomes 'p: updates;' or plain updates, not both",
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

    def agent_action_reward(self, meta: Any, c: list[Any]) -> ast.RewardItem:
        return ast.RewardItem(self._id(c[1]), c[2], c[3], self._s(meta), self._id(c[0]))

    def state_reward(self, meta: Any, c: list[Any]) -> ast.RewardItem:
        return ast.RewardItem(None, c[0], c[1], self._s(meta))

    def property_decl(self, meta: Any, c: list[Any]) -> ast.PropertyDecl:
        return ast.PropertyDecl(self._id(c[0]), c[1], self._s(meta))

    def p_op(self, meta: Any, c: list[Token]) -> str:
        return str(c[0])

    def minmax(self, meta: Any, c: list[Token]) -> str:
        return str(c[0])

    def threshold_op(self, meta: Any, c: list[Token]) -> str:
        return str(c[0])

    def threshold(self, meta: Any, c: list[Any]) -> ast.Threshold:
        return ast.Threshold(cast(Any, c[0]), c[1], self._s(meta))

    def p_query(self, meta: Any, c: list[Any]) -> ast.PQuery:
        limit = next((x for x in c if isinstance(x, ast.Threshold)), None)
        return ast.PQuery(c[0], c[-1], self._s(meta), limit)

    def r_query(self, meta: Any, c: list[Any]) -> ast.RQuery:
        reward = reward_span = None
        opt = ""
        limit = None
        for item in c[:-1]:
            if isinstance(item, Token):
                reward = str(item)[1:-1]
                reward_span = span_of(self.source, item)
            elif isinstance(item, ast.Threshold):
                limit = item
            else:
                opt = item
        return ast.RQuery(reward, reward_span, cast(Any, opt), c[-1], self._s(meta), limit)

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
        if len(c) == 2:  # `r1.mode in {...}`
            return ast.ModeIn(c[1], self._s(meta), self._id(c[0]))
        return ast.ModeIn(c[0], self._s(meta))

    def agent_mode_ref(self, meta: Any, c: list[Token]) -> ast.FieldRef:
        """`r1.mode`: "mode" is a keyword, so the field a name of its own, at the last
        four characters (the keyword's)."""
        span = self._s(meta)
        mode = Span.at_offset(self.source, span.end - 4, span.end)
        return ast.FieldRef(self._id(c[0]), ast.Ident("mode", mode), span)
