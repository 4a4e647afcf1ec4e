"""The abstract syntax tree of an .afsm file: exactly what was written, with spans.

Nothing here is resolved or checked; :mod:`afsmc.resolve` turns it into the typed IR.
The formatter and the language server work on this tree, so it keeps every construct
the author wrote (e.g. `mode in {...}` and `+=` stay as written).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal, Union

from afsmc.diagnostics import Span


@dataclass(frozen=True)
class Ident:
    text: str
    span: Span


# ---- expressions -------------------------------------------------------------


@dataclass(frozen=True)
class Num:
    value: int | float
    text: str
    span: Span


@dataclass(frozen=True)
class BoolLit:
    value: bool
    span: Span


@dataclass(frozen=True)
class Name:
    name: Ident
    span: Span


@dataclass(frozen=True)
class FieldRef:
    base: Ident
    field: Ident
    span: Span


@dataclass(frozen=True)
class ModeRef:
    """The keyword `mode`: the machine's current mode."""

    span: Span


@dataclass(frozen=True)
class LabelRef:
    """`"success"`: a label, as PRISM writes it in properties."""

    name: str
    span: Span


@dataclass(frozen=True)
class Call:
    func: Ident
    args: tuple[Expr, ...]
    span: Span


@dataclass(frozen=True)
class Unary:
    op: Literal["-", "!"]
    operand: Expr
    span: Span


BinOp = Literal["+", "-", "*", "/", "==", "!=", "<", "<=", ">", ">=", "&&", "||", "=>"]


@dataclass(frozen=True)
class Binary:
    op: BinOp
    left: Expr
    right: Expr
    span: Span


@dataclass(frozen=True)
class Ite:
    cond: Expr
    then: Expr
    other: Expr
    span: Span


@dataclass(frozen=True)
class ModeIn:
    modes: ModeSet
    span: Span
    agent: Ident | None = None  # `r1.mode in {...}`: that agent's mode (a composed mission)


Expr = Union[Num, BoolLit, Name, FieldRef, ModeRef, LabelRef, Call, Unary, Binary, Ite, ModeIn]


@dataclass(frozen=True)
class TupleLit:
    items: tuple[Expr, ...]
    span: Span


# ---- mode sets -------------------------------------------------------------------


@dataclass(frozen=True)
class ModeName:
    name: Ident
    span: Span


@dataclass(frozen=True)
class ModeNumber:
    number: int
    span: Span


@dataclass(frozen=True)
class ModeRange:
    lo: int
    hi: int
    span: Span


ModeItem = Union[ModeName, ModeNumber, ModeRange]


@dataclass(frozen=True)
class ModeSet:
    items: tuple[ModeItem, ...]
    every: bool  # `*`; items are then the exceptions
    span: Span


# ---- declarations ----------------------------------------------------------------

TypeName = Literal["int", "double", "prob", "bool"]


@dataclass(frozen=True)
class MachineDecl:
    name: Ident
    span: Span


@dataclass(frozen=True)
class Interval:
    lo: Expr
    hi: Expr
    span: Span


@dataclass(frozen=True)
class SimSource:
    ref: Ident  # dotted reference, e.g. uav.approach.duration; a data file's path
    policy: tuple[tuple[Ident, float], ...]
    span: Span
    column: Ident | None = None  # `from data "PATH" column NAME`: the data file's column


@dataclass(frozen=True)
class ConstDecl:
    type: TypeName
    name: Ident
    value: Expr | Interval
    source: SimSource | None
    span: Span


@dataclass(frozen=True)
class ParamDecl:
    type: TypeName
    name: Ident
    default: Expr | None
    span: Span


@dataclass(frozen=True)
class RangeType:
    lo: Expr
    hi: Expr
    span: Span


@dataclass(frozen=True)
class BoolType:
    span: Span


@dataclass(frozen=True)
class FieldDecl:
    name: Ident
    type: RangeType | BoolType
    span: Span


@dataclass(frozen=True)
class TupleType:
    fields: tuple[FieldDecl, ...]
    span: Span


@dataclass(frozen=True)
class VarDecl:
    name: Ident
    type: RangeType | BoolType | TupleType
    init: Expr | TupleLit | None
    clamp: bool
    span: Span
    # a shared variable of a composed mission: the agents that may write it
    # (`written by a, b`); None: not stated
    writers: tuple[Ident, ...] | None = None


@dataclass(frozen=True)
class ModeDecl:
    name: Ident
    number: int | None
    number_span: Span | None
    initial: bool
    final: bool
    span: Span


@dataclass(frozen=True)
class LValue:
    name: Ident
    field: Ident | None
    span: Span

    @property
    def text(self) -> str:
        return self.name.text + (f".{self.field.text}" if self.field else "")


@dataclass(frozen=True)
class Goto:
    mode: Ident
    span: Span


@dataclass(frozen=True)
class Assign:
    target: LValue
    op: Literal[":=", "+=", "-="]
    value: Expr | TupleLit
    span: Span


Update = Union[Goto, Assign]


@dataclass(frozen=True)
class Outcome:
    """`prob: updates;` -- or, with prob None, the single outcome of a plain body."""

    prob: Expr | None
    updates: tuple[Update, ...]
    span: Span


@dataclass(frozen=True)
class Body:
    outcomes: tuple[Outcome, ...]
    span: Span


@dataclass(frozen=True)
class ActionDecl:
    name: Ident
    modes: ModeSet
    guard: Expr | None
    weight: Expr | None
    body: Body
    span: Span
    sync: bool = False  # `sync action`: taken together by every agent that declares it


@dataclass(frozen=True)
class HazardDecl:
    name: Ident
    modes: ModeSet
    kind: Literal["probabilistic", "preemptive"]
    trigger: Expr  # the probability, or the condition
    weight: Expr | None
    body: Body
    span: Span


@dataclass(frozen=True)
class FormulaDecl:
    name: Ident
    value: Expr
    span: Span


@dataclass(frozen=True)
class LabelDecl:
    name: Ident
    value: Expr
    span: Span


@dataclass(frozen=True)
class RewardItem:
    action: Ident | None  # None: a state reward
    guard: Expr
    value: Expr
    span: Span
    agent: Ident | None = None  # `[uav1.Search]`: the agent of the action


@dataclass(frozen=True)
class RewardsDecl:
    name: Ident
    items: tuple[RewardItem, ...]
    span: Span


# ---- properties ------------------------------------------------------------------


@dataclass(frozen=True)
class Eventually:
    bound: Expr | None
    target: Expr
    span: Span


@dataclass(frozen=True)
class Globally:
    bound: Expr | None
    target: Expr
    span: Span


@dataclass(frozen=True)
class Until:
    left: Expr
    bound: Expr | None
    right: Expr
    span: Span


@dataclass(frozen=True)
class Next:
    target: Expr
    span: Span


@dataclass(frozen=True)
class ReachReward:
    target: Expr
    span: Span


@dataclass(frozen=True)
class CumulativeReward:
    bound: Expr | None
    span: Span


@dataclass(frozen=True)
class InstantReward:
    at: Expr
    span: Span


PathFormula = Union[Eventually, Globally, Until, Next]
RewardPath = Union[ReachReward, CumulativeReward, InstantReward]


@dataclass(frozen=True)
class Threshold:
    """A requirement's comparison: `>= 0.65` in `P>=0.65 [ ... ]`."""

    op: Literal["<=", ">=", "<", ">"]
    value: Expr
    span: Span


@dataclass(frozen=True)
class PQuery:
    op: Literal["P", "Pmin", "Pmax"]
    path: PathFormula
    span: Span
    threshold: Threshold | None = None  # None: `=?`, the value is asked


@dataclass(frozen=True)
class RQuery:
    reward: str | None
    reward_span: Span | None
    opt: Literal["", "min", "max"]
    path: RewardPath
    span: Span
    threshold: Threshold | None = None  # None: `=?`, the value is asked


@dataclass(frozen=True)
class PropertyDecl:
    name: Ident
    query: PQuery | RQuery
    span: Span


@dataclass(frozen=True)
class ComposeDecl:
    """`compose interleaving;`, `compose interleaving uniform;` or `compose timed ties
    order;`."""

    kind: Ident
    ties: Ident | None
    span: Span
    scheduler: Ident | None = None  # `uniform` in `compose interleaving uniform;`


@dataclass(frozen=True)
class AgentDecl:
    """`agent NAME clock VAR { ... }`: one agent of a composed mission."""

    name: Ident
    clock: Ident | None
    decls: tuple[Decl, ...]
    span: Span
    # a template (`agent Robot(id, grant) { ... }`): its parameters; None: an agent
    params: tuple[Ident, ...] | None = None


@dataclass(frozen=True)
class Instance:
    """`r1 = Robot(1, Grant1)`: an agent made from a template."""

    name: Ident
    template: Ident
    args: tuple[Expr, ...]
    span: Span


@dataclass(frozen=True)
class AgentsDecl:
    """`agents r1 = Robot(1, Grant1), r2 = Robot(2, Grant2);`."""

    instances: tuple[Instance, ...]
    span: Span


@dataclass(frozen=True)
class FamilyDecl:
    """`agent r[1..N] : Robot;`: the agents r1 .. rN, each an instance of the template
    (its index the template's one parameter, if it has one)."""

    name: Ident
    lo: Expr
    hi: Expr
    template: Ident
    span: Span


Decl = Union[ConstDecl, ParamDecl, VarDecl, ModeDecl, ActionDecl, HazardDecl, FormulaDecl,
             LabelDecl, RewardsDecl, PropertyDecl, ComposeDecl, AgentDecl, AgentsDecl,
             FamilyDecl]


@dataclass(frozen=True)
class Module:
    """One parsed .afsm file."""

    machine: MachineDecl | None
    decls: tuple[Decl, ...]
    span: Span
