"""Split a simulation into fixed-size batches, run them (here, in worker processes or on
a Dask cluster) and combine the counts into estimates with confidence intervals.

The batches and their seeds (`numpy.random.SeedSequence(seed).spawn`) depend only on
the seed, the number of runs and the batch size, and results are combined in batch
order, so an estimate never depends on how many workers computed it.
"""

from __future__ import annotations

import dataclasses
import math
import os
import sys
import time
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from typing import Any, Literal

import numpy as np

from afsmc.compiler import load
from afsmc.interrupt import Stopped
from afsmc.lifetime import die_with_parent, worker_died
from afsmc.lower.lowering import lower
from afsmc.model import ir
from afsmc.sim import rare, stats
from afsmc.sim.compile import SimError
from afsmc.sim.engine import BatchResult, Program, build, simulate_batch
from afsmc.sim.policy import Lookup, Table
from afsmc.sim.stats import merge_moments

Strategy = Literal["uniform", "floor", "ceil", "lo", "hi"]
STRATEGIES: tuple[Strategy, ...] = ("uniform", "floor", "ceil", "lo", "hi")
# lo/hi as `compile --resolve` spells them. No "min"/"max": a simulation follows one fixed
# strategy and cannot find the MDP's optimum (the floor is no minimum: on patrol.afsm it
# gives the higher probability, so a "min" strategy would estimate Pmax).
LOWERING = {"uniform": "uniform", "floor": "lo", "ceil": "hi", "lo": "lo", "hi": "hi"}
BATCH = 65_536
# Every batch's seed is made before the runs, and a batch holds each variable of each of
# its runs in memory: `simulate --runs 10^14` grew without a word until memory ran out.
MAX_BATCHES = 100_000  # 1.2 s and 40 MB of seeds
MAX_BATCH_SIZE = 1_000_000


@dataclass(frozen=True)
class Job:
    """Everything a worker needs: the source text travels, not the path."""

    path: str
    text: str
    overrides: tuple[tuple[str, str], ...]
    strategy: str
    max_steps: int
    # interval probabilities: drawn once per run, uniform in the interval ("draw"), or every
    # run at their midpoint ("mid"), lower ("min") or upper ("max") end
    at: str = "draw"
    policy: Table | None = None  # a scheduler to follow (strategy is then ignored)


def fix_prob_intervals(model: ir.Model, at: str) -> ir.Model:
    """`model` with each interval probability at one end, or at its midpoint (its value;
    also for "draw", whose runs draw their own)."""
    if at in ("mid", "draw") or not model.prob_intervals:
        return model
    consts = tuple(dataclasses.replace(c, value=c.prob_interval[0 if at == "min" else 1])
                   if c.prob_interval is not None else c for c in model.constants)
    return dataclasses.replace(model, constants=consts)


@dataclass
class Estimate:
    name: str
    kind: str  # P or R
    estimate: float
    low: float
    high: float
    undecided: int
    no_spread: bool = False  # R: fewer than two runs finished, so no interval from a variance
    # how the interval was made (afsmc.sim.rare: clopper-pearson, normal, range, one-sided),
    # and why, when it is not the usual one of its kind
    method: str = rare.NORMAL
    reason: str = ""


@dataclass
class Outcome:
    runs: int
    estimates: list[Estimate]
    steps: int
    seconds: float
    traces: list[list[dict[str, Any]]] = field(default_factory=list)
    batches: int = 0


_PROGRAMS: dict[Job, Program] = {}
# (lifetime.worker_died)
_DIED = "a worker process died before it finished (was it killed, or out of memory?)"


def program(job: Job) -> Program:
    """Compile once per process (workers keep it between batches)."""
    prog = _PROGRAMS.get(job)
    if prog is None:
        checked = load(job.path, dict(job.overrides), text=job.text)
        model = fix_prob_intervals(checked.model, job.at)
        draw = job.at == "draw"
        if job.policy is not None:
            prog = build(lower(model, "nondet"), draw)
            prog.policy = Lookup(job.policy, model)
        else:
            prog = build(lower(model, LOWERING[job.strategy]), draw)  # type: ignore[arg-type]
        prog.diagnostics = checked.diagnostics
        _PROGRAMS.clear()
        _PROGRAMS[job] = prog
    return prog


def run_batch(job: Job, runs: int, seed: np.random.SeedSequence, trace: int) -> BatchResult:
    return simulate_batch(program(job), runs, np.random.default_rng(seed), job.max_steps, trace)


def batch_count(runs: int, size: int) -> int:
    return max(1, -(-runs // size))  # integers: math.ceil(runs / size) rounds above 2^53


def batches(runs: int, seed: int, size: int = BATCH) -> list[tuple[int, np.random.SeedSequence]]:
    count = batch_count(runs, size)
    seeds = np.random.SeedSequence(seed).spawn(count)
    return [(min(size, runs - i * size), seeds[i]) for i in range(count)]


def simulate(job: Job, runs: int, seed: int, *, confidence: float = 0.999, jobs: int = 1,
             dask: str | Any | None = None, trace: int = 0, batch_size: int = BATCH,
             progress: Callable[[int, int], None] | None = None) -> Outcome:
    prog = program(job)  # compile errors surface here, before any worker starts
    plan = batches(runs, seed, batch_size)
    started = time.monotonic()
    results: list[BatchResult | None] = [None] * len(plan)
    done = 0

    def finished(i: int, r: BatchResult) -> None:
        nonlocal done
        results[i] = r
        done += r.runs
        if progress:
            progress(done, runs)

    def outcome() -> Outcome:
        res = [r for r in results if r is not None]
        return Outcome(sum(r.runs for r in res), combine(prog, res, confidence),
                       sum(r.steps for r in res), time.monotonic() - started,
                       res[0].traces if res else [], len(plan))

    try:
        if dask is not None:
            _on_dask(dask, job, plan, trace, finished)
        elif jobs > 1 and len(plan) > 1:
            _on_pool(jobs, job, plan, trace, finished)
        else:
            for i, (n, s) in enumerate(plan):
                finished(i, simulate_batch(prog, n, np.random.default_rng(s), job.max_steps,
                                           trace if i == 0 else 0))
    except KeyboardInterrupt as exc:
        if done:  # the batches that finished are an estimate of their own (the CLI shows it)
            raise Stopped(partial=outcome()) from exc
        raise
    return outcome()


Plan = list[tuple[int, np.random.SeedSequence]]
Finished = Callable[[int, BatchResult], None]


def _on_dask(dask: str | Any, job: Job, plan: Plan, trace: int, finished: Finished) -> None:
    from distributed import Client  # optional: only when --dask is used

    client = dask if isinstance(dask, Client) else Client(dask)  # type: ignore[no-untyped-call]
    try:
        futures = [client.submit(run_batch, job, n, s, trace if i == 0 else 0, pure=False)
                   for i, (n, s) in enumerate(plan)]
        index = {f.key: i for i, f in enumerate(futures)}
        from distributed import as_completed

        try:
            for fut in as_completed(futures):  # type: ignore[no-untyped-call]
                finished(index[fut.key], fut.result())
        except Exception as exc:
            if not worker_died(exc):
                raise
            raise SimError(_DIED) from None
    finally:
        if not isinstance(dask, Client):
            client.close()  # type: ignore[no-untyped-call]


def _on_pool(jobs: int, job: Job, plan: Plan, trace: int, finished: Finished) -> None:
    import multiprocessing
    from concurrent.futures import ProcessPoolExecutor, as_completed

    ctx = multiprocessing.get_context("fork" if sys.platform == "linux" else "spawn")
    pool = ProcessPoolExecutor(max_workers=jobs, mp_context=ctx, initializer=die_with_parent,
                               initargs=(os.getpid(),))
    try:
        futs = {pool.submit(run_batch, job, n, s, trace if i == 0 else 0): i
                for i, (n, s) in enumerate(plan)}
        try:
            for f in as_completed(futs):
                finished(futs[f], f.result())
        except Exception as exc:
            if not worker_died(exc):
                raise
            raise SimError(_DIED) from None
    except BaseException:
        # A Ctrl-C (or SIGTERM, to afsmc alone) stops the workers now: leaving a pool's
        # `with` would run every batch still queued first.
        for proc in list(getattr(pool, "_processes", {}).values()):
            proc.terminate()
        pool.shutdown(wait=False, cancel_futures=True)
        raise
    pool.shutdown()


def combine(prog: Program, results: list[BatchResult], confidence: float) -> list[Estimate]:
    n = sum(r.runs for r in results)
    out = []
    for k, mo in enumerate(prog.monitors):
        und = sum(r.undecided[k] for r in results)
        if mo.kind == "P":
            s = sum(r.true[k] for r in results)
            low, _ = stats.clopper_pearson(s, n, confidence)
            # Undecided runs may go either way: the interval covers both outcomes.
            _, high = stats.clopper_pearson(s + und, n, confidence)
            out.append(Estimate(mo.name, "P", s / n if n else 0.0, low, high, und,
                                method=rare.CLOPPER_PEARSON))
            continue
        inf = sum(r.infinite[k] for r in results)
        m = n - und - inf
        count, sums, m2 = [0], [0.0], [0.0]
        for r in results:  # the batches' moments, merged in batch order (deterministic)
            merge_moments(count, sums, m2, 0,
                          (r.runs - r.undecided[k] - r.infinite[k], r.total[k], r.m2[k]))
        total = sums[0]
        if inf:
            out.append(Estimate(mo.name, "R", math.inf, math.inf, math.inf, und))
            continue
        mean = total / m if m else math.nan  # no run got a value: nothing to estimate
        floor = 0.0 if mo.nonneg else -math.inf  # no reward below 0: neither is the mean
        if m < 2:
            # A sample variance needs two values: one run says nothing about the spread.
            out.append(Estimate(mo.name, "R", mean, floor, math.inf, und, no_spread=True))
            continue
        least = min(r.least[k] for r in results)
        if least == max(r.most[k] for r in results):
            # No run differed: no spread to measure, and a rare event unseen (rare.py).
            low, high, method, why = rare.no_variation(least, m, mo.span, confidence)
            out.append(Estimate(mo.name, "R", mean, max(low, floor),
                                math.inf if und else high, und, method=method, reason=why))
            continue
        var = m2[0] / (m - 1)
        z = stats.normal_quantile(0.5 + confidence / 2)
        half = z * math.sqrt(var / m)
        # An undecided run's reward is only known to be at least its partial sum.
        out.append(Estimate(mo.name, "R", mean, max(mean - half, floor),
                            math.inf if und else mean + half, und))
    return out


def job_for(path: str, text: str, overrides: Mapping[str, str], strategy: str,
            max_steps: int, at: str = "draw") -> Job:
    return Job(path, text, tuple(sorted(overrides.items())), strategy, max_steps, at)
