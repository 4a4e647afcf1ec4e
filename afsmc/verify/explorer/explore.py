"""afsmc's own explicit-state exploration of a lowered model whose clock only grows.

Storm's sparse build of the UAV mission needs about 267 bytes per state; this one keeps
the states as packed int64 keys (each variable's offset in its range, the mode's too) and
the transitions as flat arrays, explored with numpy a bucket at a time:

* the **bucket** variable is one that only grows along every transition (the mission
  clock, saturated at its cap, where it may stay equal): its states are explored bucket
  by bucket in increasing order, each to a fixpoint (successors in the same bucket are
  explored in further rounds, those in later buckets wait);
* a transition that makes it smaller (the dead-variable reset of a final mode's clock)
  leads to a **late** state, explored after every bucket, whose successors are late too;
* within a bucket (and among the late states) the states are ordered topologically by the
  edges between them (Kahn, self-loops ignored). A cycle of more than one state, a
  variable out of its range, a probability that does not sum to 1, a state without a
  command (or with two, in a DTMC): :func:`explore` returns None and Storm builds instead.

Each choice is one enabled command (an MDP's), its branches those of non-zero probability
with equal successors merged, as Storm builds them, so the counts of states, choices and
transitions equal Storm's. The result is :class:`afsmc.verify.arrays.acyclic.Arrays`: the states
numbered so that every successor of a state lies in an earlier layer, for its backward
pass. Everything is vectorised per bucket, per mode and per command.
"""

from __future__ import annotations

import dataclasses
import os
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import numpy.typing as npt

from afsmc.backends.prism import variant_label
from afsmc.lower.lowering import Lowered
from afsmc.lower.reduce import _step
from afsmc.model import expr as E
from afsmc.model import ir
from afsmc.model.bounds import bounds
from afsmc.sim.compile import Scope, fold, static
from afsmc.verify.arrays import acyclic
from afsmc.verify.arrays.acyclic import F64, I64
from afsmc.verify.explorer.explore_eval import MEMO, Compiler, Fn, frame

KEY_BITS = 62  # a state's key must fit in a signed 64-bit integer
SUM_TOLERANCE = 1e-6  # Storm's default check that a command's probabilities sum to 1

Notify = Callable[[str, Any], None]


class GiveUp(Exception):
    """The model is not one this explorer handles: Storm builds it instead."""


class TooManyStates(Exception):
    """More states than the limit; `partial`: counted in a round the explorer stopped, so
    the model has at least `states`."""

    def __init__(self, states: int, partial: bool = False) -> None:
        super().__init__(states)
        self.states = states
        self.partial = partial


@dataclass(frozen=True)
class Field:
    name: str  # a variable's name, or "mode"
    lo: int
    size: int
    shift: int  # its bits start here: a value's offset in the range times `stride`
    boolean: bool

    @property
    def stride(self) -> int:
        return 1 << self.shift

    @property
    def mask(self) -> int:
        return (1 << (self.size - 1).bit_length()) - 1


@dataclass
class Layout:
    """How a state is packed into an int64: each field in its own bits (shifts and masks
    decode them, far faster than divisions), the bucket variable most significant, so
    that keys sort by bucket first."""

    fields: dict[str, Field]
    bucket: Field | None

    def decode(self, keys: I64) -> dict[str, Any]:
        out: dict[str, Any] = {}
        for f in self.fields.values():
            v = (keys >> f.shift) & f.mask
            out[f.name] = v.astype(bool) if f.boolean else v + f.lo if f.lo else v
        return out

    def bucket_of(self, keys: I64) -> I64:
        if self.bucket is None:
            return np.zeros(len(keys), np.int64)
        out: I64 = keys >> self.bucket.shift
        return out


def bucket_variable(low: Lowered) -> str | None:
    """An integer variable every update of which adds a non-negative amount to it (under
    a cap) or sets a constant, and some update adds: the mission clock."""
    model = low.model
    best: tuple[int, str] | None = None
    for v in model.variables:
        if v.type is not E.Type.INT:
            continue
        ok, grows = True, False
        for cmd in low.commands:
            for b in cmd.branches:
                for var, value in b.updates:
                    if var != v.name:
                        continue
                    k = _step(v.name, _uncapped(value), model, low.bounds, True)
                    if k is not None and v.name not in E.vars_read(k):
                        grows = True
                    elif not isinstance(value, E.Lit):
                        ok = False
        if ok and grows and (best is None or v.hi - v.lo > best[0]):
            best = (v.hi - v.lo, v.name)
    return None if best is None else best[1]


def _uncapped(value: E.Expr) -> E.Expr:
    """`x` of the saturation's `min(x, cap)`."""
    if isinstance(value, E.Call) and value.func == "min" and len(value.args) == 2 \
            and isinstance(value.args[1], E.Lit):
        return value.args[0]
    return value


def layout(low: Lowered) -> Layout:
    model = low.model
    numbers = [m.number for m in model.modes]
    spans = [("mode", min(numbers), max(numbers) - min(numbers) + 1, False)]
    spans += [(v.name, int(v.lo), int(v.hi) - int(v.lo) + 1, v.type is E.Type.BOOL)
              for v in model.variables]
    bucket = bucket_variable(low)
    spans.sort(key=lambda s: s[0] == bucket)  # the bucket variable last: most significant
    fields: dict[str, Field] = {}
    shift = 0
    for name, lo, size, boolean in spans:
        fields[name] = Field(name, lo, size, shift, boolean)
        shift += (size - 1).bit_length()
    if shift > KEY_BITS:
        raise GiveUp(f"its variables need {shift} bits, more than a 64-bit key holds")
    return Layout(fields, fields[bucket] if bucket is not None else None)


@dataclass
class CBranch:
    prob: Fn
    updates: list[tuple[Field, Fn, bool]]  # (variable, new value, checked against its range)
    clear: int = 0  # the bits of the variables set to constants ...
    bits: int = 0  # ... and their new bits
    # its probability at further valuations of the interval probabilities (`Compiled.at`)
    others: list[Fn] = field(default_factory=list)
    # the folded expressions of `prob` and of each update's value, in the order of
    # `updates` (afsmc.verify.kernels.successors translates them)
    source: tuple[E.Expr, list[E.Expr]] | None = None


@dataclass
class CCommand:
    index: int
    guard: Fn
    guard_key: int | None  # the guard's subexpression number: commands with one share states
    branches: list[CBranch]
    rewards: list[Fn | None]  # per reward structure asked: its action reward (None: none)
    guard_expr: E.Expr | None = None  # the folded guard (afsmc.verify.kernels.successors)
    reward_exprs: list[E.Expr | None] | None = None  # ... and the folded `rewards`


@dataclass
class Compiled:
    layout: Layout
    modes: dict[int, list[CCommand]]
    targets: list[Fn]  # each query target's truth
    state_rewards: list[list[tuple[Fn, Fn]]]  # per reward structure: (guard, value)
    initial: int
    dtmc: bool
    reward_names: list[str]
    keep: bool = False  # keep each state's key and each choice's command (a strategy's)
    # With valuations of the interval probabilities (compile_model's `points`): the model is
    # explored at the first, and each distinct branch probability there (a code of the
    # explored arrays) maps to its values at the others, merged as the branches are
    # (afsmc.verify.lifting; PointTable).
    at: PointTable | None = None
    # the compiled successor kernel (afsmc.verify.kernels.successors), once built; False:
    # the model is not translated
    successors: Any = field(default=None, repr=False, compare=False)


def storm_order(low: Lowered) -> dict[int, tuple[int, int, int]]:
    """Each command's place among a state's choices in Storm's model of the PRISM text
    emitted with variant labels (the one a strategy's extraction checks): unlabelled
    commands first, then the labelled ones by their label's first appearance, each in
    command order. The first optimal choice of a state is then the one Storm keeps."""
    first: dict[str, int] = {}
    out = {}
    for i, cmd in enumerate(low.commands):
        label = "" if cmd.silent else variant_label(low, i) if cmd.choice else cmd.action
        out[i] = (1, first.setdefault(label, len(first)), i) if label else (0, 0, i)
    return out


def compile_model(low: Lowered, targets: list[E.Expr], rewards: list[str],
                  keep: bool = False, points: Sequence[Mapping[str, float]] = ()) -> Compiled:
    """`points`: valuations of some constants (the interval probabilities), explored at
    the first; each branch's probability also at the others (`Compiled.at`)."""
    model = low.model
    if low.parameters or low.network is not None:
        raise GiveUp("undefined constants or a composed mission")
    consts: dict[str, Any] = dict(model.const_values)
    for gen, (_, value) in low.bounds.items():
        consts[gen] = value
    if points:
        consts |= points[0]
    formulas = {f.name: f.value for f in model.formulas}
    labels = {lb.name: lb.value for lb in model.labels}
    base = Scope(consts, formulas, labels, low.weights)
    lay = layout(low)
    compile_expr = Compiler()
    structs = [model_reward(model, r) for r in rewards]
    rank = storm_order(low)
    modes: dict[int, list[CCommand]] = {}
    for m in model.modes:
        sc = Scope(consts, formulas, labels, low.weights, m.number)
        cmds: list[CCommand] = []
        for i, cmd in enumerate(low.commands):
            if m.number not in cmd.modes:
                continue
            g = fold(cmd.guard, sc)
            if static(g) is False:
                continue
            branches = [_branch(b.prob, b.updates, sc, lay, low, compile_expr)
                        for b in cmd.branches]
            for b, cb in zip(cmd.branches, branches, strict=True):
                cb.others = [compile_expr(fold(b.prob, dataclasses.replace(sc, consts={**consts, **p})))
                             for p in points[1:]]
            sums = [_sum_items([] if cmd.silent else
                               [it for it in r.items if it.action == cmd.action], sc)
                    for r in structs]
            acts = [None if e is None else compile_expr(e) for e in sums]
            cmds.append(CCommand(i, compile_expr(g), compile_expr.key(g), branches, acts, g,
                                 sums))
        modes[m.number] = sorted(cmds, key=lambda c: rank[c.index])
    state = [[(compile_expr(fold(it.guard, base)), compile_expr(fold(it.value, base)))
              for it in r.items if it.action is None] for r in structs]
    init = {"mode": model.initial_mode.number} | {v.name: int(v.init) for v in model.variables}
    key = sum((init[f.name] - f.lo) * f.stride for f in lay.fields.values())
    return Compiled(lay, modes, [compile_expr(fold(t, base)) for t in targets], state,
                    int(key), low.kind == "dtmc", list(rewards), keep,
                    PointTable() if points else None)


def _branch(prob: E.Expr, updates: tuple[tuple[str, E.Expr], ...], sc: Scope, lay: Layout,
            low: Lowered, compile_expr: Compiler) -> CBranch:
    p, values = fold(prob, sc), list[E.Expr]()
    out = CBranch(compile_expr(p), [], source=(p, values))
    for var, val in updates:
        f, v = lay.fields[var], fold(val, sc)
        if isinstance(v, E.Lit):
            k = int(v.value)
            if not f.lo <= k < f.lo + f.size:
                raise GiveUp(f"{f.name} set to {k}, out of its range")
            out.clear |= f.mask << f.shift
            out.bits |= (k - f.lo) << f.shift
        else:
            out.updates.append((f, compile_expr(v), _may_leave(val, f, low)))
            values.append(v)
    return out


def _may_leave(value: E.Expr, f: Field, low: Lowered) -> bool:
    """Whether an update may leave its variable's range (interval bounds cannot rule it
    out): checked as it is explored."""
    if f.name == "mode":
        return False  # a mode number the lowering wrote
    try:
        lo, hi = bounds(value, low.model, generated=low.bounds)
    except Exception:  # an expression bounds() does not know: check each value
        return True
    return not (f.lo <= lo and hi < f.lo + f.size)


def model_reward(model: ir.Model, name: str) -> ir.RewardStruct:
    for r in model.rewards:
        if r.name == name:
            return r
    raise GiveUp(f"no reward structure {name}")


def _sum_items(items: list[ir.RewardItem], sc: Scope) -> E.Expr | None:
    """The folded sum of the action reward items (None: none)."""
    if not items:
        return None
    total: E.Expr = E.Ite(items[0].guard, items[0].value, E.Lit(0, E.Type.INT), items[0].value.type)
    for it in items[1:]:
        total = E.Binary("+", total, E.Ite(it.guard, it.value, E.Lit(0, E.Type.INT),
                                           it.value.type), E.Type.DOUBLE)
    return fold(total, sc)


def full(v: Any, n: int, dtype: Any) -> Any:
    """`v` (an array or a scalar) as an array of `n`."""
    a = np.asarray(v, dtype=dtype)
    return np.full(n, a, dtype) if a.ndim == 0 else a


@dataclass
class Expansion:
    """The choices of some states (each state's contiguous, in command order)."""

    state: I64  # choice -> the state (index into the expanded keys)
    first: I64  # choice -> its first branch (len = choices + 1)
    target: I64  # branch -> successor key
    prob: F64
    reward: list[F64]  # per reward structure asked: the action reward per choice
    command: npt.NDArray[np.int32]  # choice -> its lowered command's index


def _merge(tk: I64, pr: F64, others: F64 | None = None
           ) -> tuple[I64, I64, F64, F64 | None]:
    """Rows of (successor, probability): zero probabilities dropped, equal successors of
    a row merged (summed); (row of each branch, successor, probability), and `others`
    (the probabilities at further points, n x k x points) dropped and merged alike."""
    n, k = tk.shape
    if k <= 4 and (pr != 0).all() and not any(
            (tk[:, i] == tk[:, j]).any() for i in range(k) for j in range(i + 1, k)):
        return (np.repeat(np.arange(n, dtype=np.int64), k), tk.ravel(), pr.ravel(),
                None if others is None else others.reshape(n * k, -1))
    order = np.argsort(tk, axis=1, kind="stable")
    tk = np.take_along_axis(tk, order, axis=1)
    pr = np.take_along_axis(pr, order, axis=1)
    keep = (pr != 0).ravel()
    row = np.repeat(np.arange(n, dtype=np.int64), k)[keep]
    tkf, prf = tk.ravel()[keep], pr.ravel()[keep]
    of = None if others is None else np.take_along_axis(
        others, order[:, :, None], axis=1).reshape(n * k, -1)[keep]
    if tkf.size == 0:
        return row, tkf, prf, of
    start = np.ones(tkf.size, bool)
    start[1:] = (tkf[1:] != tkf[:-1]) | (row[1:] != row[:-1])
    at = np.flatnonzero(start)
    return (row[at], tkf[at], np.add.reduceat(prf, at),
            None if of is None else np.add.reduceat(of, at, axis=0))


def _command(cmd: CCommand, base: I64, sub: dict[str, Any],
             at: PointTable | None = None
             ) -> tuple[I64, I64, F64, list[F64]]:
    """The command's choices in the states `base` (their frame `sub`): (row, successor,
    prob) per branch and the action rewards per choice; with `at` (Compiled.at), each
    merged probability's values at the further points recorded there."""
    n = len(base)
    tks = np.empty((n, len(cmd.branches)), np.int64)
    prs = np.empty((n, len(cmd.branches)))
    uniform = True  # every branch probability the same in every state
    for j, b in enumerate(cmd.branches):
        p = b.prob(sub)
        uniform = uniform and np.ndim(p) == 0
        prs[:, j] = p
        tk = (base & ~b.clear) | b.bits if b.clear else base.copy()
        for f, fn, check in b.updates:
            new = fn(sub)
            if isinstance(new, np.ndarray) and new.dtype.kind == "f":
                raise GiveUp(f"{f.name} takes an undefined value (a division by zero)")
            if check and (np.min(new) < f.lo or np.max(new) >= f.lo + f.size):
                raise GiveUp(f"{f.name} leaves its range")
            if f.boolean:  # numpy has no `-` of booleans
                tk = (tk & ~(1 << f.shift)) | (np.asarray(new, np.int64) << f.shift)
            else:
                tk += (new - sub[f.name]) * f.stride
        tks[:, j] = tk
    if n and not np.abs(prs.sum(axis=1) - 1.0).max() <= SUM_TOLERANCE:  # NaN too
        raise GiveUp("a command's probabilities do not sum to 1")
    others = None
    if at is not None and n:
        others, uniform = _at_points(cmd, sub, prs, uniform)
    rewards = [np.zeros(n) if r is None else full(r(sub), n, np.float64) for r in cmd.rewards]
    row, tk, pr, of = _merge(tks, prs, others)
    if at is not None and of is not None:
        k = len(cmd.branches)
        # nothing merged or dropped from rows all alike: each row holds the first's
        # probabilities (in its successors' order), so the first is recorded alone
        at.record(*((pr[:k], of[:k]) if uniform and len(pr) == n * k else (pr, of)))
    return row, tk, pr, rewards


def _at_points(cmd: CCommand, sub: dict[str, Any], prs: F64, uniform: bool
               ) -> tuple[F64, bool]:
    """The command's branch probabilities at the further points (states x branches x
    points; `prs` those at the point explored), and whether they are the same in every
    state (`uniform`: so are those of `prs`). GiveUp where a distribution does not sum to
    1 at a point, or a branch the merge drops (probability 0 at the point explored) is
    not 0 at another, so that the merged distributions sum to 1 wherever these do."""
    others = np.empty((len(prs), len(cmd.branches), len(cmd.branches[0].others)))
    for j, b in enumerate(cmd.branches):
        for i, fn in enumerate(b.others):
            v = fn(sub)
            uniform = uniform and np.ndim(v) == 0
            others[:, j, i] = v
    rows, at = (others[:1], prs[:1]) if uniform else (others, prs)  # alike: one checked
    if not np.abs(rows.sum(axis=1) - 1.0).max() <= SUM_TOLERANCE or (rows[at == 0.0] != 0.0).any():
        raise GiveUp("a command's probabilities do not sum to 1 at a further valuation of "
                     "the interval probabilities")
    return others, uniform


# Two branch probabilities equal at the exploration's point must be the same function of
# the interval probabilities: their values at the other points may differ by rounding only.
SAME_FUNCTION = 1e-12


class PointTable:
    """Each distinct branch probability at the exploration's point (`Compiled.at`) and its
    values at the further points, kept sorted by the first so that a batch's probabilities
    are looked up (as ProbTable encodes them) rather than sorted."""

    def __init__(self) -> None:
        self.values = np.zeros(0)  # sorted
        self.rows = np.zeros((0, 0))  # values x further points

    def row(self, v: float) -> tuple[float, ...]:
        i = int(np.searchsorted(self.values, v))
        return tuple(self.rows[i].tolist())

    def record(self, pr: F64, others: F64) -> None:
        """Each value of `pr` with its values at the other points (`others`, one row per
        branch); GiveUp if one value stands for two functions (the point is meant to be
        generic: this should not happen)."""
        if not len(pr):
            return
        pos = np.searchsorted(self.values, pr)
        hit = (self.values[np.minimum(pos, len(self.values) - 1)] == pr) \
            if len(self.values) else np.zeros(len(pr), bool)
        if not hit.all():
            new, first = np.unique(pr[~hit], return_index=True)
            rows = others[~hit][first]
            values = np.concatenate([self.values, new])
            order = np.argsort(values, kind="stable")
            self.values = values[order]
            self.rows = np.concatenate([self.rows.reshape(-1, others.shape[1]), rows])[order]
            pos = np.searchsorted(self.values, pr)
        if np.abs(others - self.rows[pos]).max(initial=0.0) > SAME_FUNCTION:
            raise GiveUp("two branch probabilities agree at the point explored but not "
                         "elsewhere")


def expand(c: Compiled, keys: I64, fast: bool = False) -> Expansion:
    """Every choice of the states `keys`; `fast`: sorted by state by a compiled kernel
    (afsmc.verify.kernels.blocks.by_state)."""
    lay = c.layout
    mf = lay.fields["mode"]
    mode = ((keys >> mf.shift) & mf.mask) + mf.lo
    order = np.argsort(mode, kind="stable")
    bounds = np.flatnonzero(np.diff(mode[order])) + 1
    if fast and len(keys) and os.environ.get("AFSMC_SUCCESSORS") == "numba":
        x = _compiled(c, keys, mode, order, bounds)
        if x is not None:
            return x
    states, rows, tks, prs, cmds = [], [], [], [], []
    rws: list[list[F64]] = [[] for _ in range(len(c.state_rewards))]
    choices = 0
    with np.errstate(all="ignore"):
        for part in np.split(order, bounds):
            if part.size == 0:
                continue
            fr = frame(lay.decode(keys[part]))
            subs: dict[int | None, tuple[I64, dict[str, Any]]] = {}
            for cmd in c.modes.get(int(mode[part[0]]), []):
                hit = subs.get(cmd.guard_key) if cmd.guard_key is not None else None
                if hit is None:
                    sel = np.flatnonzero(full(cmd.guard(fr), len(part), bool))
                    hit = subs[cmd.guard_key] = (sel, frame({k: v[sel] for k, v in fr.items()
                                                             if k != MEMO}))
                sel, sub = hit
                if sel.size == 0:
                    continue
                row, tk, pr, rw = _command(cmd, keys[part][sel], sub, c.at)
                states.append(part[sel])
                rows.append(row + choices)
                tks.append(tk)
                prs.append(pr)
                cmds.append(np.full(len(sel), cmd.index, np.int32))
                for i, r in enumerate(rw):
                    rws[i].append(r)
                choices += len(sel)
    return _ordered(len(keys), states, rows, tks, prs, rws, cmds, c.dtmc, fast)


def _compiled(c: Compiled, keys: I64, mode: I64, order: I64, bounds: I64) -> Expansion | None:
    """`expand` by the model's compiled kernel (afsmc.verify.kernels.successors); None
    where it has none or leaves these states to the numpy path."""
    from afsmc.verify.kernels import successors

    fn = successors.kernel(c)
    if fn is None:
        return None
    starts = np.concatenate([[0], bounds]).astype(np.int64)
    ends = np.concatenate([bounds, [len(keys)]]).astype(np.int64)
    most = max((len(cmd.branches) for cmds in c.modes.values() for cmd in cmds), default=1)
    raw = successors.run(fn, keys, order, starts, ends, mode[order[starts]], most,
                         len(c.reward_names))
    if raw is None:
        return None
    return _ordered(len(keys), [raw.state], [raw.row], [raw.target], [raw.prob],
                    [[r] for r in raw.rewards], [raw.command], c.dtmc, True)


def _cat(parts: list[Any], dtype: Any) -> Any:
    return np.concatenate(parts) if parts else np.zeros(0, dtype)


def _ordered(n: int, states: list[I64], rows: list[I64], tks: list[I64], prs: list[F64],
             rws: list[list[F64]], cmds: list[npt.NDArray[np.int32]], dtmc: bool,
             fast: bool = False) -> Expansion:
    """The choices sorted by state (command order kept within a state); `fast`: by a
    compiled counting sort."""
    state = _cat(states, np.int64)
    per_state = np.bincount(state, minlength=n)
    if n and (per_state.min() == 0 or (dtmc and per_state.max() > 1)):
        raise GiveUp("a state without a command" if per_state.min() == 0
                     else "a DTMC state with two commands")
    row = _cat(rows, np.int64)
    counts = np.bincount(row, minlength=len(state))
    old_first = np.zeros(len(state) + 1, np.int64)
    np.cumsum(counts, out=old_first[1:])
    if fast:
        from afsmc.verify.kernels.blocks import by_state

        order, branch = by_state(state, per_state, old_first)
    else:
        order = np.argsort(state, kind="stable")
        branch = acyclic._ranges(old_first[order], old_first[order + 1])
    first = np.zeros(len(state) + 1, np.int64)
    np.cumsum(counts[order], out=first[1:])
    return Expansion(state[order], first, _cat(tks, np.int64)[branch],
                     _cat(prs, np.float64)[branch], [_cat(r, np.float64)[order] for r in rws],
                     _cat(cmds, np.int32)[order])
