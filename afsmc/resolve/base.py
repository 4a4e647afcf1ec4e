"""The resolver's shared state, and what its concerns offer each other.

The resolver is one object built from mixins, one per concern (names, constants,
declarations, expressions, actions, properties), over `ResolverBase`. The base holds the
tables they fill and read, and declares the methods one concern calls in another: a
constant's value is an expression, an expression names a formula, a formula is an
expression, and so on. Each abstract method below is defined by the concern named above it.
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from collections.abc import Iterator, Mapping
from dataclasses import dataclass
from typing import Any

from afsmc.diagnostics import Diagnostic, Reporter, Span
from afsmc.model import expr as E
from afsmc.model import ir
from afsmc.model.expr import Type
from afsmc.syntax import ast
from afsmc.text import article


class _Values(Mapping[str, Any]):
    """The values of the constants declared so far, read through: a copy per constant
    would make a file of N constants cost N^2."""

    def __init__(self, consts: Mapping[str, ir.Constant]) -> None:
        self._consts = consts

    def __getitem__(self, name: str) -> Any:
        return self._consts[name].value

    def __iter__(self) -> Iterator[str]:
        return iter(self._consts)

    def __len__(self) -> int:
        return len(self._consts)


@dataclass(frozen=True)
class Ctx:
    """Where an expression stands decides what it may mention."""

    what: str  # for messages: "a guard", "a weight", ...
    state: bool = True  # variables and `mode`
    intervals: bool = False  # interval constants (only in updates)
    probabilities: bool = False  # interval probabilities (only in probabilities)
    weights: bool = False  # w(Action)
    labels: bool = False  # "label" (only in properties)
    constant_only: bool = False


CONST_CTX = Ctx("a constant", state=False, constant_only=True)


def a(word: str) -> str:
    """The word with its article: 'a bool', 'an int', 'an action'."""
    return f"{article(word)} {word}"


class ResolverBase(ABC):
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
        # A param with no value is a stand-in, not an E206 (see afsmc.resolve.resolve).
        self.open_params = open_params
        self.open_errors: dict[str, Diagnostic] = {}  # the E206 of each param it stood in for
        self.open_reads: dict[str, frozenset[str]] = {}  # constant -> open params it reads
        self.reading_open: set[str] = set()  # those of the declaration being resolved
        self.modes: dict[str, ir.Mode] = {}
        self._by_number: tuple[int, dict[int, ir.Mode]] = (0, {})  # (len(modes), by number)
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
        self._values: dict[int, tuple[E.Expr, Any]] = {}  # id -> (node, its value): folding

    def _placeholder(self, s: Span) -> E.Expr:
        """What an expression that was just reported stands for: no type error follows
        from it (a missing field in `F p.z` is E223, not also E222)."""
        x = E.Lit(0, Type.INT, s)
        self.placeholders[id(x)] = x
        return x

    def _const_env(self) -> Mapping[str, Any]:
        return _Values(self.consts)

    # ---- names (afsmc.resolve.names) -------------------------------------------------
    @abstractmethod
    def _undefined(self, name: ast.Ident, ctx: Ctx) -> None: ...

    @abstractmethod
    def _name(self, ident: ast.Ident, ctx: Ctx, s: Span) -> E.Expr: ...

    @abstractmethod
    def _field_ref(self, e: ast.FieldRef, ctx: Ctx) -> E.Expr: ...

    # ---- constants (afsmc.resolve.constants) -----------------------------------------
    @abstractmethod
    def _const_value(self, e: ast.Expr, want: Type) -> Any: ...

    # ---- declarations (afsmc.resolve.declarations) -----------------------------------
    @abstractmethod
    def _formula(self, name: str) -> ir.Formula | None: ...

    @abstractmethod
    def _mode_set(self, ms: ast.ModeSet, for_what: str) -> tuple[int, ...]: ...

    # ---- expressions (afsmc.resolve.expressions) -------------------------------------
    @abstractmethod
    def _expr(self, e: ast.Expr, ctx: Ctx) -> E.Expr: ...

    @abstractmethod
    def _bool(self, e: ast.Expr, ctx: Ctx) -> E.Expr: ...

    @abstractmethod
    def _num(self, e: ast.Expr, ctx: Ctx) -> E.Expr: ...
