"""An oracle for the generated controllers: the reachable states of a mission and the
action the model takes in each, enumerated from the lowering (its guarded commands, whose
complete guards say which action fires) with afsmc's own evaluator, breadth first. It
shares nothing with the generators but the IR they both read."""

from __future__ import annotations

from typing import Any

import numpy as np

from afsmc.lower.lowering import Lowered
from afsmc.model.evaluate import Env, evaluate

State = tuple[int, ...]  # (mode number, each variable in the model's order)


def _env(low: Lowered, frontier: list[State]) -> Env:
    model = low.model
    cols = np.array(frontier, dtype=np.int64).T
    consts: dict[str, Any] = dict(model.const_values)
    consts.update({gen: value for gen, (_, value) in low.bounds.items()})
    env = Env(vars={v.name: cols[i + 1].astype(bool) if v.type.value == "bool" else cols[i + 1]
                    for i, v in enumerate(model.variables)},
              mode=cols[0], consts=consts,
              formulas={f.name: f.value for f in model.formulas},
              labels={lb.name: lb.value for lb in model.labels})
    env.weight = lambda name: _vec(evaluate(low.weights[name], env), len(frontier))
    return env


def _vec(v: Any, n: int) -> Any:
    a = np.asarray(v)
    return np.broadcast_to(a, (n,)) if a.ndim == 0 else a


def reachable(low: Lowered, limit: int = 200_000) -> dict[State, str | None]:
    """Every reachable state -> the action that fires there (None: a final mode, or a
    state where no action is enabled). Raises if there are more than `limit` states."""
    model = low.model
    init: State = (model.initial_mode.number,
                   *(int(v.init) for v in model.variables))
    names = ["mode", *(v.name for v in model.variables)]
    seen: dict[State, str | None] = {}
    frontier = [init]
    queued = {init}
    while frontier:
        env = _env(low, frontier)
        n = len(frontier)
        chosen: list[set[str]] = [set() for _ in range(n)]
        nxt: list[State] = []
        for cmd in low.commands:
            env.memo.clear()
            fires = _vec(evaluate(cmd.guard, env), n).astype(bool)
            if not fires.any():
                continue
            for i in np.flatnonzero(fires):
                chosen[i].add("" if cmd.silent else cmd.action)
            for b in cmd.branches:
                prob = _vec(evaluate(b.prob, env), n)
                live = fires & (prob > 0)
                if not live.any():
                    continue
                cols = {k: _vec(env.mode if k == "mode" else env.vars[k], n) for k in names}
                for var, value in b.updates:
                    cols[var] = _vec(evaluate(value, env), n)
                rows = np.stack([np.asarray(cols[k], dtype=np.int64) for k in names], axis=1)
                nxt += [tuple(int(x) for x in r) for r in rows[live]]
        for s, acts in zip(frontier, chosen, strict=True):
            acts.discard("")
            assert len(acts) <= 1, f"the lowering fires {acts} in {s}"
            seen[s] = next(iter(acts)) if acts else None
        frontier = []
        for s in nxt:
            if s not in queued:
                queued.add(s)
                frontier.append(s)
        if len(queued) > limit:
            raise AssertionError(f"{model.name} has more than {limit} reachable states")
    return seen
