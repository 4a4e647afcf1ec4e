"""One lowered model checked: :class:`ModelLoop` runs the Storm processes that answer its
queries (the MDP, its uniform DTMC, or the only DTMC), one unit of queries per process, and
revises the plan as processes answer, fail, or "auto" picks its engine. Its answers, stats
and errors go into the :class:`afsmc.verify.core.runner.CheckRun` of the call.
"""

from __future__ import annotations

import dataclasses
import functools
import time

from afsmc.backends.prism import emit as prism_emit
from afsmc.backends.prism import property_variants
from afsmc.diagnostics import CompileError, Diagnostic
from afsmc.interrupt import Stopped
from afsmc.lower.lowering import Lowered
from afsmc.model import ir
from afsmc.verify.core import conditioning
from afsmc.verify.core.runner import IN_PROCESS_WORK, CheckRun, so_far
from afsmc.verify.engines.explicit import applies
from afsmc.verify.engines.failures import (
    after_failure,
    failure_diagnostic,
    one_query,
    refuse_symbolic,
    symbolic_gap,
)
from afsmc.verify.engines.guard import (
    Interrupted,
    default_max_states,
    mem_available,
    run_job,
)
from afsmc.verify.engines.jobs import make_job, unfair
from afsmc.verify.engines.storm import (
    DD_MEMORY_RETRY,
    Job,
    JobResult,
    StormFailure,
)
from afsmc.verify.outcome.results import (
    ModelStats,
    add_runs,
    stats_of,
)
from afsmc.verify.outcome.strategy import request, stepped
from afsmc.verify.plan.queries import (
    REST,
    TERMINATES,
    Query,
    not_failed,
    rewrite,
    steps,
    unanswered,
    unit_text,
)
from afsmc.verify.stream.route import where


class ModelLoop:
    """The Storm processes that check one lowered model: `units` is the plan (the queries
    of each process), revised as processes answer, fail, or "auto" picks its engine."""

    def __init__(self, run: CheckRun, resolution: str, low: Lowered, what: str) -> None:
        self.run, self.resolution, self.low, self.what = run, resolution, low, what
        queries = [(p, n) for p in run.props for n, _ in property_variants(low, p)]
        run.model_queries.append([n for _, n in queries])
        self.by_name = {n: (p, n) for p, n in queries}
        self.use = run.comp if low.kind == "mdp" else {}
        # query -> its property's name (a complementary Pmin: that of the Pmax it gives)
        self.owner = {n: p.name for p, n in queries} | {
            self.use[n].name: p.name for p, n in queries if n in self.use}
        self.merged: ModelStats | None = None
        self.vals: dict[str, float] = {}
        self.secs: dict[str, float] = {}
        given = run.beside.pop(resolution, None)
        if given is not None:  # answered beside an earlier model: only the rest are asked
            self.vals, self.secs, self.merged = dict(given[0]), dict(given[1]), given[2]
            queries = [q for q in queries if q[1] not in self.vals]
        self.units = self.plan(queries, run.engine == "hybrid")
        self.i = 0  # the unit of the next process
        self.job_engine = run.engine
        # Once the guard reran one complementary Pmin query with full tables, the later ones
        # start with them: they share their shape, Pmin [F final & !target] (on scenario 1
        # three of five outgrew 1 GB, 43-144 s into their processes). The other queries keep
        # the default: the expected rewards' minimum needs it to stay under 20 GB.
        self.rest_full_tables = False
        # processes that failed after answering some queries: their time counts as checking
        self.lost, self.lost_processes = 0.0, 0
        # The model's sizes as a failed process reported them, should no process succeed
        # (their times are all in `lost`, counted as checking).
        self.built: ModelStats | None = None
        self.failed: set[str] = set()  # queries whose check failed (in `run.errors`)
        # Pmax -> its complementary Pmin, while a Pmax may still be answered that way (not
        # after termination is known: a Pmax asked then is asked itself)
        self.pending = self.use
        self.rest_errors: dict[str, Diagnostic] = {}  # a complementary Pmin's error

    def plan(self, qs: list[Query], hybrid: bool) -> list[list[Query]]:
        """Queries -> Storm processes. Hybrid: each Pmax as 1 - the complementary Pmin;
        the expected rewards in one process, with small decision-diagram tables (their
        minimum needs the most explicit memory: 18.8 GB on scenario 1), the probabilities
        in another, with large tables (their complementary targets need them)."""
        split = self.run.options.given.split
        if not hybrid:
            return [[q] for q in qs] if split and len(qs) > 1 else [qs] if qs else []
        if split:
            return [[q] for q in rewrite(qs, self.use)]
        rewards = [q for q in qs if q[0].kind != "P"]
        probabilities = rewrite([q for q in qs if q[0].kind == "P"], self.use)
        return [u for u in (rewards, probabilities) if u]

    def sizes(self, res: JobResult, known: ModelStats | None) -> ModelStats | None:
        """The model's sizes from a failed process, if not known yet and it reported any."""
        if known is not None or not res.states:
            return known
        return dataclasses.replace(stats_of(res, self.resolution), parse_time=0.0,
                                   build_time=0.0, check_time=0.0, processes=0)

    def check_all(self) -> None:
        """Run the plan to its end; adds the model's stats, answers and times to `run`."""
        while True:
            if self.i == len(self.units) and (TERMINATES in self.vals
                                              or TERMINATES in self.failed):
                self.settle_termination()
            if self.i == len(self.units):
                break
            self.step()
        # merged is None only when every process failed (then `errors`): the sizes a
        # failed one reported, if any
        merged = self.merged or self.built
        self.run.stats.append(None if merged is None else dataclasses.replace(
            merged, check_time=merged.check_time + self.lost,
            processes=merged.processes + self.lost_processes))
        self.run.values.append(self.vals)
        self.run.timings.append(self.secs)

    def settle_termination(self) -> None:
        """Pmax = 1 - Pmin of the rest, if every path ends; else (or if that could not be
        checked) ask Pmax itself, one process each (the hybrid engine only asks these)."""
        ends = self.vals.pop(TERMINATES, None) == 1.0
        self.failed.discard(TERMINATES)
        self.secs.pop(TERMINATES, None)  # a graph analysis, shared by every Pmax
        self.pending = {}
        if not ends:  # the complements are not used: nor are their errors
            self.run.errors[:] = [d for d in self.run.errors
                                  if d not in self.rest_errors.values()]
        direct = []
        for name, rest in self.use.items():
            if name == TERMINATES or name in self.failed:
                continue
            v, t = self.vals.pop(rest.name, None), self.secs.pop(rest.name, 0.0)
            if ends and v is not None:
                self.vals[name], self.secs[name] = 1.0 - v, t
            elif not ends and name in self.by_name:
                direct.append(self.by_name[name])
            # else the Pmin failed: its error says so (Pmax needs more memory still)
        if ends and self.run.progress is not None:
            self.run.progress(f"every path of the {self.what} ends in a final mode: each "
                              "Pmax [F target] is 1 - Pmin [F (final & !target)], which "
                              "needs less memory")
        self.units += [[q] for q in direct]

    def step(self) -> None:
        """One Storm process: the unit `units[i]`, then the plan revised by its outcome."""
        unit = self.units[self.i]
        if self.job_engine == "hybrid":
            kept = self.without_symbolic_gaps(unit)
            if kept is None:
                self.i += 1
                return
            unit = kept
        group = list(dict.fromkeys(p for p, _ in unit))
        job, complementary, big_tables = self.job_for(unit, group)
        fresh = self.fresh_process(group)
        progress = self.run.progress
        if progress is not None and len(self.units) > 1:
            # Long runs (scenario 1: over an hour) say how far they are.
            where = ("in its own Storm process" if len(unit) == 1 else
                     "in one Storm process" + (f" with {job.dd_memory_mb} MB decision-"
                                               "diagram tables" if big_tables else ""))
            progress(f"{self.what}, {unit_text(unit, self.i, self.units, self.run.texts)} "
                     f"{where}; {so_far(time.perf_counter() - self.run.started)}")
        res = self.execute(job, fresh)
        failure = res.failure
        # What the process set out to check ("auto" adds and leaves some for hybrid).
        asked = len(job.hybrid_queries if res.engine == "hybrid" else job.names)
        if failure is not None and asked > 1 and fresh is not False and (
                failure.stage == "tables" or (failure.stage in ("memory", "internal")
                                              and "hybrid" in (self.job_engine, res.engine))):
            self.replan(res, failure, unit, asked)
        elif failure is not None:
            self.after_query_failure(res, job, unit, group)
        else:
            self.after_answer(res, unit, complementary)

    def without_symbolic_gaps(self, unit: list[Query]) -> list[Query] | None:
        """The unit without what the hybrid engine cannot check ("auto" picked hybrid in an
        earlier process: --split), refused (E404) before building; None if nothing is left."""
        gaps = [n for p, n in unit if symbolic_gap(p, self.run.model, self.job_engine) is not None]
        if not gaps:
            return unit
        errors = self.run.errors
        try:
            refuse_symbolic(list(dict.fromkeys(p for p, _ in unit)), self.run.model,
                            self.job_engine, self.run.options.given.via)
        except CompileError as exc:
            errors.extend(d for d in exc.diagnostics if d not in errors)
        self.failed.update(gaps)
        self.units[self.i] = unit = not_failed(unit, self.failed, self.pending)
        return unit or None

    def job_for(self, unit: list[Query], group: list[ir.Property]) -> tuple[Job, bool, bool]:
        """The Storm job of `unit`; whether it asks complementary Pmin queries only, and
        whether it gets the larger decision-diagram tables."""
        run = self.run.options
        o = run.given
        limit = o.max_states if o.max_states is not None else (
            default_max_states() if self.job_engine == "sparse" else None)
        # "auto" checks what the hybrid engine would check first, if it picks that: with
        # probabilities only, that includes the queries standing in for each Pmax.
        first = [n for _, n in self.plan(unit, True)[0]] if self.job_engine == "auto" else []
        mine = [n for _, n in unit]
        extra = tuple(n for n in first if n not in mine)
        job = make_job(self.low, group, o.via, self.job_engine, limit, self.what, o.bisimulation,
                       o.memory_budget, only=tuple(mine),
                       hybrid_skip=tuple(n for n in mine if n not in first), hybrid_extra=extra,
                       exact=o.exact)
        job = dataclasses.replace(job, solver=o.solver, all_states=run.all_states,
                                  precision=run.precision, exact=o.exact)
        if applies(self.low, self.job_engine, o.solver,
                   o.bisimulation or o.exact or run.precision is not None):
            put = where(o.scratch, o.no_scratch, self.run.bound, mem_available())
            job = dataclasses.replace(job, explicit=self.low, uniform=self.uniform_beside(),
                                      scratch=put.directory, scratch_auto=put.auto)
        # no scheduler for a step-bounded query, nor for the rounding's kappa (conditioning)
        ex = request(self.low, o.strategy, run.witness, mine, self.run.asked_as,
                     skip={n for p, n in unit if stepped(p) or p.name == conditioning.STEPS})
        if ex is not None and job.fair is not None:
            raise unfair("without strategies or witnesses", "leave out --strategy and --witness")
        if self.resolution == "nondet" and o.via == "prism" and ex is not None:
            job = dataclasses.replace(job, extract=ex, model_text=prism_emit(self.low, True).model)
        if self.job_engine == "auto":
            job = dataclasses.replace(job, symbolic_refused=tuple(
                n for p, n in unit if symbolic_gap(p, self.run.model, "auto") is not None))
        complementary = any(n.startswith(REST) for _, n in unit) and all(
            n.startswith(REST) or n == TERMINATES for _, n in unit)
        # The probabilities' process (its complementary targets need the larger tables;
        # for "auto" they only take memory while the symbolic model lives).
        big_tables = (self.job_engine == "hybrid" and len(unit) > 1 and all(
            p.kind == "P" for p, _ in unit)) or bool(extra)
        if big_tables or (complementary and self.rest_full_tables):
            job = dataclasses.replace(job, dd_memory_mb=DD_MEMORY_RETRY)
        if big_tables and (extra or any(n.startswith(REST) for _, n in unit)):
            # should they fall back to a process each, they keep the larger tables
            self.rest_full_tables = True
        return job, complementary, big_tables

    def uniform_beside(self) -> tuple[str, ...]:
        """The uniform DTMC's queries this MDP's exploration answers too (Job.uniform):
        all of them, when one process explores the MDP for every query (not --split)."""
        lows = self.run.lows
        if self.resolution != "nondet" or len(lows) < 2 or lows[1][0] != "uniform" \
                or len(self.units) != 1 or self.run.options.given.split:
            return ()
        return tuple(n for p in self.run.props for n, _ in property_variants(lows[1][1], p))

    def fresh_process(self, group: list[ir.Property]) -> bool | None:
        """A fresh process per unit when there are several, except where no child process
        may be started (isolate=False: Dask workers); None lets the guard decide."""
        isolate = self.run.options.given.isolate
        fresh = isolate if isolate is False or len(self.units) == 1 else True
        if fresh is None and self.run.bound * max(
                steps(p, self.run.model) for p in group) > IN_PROCESS_WORK:
            # A small model with a huge step bound (F<=10^11) checks for hours, and a
            # check in this process ignores Ctrl-C and SIGTERM; a child can be stopped.
            fresh = True
        return fresh

    def execute(self, job: Job, fresh: bool | None) -> JobResult:
        """Run the job. An hour's answers are not lost to a Ctrl-C: the interrupt becomes
        a Stopped with the errors, a note of the values and the answers as data."""
        try:
            res = run_job(job, self.run.bound, isolate=fresh, progress=self.run.progress)
            self.run.exact.setdefault(self.resolution, {}).update(res.exact)
            if res.extracted is not None:
                self.run.extracted.append(res.extracted)
            return res
        except KeyboardInterrupt as exc:
            got = exc.values if isinstance(exc, Interrupted) else {}
            vals = self.vals | got
            raise Stopped(self.run.errors, [d.message for d in self.run.kept(self.what, vals)],
                          self.run.partial(vals, self.secs, self.merged or self.built)) from exc

    def replan(self, res: JobResult, failure: StormFailure, unit: list[Query],
               asked: int) -> None:
        """A process for several queries filled its tables or ran out of memory: keep what
        it answered and plan the others again."""
        self.vals |= res.values
        self.secs |= res.seconds
        # its time counts as checking: it answered some of the queries
        self.lost, self.lost_processes = self.lost + res.elapsed, self.lost_processes + 1
        self.built = self.sizes(res, self.built)
        left = unanswered(unit, self.vals, self.use)
        # "auto" leaves here only after a hybrid check (sparse fills no tables, and
        # a sparse process out of memory is not retried).
        head, *later = ([unanswered(u, self.vals, self.use) for u in self.plan(left, True)]
                        if self.job_engine == "auto" else [left]) or [[]]
        self.job_engine = "hybrid"
        if failure.stage == "tables" and head:
            # Full after some answers: the nodes of the earlier checks may have
            # filled them, so the rest go on in a fresh process. Full at the first
            # query: that one alone (the guard gives it larger tables), then the rest.
            again = [head] if res.values else [[head[0]], head[1:]]
            then = ("the others follow in a fresh process" if res.values else
                    f"{head[0][1]} follows alone, the others in a further process")
        else:
            again = [[q] for q in head]
            then = "the others follow one per Storm process"
        if self.run.progress is not None:
            self.run.progress(f"{failure.message}; {len(res.values)} of its {asked} "
                              f"queries were answered, {then}")
        i = self.i
        self.units = self.units[:i + 1] + [u for u in again if u] + later + self.units[i + 1:]
        self.i += 1

    def after_query_failure(self, res: JobResult, job: Job, unit: list[Query],
                            group: list[ir.Property]) -> None:
        """A process failed: at the model (raise now, with what was answered) or at one
        query (keep its error for the end; the other queries go on)."""
        run = self.run
        self.vals |= res.values
        self.secs |= res.seconds
        self.built = self.sizes(res, self.built)
        diagnose = functools.partial(failure_diagnostic, model=run.model, low=self.low,
                                     props=group, job=job)
        ds, retry, bad = after_failure(res, job, unit, self.vals, self.pending, self.failed,
                                       self.owner, run.texts, diagnose)
        if bad is not None and bad.startswith(REST):
            self.rest_errors[bad] = ds[0]  # no error if the complement is not used
        if not one_query(res):
            raise CompileError([*run.errors, *ds, *run.kept(self.what, self.vals)],
                               run.partial(self.vals, self.secs, self.merged or self.built))
        for d in ds:
            if d not in run.errors:  # a min and a max: one error
                run.errors.append(d)
        self.lost, self.lost_processes = self.lost + res.elapsed, self.lost_processes + 1
        self.i += 1
        i = self.i
        later = [u for u in (not_failed(u, self.failed, self.pending) for u in self.units[i:])
                 if u]
        if self.job_engine == "auto" and res.engine == "hybrid":
            self.job_engine = "hybrid"  # as after an answer
            self.units = self.units[:i] + [u for u in (unanswered(u, self.vals, self.use)
                                                       for u in self.plan(
                retry + [q for u in later for q in u], True)) if u]
        else:
            self.units = self.units[:i] + ([retry] if retry else []) + later
        if run.progress is not None:
            more = len(self.units) > i or self.what != run.lows[-1][2]
            run.progress(f"{ds[0].code}: {ds[0].message.rstrip('.')}; "
                         + ("the other queries go on, and " if more else "")
                         + "the error is reported at the end")

    def after_answer(self, res: JobResult, unit: list[Query], complementary: bool) -> None:
        """A process answered its queries: add them and its stats, and if "auto" chose
        hybrid, plan what is left as the hybrid engine wants it."""
        run = self.run
        if complementary and res.dd_retried and not self.rest_full_tables:
            self.rest_full_tables = True
            if run.progress is not None:
                run.progress(f"the {self.what}'s further complementary Pmin queries start with "
                             f"{DD_MEMORY_RETRY} MB decision-diagram tables")
        if run.reason and not res.engine_reason:
            res.engine_reason = run.reason
        one = stats_of(res, self.resolution)
        self.merged = one if self.merged is None else add_runs(self.merged, one)
        if res.uniform is not None:
            u = res.uniform
            run.beside["uniform"] = (u.values, u.seconds, ModelStats(
                "dtmc", "uniform", res.states, u.transitions, res.states, 0.0, 0.0,
                sum(u.seconds.values()), "explicit", "afsmc's exploration of the MDP: each "
                "state's value the mean of its floor/ceil choices, by one more backward pass",
                processes=0, solver="acyclic"))
        self.vals |= res.values
        self.secs |= res.seconds
        self.i += 1
        if self.job_engine == "auto" and res.engine == "hybrid":
            # "auto" chose hybrid: the queries it left (Job.hybrid_skip) and any later
            # ones follow as the hybrid engine wants them.
            self.job_engine = "hybrid"
            left = unanswered([q for u in [unit, *self.units[self.i:]] for q in u], self.vals,
                              self.use)
            self.units = self.units[:self.i] + [u for u in (unanswered(u, self.vals, self.use)
                                                            for u in self.plan(left, True)) if u]
            if run.progress is not None and left:
                run.progress(f"the {self.what} is checked with the hybrid engine: "
                             + ("one query per Storm process" if run.options.given.split else
                                "the other queries follow in one more Storm process"))
