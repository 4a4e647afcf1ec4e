"""Exact state-space reductions of the lowered model, each switchable.

* ``dead_reset`` -- a live-variable analysis over modes: a variable that will not be
  read again before it is written (in the mode a transition enters) is reset to its
  initial value by that transition. States that differed only in a dead variable merge;
  no property can tell, because a variable that a label, reward or property reads in a
  mode is live there (and, by the analysis, wherever it may be read later). (Measured on
  UAV-like models: about half the states, see docs/benchmarks.md.)
* ``saturate`` -- a counter that only grows (the mission time) and is only ever compared
  with constants is saturated just above the largest constant it is compared with: all
  larger values satisfy the same comparisons and stay larger, so they are one state
  (bisimilar). Likewise downwards for a counter that only shrinks (the battery, below the
  lowest threshold). Its range shrinks accordingly.
* ``reorder`` -- the declaration order of the variables, which Storm's decision
  diagrams (dd and hybrid engines) follow: control variables first, the fields of tuples
  interleaved (pos.x, ret.x, pos.y, ret.y), wide counters (time, battery) last. The
  state space is unchanged.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, replace
from typing import Literal

from afsmc.lower.lowering import Branch, Command, Lowered
from afsmc.model import expr as E
from afsmc.model import ir
from afsmc.model.bounds import bounds, static
from afsmc.model.semantics import inline

Symmetry = Literal["auto", "on", "off"]


@dataclass(frozen=True)
class Reductions:
    dead_reset: bool = True
    reorder: bool = True
    saturate: bool = True
    # agents alike kept in a canonical order (afsmc.lower.symmetry): "on" (--symmetry)
    # tries it whatever is asked; "auto" (the verifying front-ends' default) tries it too
    # once afsmc.lower.symmetry.decide has found that no output asked for names the agents
    # (it changes which agent a strategy or a path names), else turns it "off" with
    # `symmetry_off` saying why; "off" without a reason is --no-symmetry (and the default of
    # every other use of the lowered model: the simulator, the diagrams)
    symmetry: Symmetry = "off"
    symmetry_off: str | None = None

    @staticmethod
    def none() -> Reductions:
        return Reductions(dead_reset=False, reorder=False, saturate=False)

    def describe(self) -> str:
        on = [n for n, v in (("dead-reset", self.dead_reset), ("saturate", self.saturate),
                             ("reorder", self.reorder),
                             ("symmetry", self.symmetry != "off")) if v]
        return ", ".join(on) if on else "none"


def reduce(low: Lowered, options: Reductions = Reductions()) -> Lowered:
    if low.network is not None:
        from afsmc.lower.reduce_compose import reduce_composed

        return reduce_composed(low, options)
    if options.saturate:
        low, done = saturate(low)
        if done:
            low = replace(low, reductions=(*low.reductions, "saturated " + ", ".join(done)))
    if options.dead_reset:
        low = dead_reset(low)
        low = replace(low, reductions=(*low.reductions, "dead-variable reset"))
    if options.reorder:
        low = reorder(low)
        low = replace(low, reductions=(*low.reductions, "variable order"))
    return low


# ---- live variables ------------------------------------------------------------------


def _observed(model: ir.Model) -> list[tuple[E.Expr, tuple[int, ...] | None]]:
    """What labels, rewards and properties read, each with the modes it is read in (None:
    every mode): an action's reward is read in the states its action leaves."""
    out: list[tuple[E.Expr, tuple[int, ...] | None]] = [(lb.value, None) for lb in model.labels]
    for r in model.rewards:
        for it in r.items:
            where = None if it.action is None else tuple(model.action(it.action).modes)
            out += [(it.guard, where), (it.value, where)]
    for p in model.properties:
        out += [(x, None) for x in (getattr(p.path, "target", None), getattr(p.path, "left", None),
                                    getattr(p.path, "bound", None)) if x is not None]
    return out


def observable(model: ir.Model, mode: int | None = None) -> set[str]:
    """Variables that labels, rewards or properties read: never reset. With `mode`, those
    they read in a state of that mode: `mode == Done && obj == 0` reads nothing elsewhere,
    so a final EmergencyLand keeps no mission variables and is one state, not one per
    (obj, t, ...) it was entered with."""
    if mode is None:
        return set().union(*(E.vars_read(inline(e, model)) for e, _ in _observed(model)))
    return observable_by_mode(model, (mode,))[mode]


def observable_by_mode(model: ir.Model, modes: Sequence[int]) -> dict[int, set[str]]:
    """`observable(model, m)` for each of `modes`, in time linear in the model: an
    expression whose only use of the mode is `mode == M` or `mode != M` (a label
    `x == 3 && mode == M17`) is folded once for each mode it names and once for all the
    others (it reads the same there); only another use of the mode (`mode < 3`) has it
    folded in every mode. Folding every expression in every mode was quadratic: the
    labels of 12,000 modes took minutes to compile."""
    out: dict[int, set[str]] = {m: set() for m in modes}
    everywhere: set[str] = set()  # read in every mode
    # a number no mode has: a comparison with any named mode folds as for the others
    other = E.ModeVal("", min(m.number for m in model.modes) - 1)
    for e, where in _observed(model):
        inlined = inline(e, model)
        if not E.vars_read(inlined):
            continue
        named = _modes_compared(inlined)
        if named is None:  # the mode read otherwise: each mode on its own
            for m in out if where is None else [m for m in where if m in out]:
                out[m] |= E.vars_read(_fold_at(inlined, _mode_val(model, m)))
            continue
        for m in named & set(out if where is None else where) & out.keys():
            out[m] |= E.vars_read(_fold_at(inlined, _mode_val(model, m)))
        rest = E.vars_read(_fold_at(inlined, other))
        if not rest:  # `x == 3 && mode == M17` elsewhere: nothing
            continue
        if where is None and not named:
            everywhere |= rest
            continue
        for m in out if where is None else [m for m in where if m in out]:
            if m not in named:
                out[m] |= rest
    for m in out:
        out[m] |= everywhere
    return out


def _modes_compared(e: E.Expr) -> set[int] | None:
    """The modes `e` compares the current mode with (`mode == M`, `M != mode`); None if it
    reads the mode in any other way."""
    named: set[int] = set()
    seen = 0
    for n in E.walk(e):
        if isinstance(n, E.CurrentMode):
            seen += 1
        elif isinstance(n, E.Binary) and n.op in ("==", "!="):
            for a, b in ((n.left, n.right), (n.right, n.left)):
                if isinstance(a, E.CurrentMode) and isinstance(b, E.ModeVal):
                    named.add(b.number)
                    seen -= 1
    return named if seen == 0 else None


def _mode_val(model: ir.Model, mode: int) -> E.ModeVal:
    m = model.mode_by_number(mode)
    return E.ModeVal(m.name, m.number)


def _fold_at(inlined: E.Expr, mode: E.ModeVal) -> E.Expr:
    """An inlined expression in a state of `mode`, folded as far as that goes."""
    return fold(E.transform(inlined, lambda n: mode if isinstance(n, E.CurrentMode) else None))


def at_mode(e: E.Expr, mode: int, model: ir.Model) -> E.Expr:
    """`e` (formulas and labels inlined) in a state of `mode`, folded as far as that goes."""
    return _fold_at(inline(e, model), _mode_val(model, mode))


_CMP = {"==": lambda a, b: a == b, "!=": lambda a, b: a != b, "<": lambda a, b: a < b,
        "<=": lambda a, b: a <= b, ">": lambda a, b: a > b, ">=": lambda a, b: a >= b}


def _known(e: E.Expr) -> int | float | bool | None:
    if isinstance(e, E.Lit):
        return e.value
    if isinstance(e, E.ModeVal):
        return e.number
    return None


def _is(e: E.Expr, value: bool) -> bool:
    return isinstance(e, E.Lit) and e.type is E.Type.BOOL and e.value is value


def fold(e: E.Expr) -> E.Expr:
    """Fold what is known: comparisons of numbers and modes, connectives with a constant
    side, if-then-else on a constant condition."""
    def fn(n: E.Expr) -> E.Expr | None:
        if isinstance(n, E.Binary):
            a, b = _known(n.left), _known(n.right)
            if n.op in _CMP and a is not None and b is not None:
                return E.lit(bool(_CMP[n.op](a, b)))
            if n.op == "&&" and (_is(n.left, False) or _is(n.right, False)):
                return E.FALSE
            if n.op == "||" and (_is(n.left, True) or _is(n.right, True)):
                return E.TRUE
            if n.op in ("&&", "||"):
                unit = n.op == "&&"
                if _is(n.left, unit):
                    return n.right
                if _is(n.right, unit):
                    return n.left
            if n.op == "=>":
                if _is(n.left, False) or _is(n.right, True):
                    return E.TRUE
                if _is(n.left, True):
                    return n.right
            return None
        if isinstance(n, E.Unary) and n.op == "!" and isinstance(n.operand, E.Lit):
            return E.lit(not n.operand.value)
        if isinstance(n, E.Ite) and isinstance(n.cond, E.Lit):
            return n.then if n.cond.value else n.other
        return None

    return E.transform(e, fn)


def _reads(cmd: Command, model: ir.Model) -> set[str]:
    out = E.vars_read(inline(cmd.guard, model))
    for b in cmd.branches:
        out |= E.vars_read(inline(b.prob, model))
        for _, value in b.updates:
            out |= E.vars_read(inline(value, model))
    return out


def _targets(cmd: Command, branch: Branch) -> tuple[int, ...]:
    for var, value in branch.updates:
        if var == "mode":
            if isinstance(value, E.ModeVal):
                return (value.number,)
            return ()  # unknown: treated as "any mode" by the caller
    return cmd.modes


def live_variables(low: Lowered) -> dict[int, set[str]]:
    """For every mode, the variables that may be read before being written from there."""
    model = low.model
    everything = {v.name for v in model.variables}
    modes = [m.number for m in model.modes]
    reads = observable_by_mode(model, modes)
    for cmd in low.commands:
        r = _reads(cmd, model)
        for m in cmd.modes:
            reads[m] |= r
    live = {m: set(reads[m]) for m in modes}
    changed = True
    while changed:
        changed = False
        for cmd in low.commands:
            for b in cmd.branches:
                targets = _targets(cmd, b)
                after: set[str] = set(everything) if not targets else set().union(
                    *(live[t] for t in targets))
                written = {v for v, _ in b.updates}
                need = after - written
                for m in cmd.modes:
                    if not need <= live[m]:
                        live[m] |= need
                        changed = True
    return live


def dead_reset(low: Lowered) -> Lowered:
    model = low.model
    live = live_variables(low)
    init = {v.name: v.init for v in model.variables}
    order = {"mode": -1} | {v.name: i for i, v in enumerate(model.variables)}
    commands = []
    for cmd in low.commands:
        branches = []
        for b in cmd.branches:
            targets = _targets(cmd, b)
            if not targets:
                branches.append(b)
                continue
            alive = set().union(*(live[t] for t in targets))
            updates = dict(b.updates)
            for v in model.variables:
                if v.name in alive:
                    continue
                # Dead after this transition: pin it, unless it provably is already there.
                if updates.get(v.name) != E.lit(init[v.name]):
                    updates[v.name] = E.lit(init[v.name])
            new = tuple(sorted(updates.items(), key=lambda kv: order[kv[0]]))
            branches.append(replace(b, updates=new) if new != b.updates else b)
        commands.append(replace(cmd, branches=tuple(branches)))
    return replace(low, commands=tuple(commands))


# ---- variable order --------------------------------------------------------------------


def _order_key(v: ir.Variable, index: int, fields: dict[str, int]) -> tuple[int, int, int]:
    if v.type is E.Type.BOOL or (v.size <= 8 and "." not in v.display):
        return (0, index, 0)
    if "." in v.display:
        _group, field = v.display.split(".", 1)
        return (1, fields[field], index)
    return (2, v.size, index)


def reorder(low: Lowered) -> Lowered:
    model = low.model
    fields: dict[str, int] = {}
    for v in model.variables:
        if "." in v.display:
            fields.setdefault(v.display.split(".", 1)[1], len(fields))
    ranked = sorted(enumerate(model.variables), key=lambda iv: _order_key(iv[1], iv[0], fields))
    variables = tuple(v for _, v in ranked)
    if variables == model.variables:
        return low
    order = {"mode": -1} | {v.name: i for i, v in enumerate(variables)}
    new_model = replace(model, variables=variables)
    commands = tuple(
        replace(cmd, branches=tuple(
            replace(b, updates=tuple(sorted(b.updates, key=lambda kv: order[kv[0]])))
            for b in cmd.branches))
        for cmd in low.commands)
    return replace(low, model=new_model, commands=commands)


# ---- saturating counters -------------------------------------------------------------

def _step(var: str, value: E.Expr, model: ir.Model, generated: dict[str, tuple[str, int]],
          up: bool) -> E.Expr | None:
    """`k` if `value` is `var + k` (up) or `var - k` (down), possibly under the lowering's
    clamp at the range's own end (only for `clamp` variables: an author's `min`/`max` is
    kept and makes the variable no plain counter)."""
    if _clamped(var, value, model, generated, up):
        assert isinstance(value, E.Call)
        value = value.args[0]
    if isinstance(value, E.Binary) and isinstance(value.left, E.VarRef) \
            and value.left.name == var and value.op == ("+" if up else "-"):
        return value.right
    return None


def _clamped(var: str, value: E.Expr, model: ir.Model, generated: dict[str, tuple[str, int]],
             up: bool) -> bool:
    v = model.variable(var)
    func, end = ("min", v.hi) if up else ("max", v.lo)
    return (v.clamp and isinstance(value, E.Call) and value.func == func
            and len(value.args) == 2 and static(value.args[1], model, generated) == end)


# For `var OP c`: from which value on (up: upwards, down: downwards) the comparison stops
# changing, as an offset from c.
_UP = {"<": 0, "<=": 1, ">": 1, ">=": 0, "==": 1, "!=": 1}
_DOWN = {"<": -1, "<=": 0, ">": 0, ">=": -1, "==": -1, "!=": -1}
_FLIP = {"<": ">", "<=": ">=", ">": "<", ">=": "<=", "==": "==", "!=": "!="}


def _thresholds(var: str, exprs: list[E.Expr], model: ir.Model, up: bool) -> float | None:
    """The saturation point of `var`: beyond every boundary of its comparisons with
    constants, upwards or downwards; None if it is read in any other way."""
    v = model.variable(var)
    point = float(v.lo if up else v.hi)
    ok = True

    def visit(e: E.Expr) -> None:
        nonlocal point, ok
        if isinstance(e, E.Binary) and e.op in _FLIP:
            left, right, op = e.left, e.right, e.op
            if isinstance(right, E.VarRef) and right.name == var:
                left, right, op = right, left, _FLIP[op]
            if isinstance(left, E.VarRef) and left.name == var:
                c = static(right, model)
                if c is None or not math.isfinite(c) or c != int(c):
                    ok = False
                    return
                point = max(point, c + _UP[op]) if up else min(point, c + _DOWN[op])
                visit(right)
                return
        if isinstance(e, E.VarRef) and e.name == var:
            ok = False
            return
        for child in E.children(e):
            visit(child)

    for e in exprs:
        visit(e)
        if not ok:
            return None
    return point


def _monotone(var: str, updates: list[E.Expr], model: ir.Model,
              generated: dict[str, tuple[str, int]], up: bool) -> bool:
    """Every update moves `var` one way by a non-negative amount, or sets a constant."""
    for value in updates:
        k = _step(var, value, model, generated, up)
        if k is not None:
            k = inline(k, model)
            if bounds(k, model, None, generated)[0] < 0 or var in E.vars_read(k):
                return False
        elif static(value, model, generated) is None:
            return False
    return True


def saturation_points(low: Lowered) -> tuple[dict[str, tuple[bool, int]], list[str]]:
    """The counters that saturate: variable -> (upwards?, point), and their description."""
    model = low.model
    reads: dict[str, list[E.Expr]] = {v.name: [] for v in model.variables}
    exprs: list[E.Expr] = [inline(lb.value, model) for lb in model.labels]
    for r in model.rewards:
        exprs += [inline(x, model) for it in r.items for x in (it.guard, it.value)]
    for p in model.properties:
        exprs += [inline(x, model) for x in (getattr(p.path, "target", None),
                                             getattr(p.path, "left", None),
                                             getattr(p.path, "bound", None)) if x is not None]
    self_updates: dict[str, list[E.Expr]] = {v.name: [] for v in model.variables}
    for cmd in low.commands:
        exprs.append(inline(cmd.guard, model))
        for b in cmd.branches:
            exprs.append(inline(b.prob, model))
            for var, value in b.updates:
                if var != "mode":
                    self_updates[var].append(value)
                v_in = inline(value, model)
                for other in E.vars_read(v_in):
                    if other != var:
                        reads[other].append(v_in)
    done: list[str] = []
    saturated: dict[str, tuple[bool, int]] = {}  # var -> (upwards?, point)
    gen = low.bounds
    for v in model.variables:
        if v.type is not E.Type.INT or reads[v.name]:
            continue  # other variables' updates read it: its exact value matters
        for up in (True, False):
            if not _monotone(v.name, self_updates[v.name], model, gen, up):
                continue
            point = _thresholds(v.name, exprs, model, up)
            if point is None:
                continue
            if (up and v.init <= point < v.hi) or (not up and v.lo < point <= v.init):
                saturated[v.name] = (up, int(point))
                done.append(f"{v.display} {'at' if up else 'from'} {int(point)}")
                break
    return saturated, done


def capped(low: Lowered, saturated: dict[str, tuple[bool, int]], var: str,
           value: E.Expr) -> E.Expr:
    """An update of `var` to `value`, kept at its saturation point."""
    if var not in saturated:
        return value
    model, gen = low.model, low.bounds
    up, point = saturated[var]
    k = static(value, model, gen)
    if k is not None:
        return E.lit(int(min(k, point) if up else max(k, point)))
    if _clamped(var, value, model, gen, up):
        assert isinstance(value, E.Call)
        value = value.args[0]  # the clamp at the old end is subsumed
    return E.Call("min" if up else "max", (value, E.lit(point)), E.Type.INT)


def saturated_variables(model: ir.Model,
                        saturated: dict[str, tuple[bool, int]]) -> tuple[ir.Variable, ...]:
    variables = []
    for v in model.variables:
        if v.name in saturated:
            up, point = saturated[v.name]
            v = replace(v, hi=point) if up else replace(v, lo=point)
        variables.append(v)
    return tuple(variables)


def saturate(low: Lowered) -> tuple[Lowered, list[str]]:
    saturated, done = saturation_points(low)
    if not saturated:
        return low, []
    commands = tuple(replace(cmd, branches=tuple(
        replace(b, updates=tuple((var, capped(low, saturated, var, val))
                                 for var, val in b.updates))
        for b in cmd.branches)) for cmd in low.commands)
    variables = saturated_variables(low.model, saturated)
    return replace(low, model=replace(low.model, variables=variables),
                   commands=commands), done
