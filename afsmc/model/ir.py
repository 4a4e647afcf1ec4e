"""The typed, name-resolved IR of one APFSM (Hoffmann et al., Definition 2).

Frozen dataclasses, one concept each. Every constant has a concrete value (open
constants are instantiated from the command line or their defaults), so every range
is a pair of integers and every later stage can enumerate states.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any, Literal, Union, cast

from afsmc.diagnostics import Source, Span
from afsmc.model.expr import Expr, Type

if TYPE_CHECKING:
    from afsmc.model.search import Witness

Value = Union[int, float, bool]


@dataclass(frozen=True)
class SimSource:
    ref: str  # a simulator output (uav.transport.drop), or a data file's path as written
    policy: tuple[tuple[str, float], ...]
    span: Span
    keys: tuple[Span, ...] = ()  # where each policy key is written, for E504's caret
    column: str | None = None  # `from data "PATH" column NAME`: the column; None: `from sim`

    @property
    def display(self) -> str:
        """The source as the file says it: `uav.transport.drop`, `data "runs.csv" column ok`."""
        if self.column is None:
            return self.ref
        col = self.column if self.column.isidentifier() else f'"{self.column}"'
        return f'data "{self.ref}" column {col}'


@dataclass(frozen=True)
class Constant:
    name: str
    type: Type
    value: Value  # for an interval constant: its lower end
    interval: tuple[int, int] | None
    is_param: bool
    source: SimSource | None
    span: Span
    declared_type: str = "int"  # as written: int, double, prob, bool
    # `const prob P = [lo, hi]`: one fixed, unknown p in [lo, hi] (value: the midpoint);
    # afsmc.verify.engines.parametric bounds every property over it
    prob_interval: tuple[float, float] | None = None

    @property
    def is_interval(self) -> bool:
        return self.interval is not None and self.interval[0] != self.interval[1]

    @property
    def is_prob_interval(self) -> bool:
        return self.prob_interval is not None


@dataclass(frozen=True)
class Variable:
    name: str  # flat name, e.g. pos_x
    display: str  # as the author writes it, e.g. pos.x
    type: Type  # INT or BOOL
    lo: int
    hi: int
    init: int | bool
    clamp: bool
    span: Span

    @property
    def size(self) -> int:
        return self.hi - self.lo + 1


@dataclass(frozen=True)
class Mode:
    name: str
    number: int
    initial: bool
    final: bool
    span: Span


@dataclass(frozen=True)
class Update:
    var: str  # flat variable name, or "mode"
    value: Expr
    span: Span


@dataclass(frozen=True)
class Outcome:
    prob: Expr
    updates: tuple[Update, ...]
    span: Span


@dataclass(frozen=True)
class Action:
    """A weighted action (or a preemptive hazard, which is one in every mode it covers)."""

    name: str
    modes: tuple[int, ...]  # mode numbers, sorted
    guard: Expr
    weight: Expr
    outcomes: tuple[Outcome, ...]
    span: Span
    name_span: Span
    weight_span: Span | None
    guard_span: Span | None
    kind: Literal["action", "preemptive"] = "action"


@dataclass(frozen=True)
class Hazard:
    """A probabilistic hazard: in every covered mode, every action may instead do this."""

    name: str
    modes: tuple[int, ...]
    prob: Expr
    outcomes: tuple[Outcome, ...]
    span: Span
    name_span: Span


@dataclass(frozen=True)
class Formula:
    name: str
    value: Expr
    span: Span


@dataclass(frozen=True)
class Label:
    name: str
    value: Expr
    span: Span


@dataclass(frozen=True)
class RewardItem:
    action: str | None
    guard: Expr
    value: Expr
    span: Span


@dataclass(frozen=True)
class RewardStruct:
    name: str
    items: tuple[RewardItem, ...]
    span: Span


# ---- properties ------------------------------------------------------------------


@dataclass(frozen=True)
class Path:
    """F / G / U / X, with an optional step bound."""

    kind: Literal["F", "G", "U", "X"]
    target: Expr  # for U: the right-hand side
    left: Expr | None = None
    bound: Expr | None = None


@dataclass(frozen=True)
class RewardPath:
    kind: Literal["F", "C", "I"]
    target: Expr | None = None  # F
    bound: Expr | None = None  # C<=k, I=k


@dataclass(frozen=True)
class Threshold:
    """A requirement's comparison, `P>=0.65 [ ... ]`: `op` and `bound`; `exact` is the
    bound as a decimal or fraction text (`"0.65"`), so that a verdict from exact values
    compares with the number written, not its nearest double."""

    op: Literal["<=", ">=", "<", ">"]
    bound: float
    exact: str


@dataclass(frozen=True)
class Property:
    name: str
    kind: Literal["P", "R"]
    opt: Literal["", "min", "max"]
    path: Path | RewardPath
    reward: str | None
    span: Span
    # The formula as written (comments dropped, whitespace normalised): what verify and
    # sweep show, since printing the IR back would give flat names (`pos_x`) and mode
    # ranges (`mode >= A`) that afsm does not accept. "" if the property has no source.
    text: str = ""
    # Where in `text` the step bound (`<=k`, `=k`) stands, or would go after F/G/U/C.
    bound_site: tuple[int, int] | None = None
    # A requirement (`P>=0.65 [ ... ]`): Storm is still asked for the values (min and max),
    # and afsmc.verify.outcome.verdicts judges them. None: `=?`.
    threshold: Threshold | None = None


@dataclass(frozen=True)
class Agent:
    """One agent of a composed mission (docs/language.md, "Composition").

    `model` is the agent's own view, a machine of its own that the single-agent checks
    and lowering take as they are: its modes, variables (by their names in the agent),
    actions and hazards, with the shared variables and the other agents' modes it reads
    as variables it never writes. In the mission, its variable `x` is `<name>_x` and its
    mode `<name>_mode` (`prefix` + name)."""

    name: str
    model: Model
    own: tuple[str, ...]  # the view's names of the agent's own variables
    syncs: tuple[str, ...]  # its `sync action`s
    clock: str | None  # the view's name of its clock (timed composition)
    span: Span
    name_span: Span

    @property
    def prefix(self) -> str:
        return f"{self.name}_"

    @property
    def mode_var(self) -> str:
        return f"{self.name}_mode"

    def mission_name(self, var: str) -> str:
        """A view's variable in the mission: the agent's own prefixed, a shared one as is."""
        return self.prefix + var if var in self.own else var


@dataclass(frozen=True)
class Composition:
    """How a mission's agents move together: `interleaving` (any agent with an enabled
    action may move next: nondeterminism) or `timed` (the agent whose clock is least
    moves; `ties` "order": the one declared first, "nondet": left to min/max, "weight":
    the one whose current action has the larger weight)."""

    kind: Literal["interleaving", "timed"]
    # how agents that may move at once are ordered; for an interleaving, "nondet" or
    # "uniform" (`compose interleaving uniform;`: each with equal probability) or "fair"
    # (`compose interleaving fair;`: min/max over fair schedulers)
    ties: Literal["nondet", "order", "weight", "uniform", "fair"]
    agents: tuple[Agent, ...]
    writers: tuple[tuple[str, tuple[str, ...]], ...]  # shared variable -> who may write it
    span: Span | None

    def agent(self, name: str) -> Agent:
        return next(a for a in self.agents if a.name == name)

    @property
    def text(self) -> str:
        return composition_text(self.kind, self.ties)


def composition_text(kind: str, ties: str) -> str:
    """How agents move together, as a `compose` line says it: "interleaving",
    "interleaving, uniform", "timed, ties order" or "timed, ties nondet"."""
    if kind == "timed":
        return f"{kind}, ties {ties}"
    return kind + (f", {ties}" if ties != "nondet" else "")


@dataclass
class Memo:
    """What later stages derive from a model, kept with it (the model itself is frozen):
    each is computed on first use, once per model, and only from the model.
    `dataclasses.replace(model, ...)` hands the same memo to the new model, like any other
    field: what was derived already is shared, so replace only what it does not read."""

    # afsmc.model.semantics.inline: a formula ("f:NAME"), weight ("w:ACTION") or label
    # ("label:NAME") inlined
    inline: dict[str, Expr] = field(default_factory=dict)
    # afsmc.model.search.deadlock_witness: by mode number, a state with no action enabled
    deadlocks: dict[int, Witness | None] = field(default_factory=dict)
    # afsmc.check.modegraph.analyse's ModeGraph; a later stage's type, so not named here
    modegraph: object | None = None
    # Model's lookups by name or mode: key -> (the tuple indexed, the index). An index is
    # used only while the model's tuple is that very object (`replace` may change it).
    lookups: dict[str, tuple[object, Any]] = field(default_factory=dict)

    def __reduce__(self) -> tuple[type[Memo], tuple[()]]:
        """A model sent to another process (a verify job) goes without what was derived
        from it: the caches may hold closures, and the other process derives its own."""
        return (Memo, ())


@dataclass(frozen=True)
class Model:
    name: str
    source: Source
    constants: tuple[Constant, ...]
    variables: tuple[Variable, ...]
    modes: tuple[Mode, ...]
    actions: tuple[Action, ...]
    hazards: tuple[Hazard, ...]
    formulas: tuple[Formula, ...]
    labels: tuple[Label, ...]
    rewards: tuple[RewardStruct, ...]
    properties: tuple[Property, ...]
    memo: Memo = field(default_factory=Memo, compare=False, repr=False)
    # Several agents (`agent` blocks): the variables hold every agent's mode and own
    # variables by their mission names; modes, actions and hazards are each agent's
    # (`composition.agents[i].model`). None: one machine, as always.
    composition: Composition | None = None

    # Lookups, by indexes built on first use (a scan per lookup would make a model of N
    # declarations cost N^2 to check).
    def _index(self, key: str, of: tuple[Any, ...], build: Callable[[], Any]) -> Any:
        hit = self.memo.lookups.get(key)
        if hit is not None and hit[0] is of:
            return hit[1]
        index = build()
        self.memo.lookups[key] = (of, index)
        return index

    def _by_name(self, key: str, items: tuple[Any, ...]) -> dict[Any, Any]:
        def build() -> dict[Any, Any]:
            out: dict[Any, Any] = {}
            for x in items:
                out.setdefault(x.name, x)  # the first, as a scan finds it
            return out
        return cast("dict[Any, Any]", self._index(key, items, build))

    def constant(self, name: str) -> Constant:
        return cast(Constant, self._lookup("constant", self.constants, name))

    def variable(self, name: str) -> Variable:
        return cast(Variable, self._lookup("variable", self.variables, name))

    def display_names(self) -> dict[str, str]:
        """Flat variable name (`pos_x`) -> as written (`pos.x`), for messages."""
        return {v.name: v.display for v in self.variables}

    def mode(self, name: str) -> Mode:
        return cast(Mode, self._lookup("mode", self.modes, name))

    def mode_by_number(self, number: int) -> Mode:
        def build() -> dict[int, Mode]:
            out: dict[int, Mode] = {}
            for m in self.modes:
                out.setdefault(m.number, m)
            return out
        try:
            return cast(Mode, self._index("mode_number", self.modes, build)[number])
        except KeyError:
            raise StopIteration from None  # as the scan it replaces

    def action(self, name: str) -> Action:
        return cast(Action, self._lookup("action", self.actions, name))

    def formula(self, name: str) -> Formula:
        return cast(Formula, self._lookup("formula", self.formulas, name))

    def label(self, name: str) -> Label:
        return cast(Label, self._lookup("label", self.labels, name))

    def _lookup(self, key: str, items: tuple[Any, ...], name: str) -> Any:
        try:
            return self._by_name(key, items)[name]
        except KeyError:
            raise StopIteration from None  # as the scan it replaces

    @property
    def initial_mode(self) -> Mode:
        return next(m for m in self.modes if m.initial)

    @property
    def mode_names(self) -> dict[int, str]:
        """Mode number -> name, built once per model (lowering asks for it per action); the
        one dict is shared: read it, do not change it."""
        return cast("dict[int, str]", self._index(
            "mode_names", self.modes, lambda: {m.number: m.name for m in self.modes}))

    @property
    def interval_constants(self) -> tuple[Constant, ...]:
        return cast("tuple[Constant, ...]", self._index(
            "interval_constants", self.constants,
            lambda: tuple(c for c in self.constants if c.is_interval)))

    @property
    def prob_intervals(self) -> tuple[Constant, ...]:
        return tuple(c for c in self.constants if c.prob_interval is not None)

    @property
    def is_nondeterministic(self) -> bool:
        return bool(self.interval_constants)

    def actions_in(self, mode: int) -> tuple[Action, ...]:
        return cast("tuple[Action, ...]", self._in_mode("actions_in", self.actions).get(mode, ()))

    def hazards_in(self, mode: int) -> tuple[Hazard, ...]:
        return cast("tuple[Hazard, ...]", self._in_mode("hazards_in", self.hazards).get(mode, ()))

    def _in_mode(self, key: str, items: tuple[Any, ...]) -> dict[int, tuple[Any, ...]]:
        def build() -> dict[int, tuple[Any, ...]]:
            out: dict[int, list[Any]] = {}
            for x in items:
                for m in dict.fromkeys(x.modes):
                    out.setdefault(m, []).append(x)
            return {m: tuple(xs) for m, xs in out.items()}
        return cast("dict[int, tuple[Any, ...]]", self._index(key, items, build))

    @property
    def const_values(self) -> dict[str, Value]:
        """Each constant's value (one dict per model: read it, do not change it)."""
        return cast("dict[str, Value]", self._index(
            "const_values", self.constants, lambda: {c.name: c.value for c in self.constants}))
