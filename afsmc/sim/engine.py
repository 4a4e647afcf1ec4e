"""Monte Carlo simulation of the lowered machine: a batch of runs advanced together.

Each step partitions the live runs by mode and evaluates only that mode's commands
(their guards already encode the weight semantics), folded for that mode. A run stops
once every property is decided for it, when it is absorbed (a final mode, a
deterministic self-loop, or no enabled command), or at `max_steps`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import numpy.typing as npt

from afsmc.diagnostics import Diagnostic
from afsmc.lower.lowering import Lowered
from afsmc.model import expr as E
from afsmc.model import ir
from afsmc.model.bounds import bounds
from afsmc.model.evaluate import scalar
from afsmc.sim import logs, rare, scheduler
from afsmc.sim.compile import Fn, Frame, Scope, SimError, compile_expr, fold, reads, static
from afsmc.sim.policy import Lookup
from afsmc.sim.stats import merge_moments

UNDECIDED, TRUE, FALSE = 0, 1, 2


@dataclass
class CBranch:
    prob: Fn
    prob_static: float | None
    updates: list[tuple[str, Fn]]
    hazard: str | None


@dataclass
class CCommand:
    index: int  # in Lowered.commands
    action: str  # "" for a final mode's self-loop
    guard: Fn
    guard_static: bool | None
    branches: list[CBranch]
    reads: list[str]  # variables to gather for this command
    selfloop: bool  # one branch with probability 1: unchanged state = absorbed
    rewards: list[tuple[int, Fn]]  # (reward structure index, value) for this action


@dataclass
class Monitor:
    """One property: P (status per run) or R (accumulated reward per run)."""

    name: str
    kind: str  # "P" or "R"
    path: str  # F G U X (P); F C I (R)
    bound: float  # math.inf if unbounded
    target: Fn | None
    left: Fn | None = None
    reward: int = -1  # reward structure index
    # R: every item of the structure is >= 0 in every state (interval bounds), so a run's
    # total is too and the mean's interval may be cut at 0
    nonneg: bool = False
    span: rare.Range = (-math.inf, math.inf)  # R: the interval a run's total lies in


@dataclass
class Program:
    model: ir.Model
    variables: list[str]
    displays: list[str]
    init: dict[str, Any]
    dtypes: dict[str, Any]
    modes: dict[int, list[CCommand]]
    mode_span: int  # modes are 0..mode_span-1 after shifting by mode_base
    mode_base: int
    monitors: list[Monitor]
    state_rewards: list[list[tuple[Fn, Fn]]]  # per structure: (guard, value)
    commands: list[Any]  # Lowered.commands
    # the check's warnings and notes on the model (sim.run.program sets them), for the CLI
    diagnostics: list[Diagnostic] = field(default_factory=list)
    # a strategy's command per state (simulate --strategy), else the first enabled command
    policy: Lookup | None = None
    # interval probabilities drawn once per run, uniform in [lo, hi] (simulate --at draw)
    draws: dict[str, tuple[float, float]] = field(default_factory=dict)
    # a composed MDP: each command's agents (afsmc.sim.scheduler picks who moves), and
    # how many agents there are; None: the first enabled command fires
    movers: dict[int, tuple[int, ...]] | None = None
    agents: int = 0
    # a composed mission's traces: each agent's (name, mode variable, mode names), and
    # each command's action in mission terms (afsmc.sim.scheduler.trace_names)
    agent_modes: list[tuple[str, str, dict[int, str]]] = field(default_factory=list)
    action_names: dict[int, str] = field(default_factory=dict)
    # (command, branch) -> its outcome and duration in the robot's log (afsmc.sim.logs)
    logged: dict[tuple[int, int], dict[str, Any]] = field(default_factory=dict)


def build(low: Lowered, draw: bool = False) -> Program:
    """The program of `low`; `draw`: each interval probability takes a value per run,
    drawn uniformly from its interval when the run starts (else its value, the midpoint
    or the end the caller fixed)."""
    model = low.model
    consts: dict[str, Any] = dict(model.const_values)
    for gen, (_, value) in low.bounds.items():
        consts[gen] = value
    draws = {c.name: (float(c.prob_interval[0]), float(c.prob_interval[1]))
             for c in model.prob_intervals if c.prob_interval is not None} if draw else {}
    formulas = {f.name: f.value for f in model.formulas}
    labels = {lb.name: lb.value for lb in model.labels}
    per_run = frozenset(draws)
    base = Scope(consts, formulas, labels, low.weights, per_run=per_run)
    reward_index = {r.name: i for i, r in enumerate(model.rewards)}
    movers = scheduler.movers(low)
    modes: dict[int, list[CCommand]] = {}
    for m in model.modes:
        sc = Scope(consts, formulas, labels, low.weights, m.number, per_run)
        cmds: list[CCommand] = []
        for i, cmd in enumerate(low.commands):
            if m.number not in cmd.modes:
                continue
            g = fold(cmd.guard, sc)
            if static(g) is False:
                continue
            branches = []
            read: set[str] = set(reads(g))
            for b in cmd.branches:
                p = fold(b.prob, sc)
                read |= reads(p)
                ups = []
                for var, val in b.updates:
                    fv = fold(val, sc)
                    read |= reads(fv)
                    read.add(var)
                    ups.append((var, compile_expr(fv)))
                ps = static(p)
                branches.append(CBranch(compile_expr(p), None if ps is None else float(ps),
                                        ups, b.hazard))
            rws: list[tuple[int, Fn]] = []
            if not cmd.silent:
                for r in model.rewards:
                    for it in r.items:
                        if it.action == cmd.action:
                            v = fold(E.Ite(it.guard, it.value, E.Lit(0, E.Type.INT), it.value.type), sc)
                            read |= reads(v)
                            rws.append((reward_index[r.name], compile_expr(v)))
            gs = static(g)
            # Where the scheduler picks who moves, an agent's move that leaves the state as
            # it is absorbs nothing (another agent may be picked next); only the mission's
            # own self-loop, where no agent can move, does.
            selfloop = len(branches) == 1 and branches[0].prob_static == 1.0 and (
                movers is None or cmd.silent)
            cmds.append(CCommand(i, "" if cmd.silent else cmd.action, compile_expr(g),
                                 None if gs is None else bool(gs), branches,
                                 sorted(read - {"mode"}), selfloop, rws))
        modes[m.number] = cmds
    numbers = [m.number for m in model.modes]
    state_rewards = [[(compile_expr(fold(it.guard, base)), compile_expr(fold(it.value, base)))
                      for it in r.items if it.action is None] for r in model.rewards]
    nonneg = [all(bounds(it.value, model, generated=low.bounds)[0] >= 0 for it in r.items)
              for r in model.rewards]
    steps = rare.step_bounds(model, low.bounds)
    monitors = [_monitor(p, base, model, reward_index, nonneg, steps) for p in model.properties]
    names = scheduler.trace_names(low)
    dtypes = {v.name: (np.bool_ if v.type is E.Type.BOOL else np.int64) for v in model.variables}
    shown = scheduler.displays(low)
    return Program(model, [v.name for v in model.variables],
                   [shown.get(v.name, v.display) for v in model.variables],
                   {v.name: v.init for v in model.variables}, dtypes, modes,
                   max(numbers) - min(numbers) + 1, min(numbers), monitors, state_rewards,
                   list(low.commands), draws=draws, movers=movers,
                   agents=0 if low.network is None else len(low.network.parts),
                   agent_modes=names[0], action_names=names[1], logged=logs.outcomes(low))


def _monitor(p: ir.Property, sc: Scope, model: ir.Model, rindex: dict[str, int],
             nonneg: list[bool], steps: list[rare.StepBounds]) -> Monitor:
    def bound(b: E.Expr | None) -> float:
        if b is None:
            return math.inf
        return float(scalar(fold(b, sc), {}))

    path = p.path
    if isinstance(path, ir.Path):
        left = compile_expr(fold(path.left, sc)) if path.left is not None else None
        return Monitor(p.name, "P", path.kind, bound(path.bound),
                       compile_expr(fold(path.target, sc)), left)
    target = compile_expr(fold(path.target, sc)) if path.target is not None else None
    rname = p.reward if p.reward is not None else (model.rewards[0].name if model.rewards else "")
    index = rindex.get(rname, -1)
    limit = bound(path.bound)
    return Monitor(p.name, "R", path.kind, limit, target, None, index,
                   index >= 0 and nonneg[index],
                   rare.run_range(path.kind, limit, steps[index] if index >= 0 else None))


@dataclass
class BatchResult:
    runs: int
    true: list[int]  # per monitor: runs where the property holds (P)
    undecided: list[int]
    total: list[float]  # per monitor: sum of rewards (R) over decided runs
    # R: sum of squared deviations from their mean (not the sum of squares: with rewards of
    # 3e9 +- 0.001, sum(x^2)/m - mean^2 cancels to noise of about 1e3)
    m2: list[float]
    infinite: list[int]  # R: runs with an infinite reward
    least: list[float]  # R: the smallest and the largest finite total of a decided run
    most: list[float]
    steps: int  # run-steps simulated
    max_steps_hit: int
    traces: list[list[dict[str, Any]]] = field(default_factory=list)


def _as_bool(v: Any, n: int) -> npt.NDArray[np.bool_]:
    a = np.asarray(v, dtype=bool)
    return np.broadcast_to(a, (n,)) if a.ndim == 0 else a


def _as_arr(v: Any, n: int) -> npt.NDArray[Any]:
    a = np.asarray(v)
    return np.broadcast_to(a, (n,)) if a.ndim == 0 else a


def simulate_batch(prog: Program, runs: int, rng: np.random.Generator, max_steps: int,
                   trace: int = 0) -> BatchResult:
    """Simulate `runs` runs of `prog` together for at most `max_steps` steps; keep the first
    `trace` runs' traces."""
    batch = _Batch(prog, runs, trace)
    for name, (lo, hi) in prog.draws.items():  # before any step: one value per run
        batch.state[name] = rng.uniform(lo, hi, runs)
    if batch.traces:
        batch.record(0)
    batch.retire(batch.observe(0, None))
    t = 0
    while len(batch.ids) and t < max_steps:
        batch.step(rng, t)
        t += 1
    return batch.result(runs)


_Updates = list[tuple[npt.NDArray[np.intp] | None, str, npt.NDArray[Any]]]
_Plan = list[tuple[CCommand, npt.NDArray[np.intp] | None]]


class _Batch:
    """The live runs of one batch (their state, and each monitor's status and accumulated
    reward per run) and the outcome of the runs already retired. Every per-run array holds
    the live runs only: a run leaves them once it is finished."""

    def __init__(self, prog: Program, n: int, trace: int) -> None:
        self.prog = prog
        self.state: dict[str, npt.NDArray[Any]] = {
            v: np.full(n, prog.init[v], dtype=prog.dtypes[v]) for v in prog.variables}
        self.state["mode"] = np.full(n, prog.model.initial_mode.number, dtype=np.int64)
        self.ids = np.arange(n)
        self.mons = prog.monitors
        nm = self.nm = len(self.mons)
        self.status = np.zeros((nm, n), dtype=np.int8)
        self.acc = np.zeros((nm, n), dtype=np.float64)
        # outcome collectors
        self.n_true = [0] * nm
        self.n_und = [0] * nm
        self.tot = [0.0] * nm
        self.m2 = [0.0] * nm
        self.n_fin = [0] * nm  # R: finite values so far, for merge_moments
        self.n_inf = [0] * nm
        self.least, self.most = [math.inf] * nm, [-math.inf] * nm
        self.absorbed = np.zeros(n, dtype=bool)
        self.traces: list[list[dict[str, Any]]] = [[] for _ in range(min(trace, n))]
        self.fired = np.full(n, -1, dtype=np.int64)
        self.branch = np.full(n, -1, dtype=np.int64)
        self.steps_done = 0
        self.has_rewards = any(mo.kind == "R" for mo in self.mons)

    def record(self, t: int) -> None:
        """Append step t to the trace of every traced run still live."""
        prog, state = self.prog, self.state
        sel = np.flatnonzero(self.ids < len(self.traces))
        for j in sel:
            rid = int(self.ids[j])
            cmd_i, br = int(self.fired[j]), int(self.branch[j])
            mode = ", ".join(f"{a}: {ms.get(int(state[v][j]), '?')}"
                             for a, v, ms in prog.agent_modes) \
                or prog.model.mode_by_number(int(state["mode"][j])).name
            entry: dict[str, Any] = {"step": t, "mode": mode}
            if t > 0 and cmd_i >= 0:
                c = prog.commands[cmd_i]
                entry["action"] = {"final": "(final)", "deadlock": "(no enabled action)"}.get(
                    c.kind, prog.action_names.get(cmd_i, c.action))
                hz = c.branches[br].hazard if 0 <= br < len(c.branches) else None
                if hz:
                    entry["hazard"] = hz
                entry.update(prog.logged.get((cmd_i, br), {}))
            elif t > 0:
                entry["action"] = "(no enabled action)"
            entry["vars"] = {d: _py(state[v][j]) for v, d in zip(prog.variables, prog.displays,
                                                                    strict=True)}
            self.traces[rid].append(entry)

    def state_reward(self, k: int, fr: Frame, size: int) -> npt.NDArray[np.float64]:
        """Reward structure k's state reward in each run of `fr`."""
        out = np.zeros(size)
        if k < 0:
            return out
        for g, v in self.prog.state_rewards[k]:
            out = out + np.where(_as_bool(g(fr), size), _as_arr(v(fr), size), 0.0)
        return out

    def observe(self, t: int, act_rw: npt.NDArray[np.float64] | None) -> npt.NDArray[np.bool_]:
        """Decide properties at step t (state s_t); return the runs that are finished."""
        size = len(self.ids)
        done = self.absorbed.copy() if t >= 1 else np.zeros(size, dtype=bool)
        all_decided = np.ones(size, dtype=bool)
        for k, mo in enumerate(self.mons):
            st = self.status[k]
            und = st == UNDECIDED
            if not und.any():
                continue
            if mo.kind == "P":
                self._observe_path(mo, st, und, t, size)
            else:
                self._observe_reward(k, mo, st, und, t, size, act_rw)
            all_decided &= st != UNDECIDED
        if self.nm:
            done |= all_decided
        return done

    def _observe_path(self, mo: Monitor, st: npt.NDArray[np.int8], und: npt.NDArray[np.bool_],
                      t: int, size: int) -> None:
        """Decide a P monitor's undecided runs where step t decides them."""
        absorbed = self.absorbed
        tgt = _as_bool(mo.target(self.state), size) if mo.target else None
        assert tgt is not None
        if mo.path == "F" or mo.path == "U":
            st[und & tgt] = TRUE
            if mo.path == "U":
                assert mo.left is not None
                st[und & ~tgt & ~_as_bool(mo.left(self.state), size)] = FALSE
            st[(st == UNDECIDED) & ((t >= mo.bound) | absorbed)] = FALSE
        elif mo.path == "G":
            st[und & ~tgt] = FALSE
            st[(st == UNDECIDED) & ((t >= mo.bound) | absorbed)] = TRUE
        elif mo.path == "X" and t == 1:
            st[und] = np.where(tgt[und], TRUE, FALSE)

    def _observe_reward(self, k: int, mo: Monitor, st: npt.NDArray[np.int8],
                        und: npt.NDArray[np.bool_], t: int, size: int,
                        act_rw: npt.NDArray[np.float64] | None) -> None:
        """Decide an R monitor's undecided runs where step t decides them, and settle their
        accumulated reward."""
        absorbed, acc = self.absorbed, self.acc
        rho = self.state_reward(mo.reward, self.state, size)
        if mo.path == "I":
            hit = und & ((t >= mo.bound) | absorbed)
            acc[k][hit] = rho[hit]
            st[hit] = TRUE
        elif mo.path == "F":
            assert mo.target is not None
            tgt = _as_bool(mo.target(self.state), size)
            st[und & tgt] = TRUE
            inf = (st == UNDECIDED) & absorbed
            acc[k][inf] = math.inf
            st[inf] = TRUE
        else:  # C, C<=k
            per = rho + (act_rw[k] if act_rw is not None else 0.0)
            hit = und & (t >= mo.bound)
            st[hit] = TRUE
            ab = (st == UNDECIDED) & absorbed
            if ab.any():
                if math.isinf(mo.bound):
                    acc[k][ab] = np.where(per[ab] > 0, math.inf, acc[k][ab])
                else:
                    acc[k][ab] += per[ab] * (mo.bound - t)
                st[ab] = TRUE

    def accumulate_rewards(self, fr_rho: list[npt.NDArray[np.float64]],
                           act_rw: npt.NDArray[np.float64], t: int) -> None:
        for k, mo in enumerate(self.mons):
            if mo.kind != "R" or mo.path == "I":
                continue
            und = self.status[k] == UNDECIDED
            if mo.path == "C" and not t < mo.bound:
                continue
            self.acc[k][und] += fr_rho[k][und] + act_rw[k][und]

    def _count(self, k: int, st: npt.NDArray[np.int8], acc: npt.NDArray[np.float64]) -> None:
        """Add finished runs (their statuses and accumulated rewards) to monitor k's outcome."""
        self.n_und[k] += int(np.count_nonzero(st == UNDECIDED))
        if self.mons[k].kind == "P":
            self.n_true[k] += int(np.count_nonzero(st == TRUE))
        else:
            vals = acc[st != UNDECIDED]
            inf = np.isinf(vals)
            self.n_inf[k] += int(np.count_nonzero(inf))
            merge_moments(self.n_fin, self.tot, self.m2, k, vals[~inf])
            if np.any(~inf):
                self.least[k] = min(self.least[k], float(np.min(vals[~inf])))
                self.most[k] = max(self.most[k], float(np.max(vals[~inf])))

    def retire(self, done: npt.NDArray[np.bool_]) -> None:
        """Count the finished runs and drop them from the live arrays."""
        if not done.any():
            return
        for k in range(self.nm):
            self._count(k, self.status[k][done], self.acc[k][done])
        keep = ~done
        self.ids = self.ids[keep]
        self.status = self.status[:, keep]
        self.acc = self.acc[:, keep]
        self.absorbed = self.absorbed[keep]
        self.fired = self.fired[keep]
        self.branch = self.branch[keep]
        self.state = {k: v[keep] for k, v in self.state.items()}

    def step(self, rng: np.random.Generator, t: int) -> None:
        """Advance every live run from step t to t + 1, then observe and retire."""
        prog, state, mons = self.prog, self.state, self.mons
        size = len(self.ids)
        rhos = [self.state_reward(mo.reward, state, size) if mo.kind == "R" else np.zeros(0)
                for mo in mons]
        act_rw = np.zeros((self.nm, size))
        new_absorbed = np.zeros(size, dtype=bool)
        mode = state["mode"]
        counts = np.bincount(mode - prog.mode_base, minlength=prog.mode_span)
        present = np.flatnonzero(counts) + prog.mode_base
        updates: _Updates = []
        for m_np in present:
            m = int(m_np)
            idx: npt.NDArray[np.intp] | None = None if counts[m - prog.mode_base] == size \
                else np.flatnonzero(mode == m)
            for c, local in self._plan(m, idx, size, new_absorbed, rng):
                gidx = idx if local is None else (local if idx is None else idx[local])
                self._fire(c, m, gidx, size, rng, act_rw, new_absorbed, updates)
        # Updates are applied after every partition was evaluated on the old state.
        for gidx, var, val in updates:
            if gidx is None:
                state[var] = np.array(np.broadcast_to(val, (size,)), dtype=state[var].dtype)
            else:
                state[var][gidx] = val
        if self.has_rewards:
            self.accumulate_rewards(rhos, act_rw, t)
        self.steps_done += size
        t += 1
        self.absorbed |= new_absorbed
        for fm in prog.model.modes:
            if fm.final:
                self.absorbed |= state["mode"] == fm.number
        if self.traces:
            self.record(t)
        # Once absorbed by a self-loop, its action reward recurs every step.
        self.retire(self.observe(t, act_rw * new_absorbed))

    def _plan(self, m: int, idx: npt.NDArray[np.intp] | None, size: int,
              new_absorbed: npt.NDArray[np.bool_], rng: np.random.Generator) -> _Plan:
        """Which command each run in mode m (all runs if `idx` is None) fires: the first
        enabled one (a composed MDP: the scheduler's pick). Each command with the runs that fire it (None: all of `idx`); runs
        with none enabled are marked absorbed."""
        nmode = size if idx is None else len(idx)
        cmds = self.prog.modes.get(m, [])
        if len(cmds) == 1 and cmds[0].guard_static is True:
            return [(cmds[0], None)]  # everyone fires cmds[0]
        sub = _gather(self.state, idx, set().union(*[c.reads for c in cmds]) if cmds else set())
        sub["mode"] = m
        which = np.full(nmode, -1, dtype=np.int64)
        movers = self.prog.movers
        if movers is not None:
            enabled = [_as_bool(c.guard(sub), nmode) for c in cmds]
            which = scheduler.pick(enabled, [movers.get(c.index, ()) for c in cmds],
                                   self.prog.agents, rng)
        for ci in range(len(cmds) - 1, -1, -1) if movers is None else ():
            g = cmds[ci].guard(sub)
            if np.ndim(g) == 0:
                if g:
                    which[:] = ci
            else:
                which[g] = ci
        if self.prog.policy is not None:
            chosen = self.prog.policy.command(self.state, m, idx, size)
            for ci, c in enumerate(cmds):
                which[chosen == c.index] = ci
        stuck = which < 0
        if stuck.any():  # no enabled action: the run stays put (absorbed)
            where_stuck = np.flatnonzero(stuck) if idx is None else idx[stuck]
            new_absorbed[where_stuck] = True
            if self.traces:
                self.fired[where_stuck] = -1
        plan: _Plan = []
        for ci, c in enumerate(cmds):
            sel = which == ci
            cnt = int(np.count_nonzero(sel))
            if cnt == 0:
                continue
            plan.append((c, None if cnt == nmode else np.flatnonzero(sel)))
        return plan

    def _fire(self, c: CCommand, m: int, gidx: npt.NDArray[np.intp] | None, size: int,
              rng: np.random.Generator, act_rw: npt.NDArray[np.float64],
              new_absorbed: npt.NDArray[np.bool_], updates: _Updates) -> None:
        """Fire command c in the runs `gidx` (all if None), which are in mode m: add its
        action rewards, draw a branch per run, and queue the branch's updates."""
        cnt = size if gidx is None else len(gidx)
        fr = _gather(self.state, gidx, c.reads)
        fr["mode"] = m
        if self.traces:
            if gidx is None:
                self.fired[:] = c.index
            else:
                self.fired[gidx] = c.index
        for k, v in c.rewards:
            for j, mo in enumerate(self.mons):
                if mo.reward == k and mo.kind == "R":
                    if gidx is None:
                        act_rw[j] += _as_arr(v(fr), cnt)
                    else:
                        act_rw[j][gidx] += _as_arr(v(fr), cnt)
        choice = _choose(c, fr, cnt, rng)
        if self.traces:
            if gidx is None:
                self.branch[:] = 0 if choice is None else choice
            else:
                self.branch[gidx] = 0 if choice is None else choice
        new = _next_values(c, fr, choice)
        if c.selfloop:
            same = np.ones(cnt, dtype=bool)
            for var, val in new.items():
                old = m if var == "mode" else fr[var]
                same &= np.asarray(np.equal(val, old), dtype=bool)
            if gidx is None:
                new_absorbed |= same
            else:
                new_absorbed[gidx] |= same
        for var, val in new.items():
            updates.append((gidx, var, val))

    def result(self, runs: int) -> BatchResult:
        """Count the runs still live (they hit `max_steps`) and return the outcome."""
        hit = len(self.ids)
        for k in range(self.nm):
            self._count(k, self.status[k], self.acc[k])
        return BatchResult(runs, self.n_true, self.n_und, self.tot, self.m2, self.n_inf,
                           self.least, self.most, self.steps_done, hit, self.traces)


def _choose(c: CCommand, fr: Frame, cnt: int,
            rng: np.random.Generator) -> npt.NDArray[np.int64] | None:
    """The branch of c each of `cnt` runs takes; None when c has one branch."""
    if len(c.branches) == 1:
        return None
    u = rng.random(cnt)
    choice = np.zeros(cnt, dtype=np.int64)
    cum: Any = 0.0
    for b in c.branches[:-1]:
        cum = cum + b.prob(fr)
        choice += u >= cum
    return choice


def _next_values(c: CCommand, fr: Frame,
                 choice: npt.NDArray[np.int64] | None) -> dict[str, Any]:
    """The value each variable that c's branches update takes in each run, by its branch."""
    new: dict[str, Any] = {}
    for bi, b in enumerate(c.branches):
        for var, f in b.updates:
            val = f(fr)
            if isinstance(val, np.ndarray) and val.dtype.kind == "f" and np.isnan(val).any():
                # (a division or mod by zero: NaN, see afsmc.model.kernel; the checks' E306
                # refuses a model where one is used)
                raise SimError(f"the update of {var} is undefined (a division by zero) in a run")
            if choice is None:
                new[var] = val
            else:
                old = new.get(var)
                if old is None:
                    old = fr["mode"] if var == "mode" else fr[var]
                new[var] = np.where(choice == bi, val, old)
    return new


def _gather(state: dict[str, npt.NDArray[Any]], idx: npt.NDArray[np.intp] | None,
            names: Any) -> dict[str, Any]:
    if idx is None:
        return {v: state[v] for v in names}
    return {v: state[v][idx] for v in names}


def _py(v: Any) -> Any:
    return v.item() if isinstance(v, np.generic) else v


__all__ = ["BatchResult", "Program", "SimError", "build", "simulate_batch"]
