"""The only module that talks to Storm: parse a generated model, build it, check properties.

A :class:`Job` is plain picklable data (the model text, the property names to check, the
engine), so it runs the same in this process, in a watched child process (see
:mod:`afsmc.verify.engines.guard`), in a process pool or on a Dask worker. Failures come
back as :class:`StormFailure` data, never as exceptions, and are turned into diagnostics by
the caller, which knows the .afsm source.
"""

from __future__ import annotations

import math
import os
import tempfile
import time
from collections.abc import Callable
from dataclasses import dataclass, field, replace
from typing import Any, Literal

from afsmc.verify.arrays import acyclic, umb
from afsmc.verify.engines import explicit, strategy_arrays
from afsmc.verify.engines.storm_solvers import Solver, solver_for, value_iteration
from afsmc.verify.engines.strategy_storm import Extract, Extracted, analyse, builder_options
from afsmc.verify.plan import fairness, precision

Engine = Literal["sparse", "dd", "hybrid", "auto"]
ENGINES: tuple[Engine, ...] = ("auto", "sparse", "dd", "hybrid")
# The sparse engine's memory per state (model plus one property's vectors): about 90 bytes
# per transition, 200-260 per state, measured with stormpy 2.0 on the UAV (5.5-11 M states).
SPARSE_BYTES_PER_STATE = 260
Via = Literal["prism", "jani"]
VIAS: tuple[Via, ...] = ("prism", "jani")

# Storm stages a failure can come from; the caller picks the diagnostic code from it.
# "stopped": the guard interrupted an explicit build that proved within --max-states
Stage = Literal["parse", "property", "build", "check", "too-big", "memory", "tables",
                "internal", "stopped", "scratch"]

Notify = Callable[[str, Any], None]


@dataclass(frozen=True)
class Job:
    via: Via
    model_text: str  # PRISM model or JANI JSON
    props_text: str  # PRISM properties file ("name": formula; per line); unused for JANI
    names: tuple[str, ...]  # the properties to check, in order
    engine: Engine = "sparse"
    max_states: int | None = None
    what: str = "model"  # for messages: "MDP", "uniform DTMC"
    bisimulation: bool = False  # minimise the sparse model (strong bisimulation) before checking
    memory_budget: int | None = None  # bytes the sparse engine may use ("auto" decides with it)
    # If "auto" picks hybrid, leave these names out: the caller checks them in a later
    # process, with the decision-diagram tables they need (a Pmax as 1 - Pmin of its
    # complement; see afsmc.verify.core.runner).
    hybrid_skip: tuple[str, ...] = ()
    # If "auto" picks hybrid, check these after the others (the queries that stand in for
    # each Pmax); the sparse engine leaves them out, as it asks each Pmax itself.
    hybrid_extra: tuple[str, ...] = ()
    # Sylvan's node tables for the symbolic engines, MB. Storm reserves 4 GB by default and
    # touches most of it; the UAV's diagrams fit in far less even at 77 M states, and the
    # memory is better spent on the explicit vectors of the hybrid engine. A model whose
    # diagrams need more makes Sylvan exit; the guard then retries with DD_MEMORY_RETRY.
    dd_memory_mb: int = 1024
    # Build every reachable state even for a single property: given exactly one, Storm makes
    # its target states absorbing (fewer states, same answer), so the states reported would
    # depend on how many properties a process checks (a sweep's chunks, --jobs).
    all_states: bool = False
    # Queries Storm's hybrid engine gives no result, or a wrong one, for (core.symbolic_gap):
    # if "auto" picks hybrid, the process leaves them out, says so at once ("refused"),
    # checks the others on the model it has built, and then fails at the first of them.
    symbolic_refused: tuple[str, ...] = ()
    solver: Solver = "auto"
    # Sound mode: Storm's sound value iteration, every value within this (a rational text,
    # absolute) of the true one (afsmc.verify.plan.precision); None: Storm's unsound stopping.
    precision: str | None = None
    exact: bool = False  # build over rationals and solve exactly (sparse engine only)
    # schedulers and most probable paths to extract (sparse engine only; strategy_storm)
    extract: Extract | None = None
    # a directory of its own for afsmc's own exploration layer by layer (guard.run_job makes
    # it under the user's --scratch DIR, or the system temp directory, and removes it);
    # None: in memory. `scratch_auto`: taken only once the in-memory exploration would not
    # fit comfortably (afsmc.verify.stream.route.where)
    scratch: str | None = None
    scratch_auto: bool = False
    # the lowered model, for afsmc's own exploration and backward pass first
    # (afsmc.verify.engines.explicit); None: Storm only
    explicit: Any = None
    # properties whose values in the uniform DTMC afsmc's exploration of this MDP gives as
    # well (explicit.Answer.uniform), saving the uniform DTMC its own exploration
    uniform: tuple[str, ...] = ()
    # `compose interleaving fair;`: each action's agents (afsmc.verify.plan.fairness) and
    # how many agents there are; None: every scheduler counts
    fair: tuple[tuple[str, tuple[int, ...]], ...] | None = None
    agents: int = 0

    @property
    def wanted(self) -> tuple[str, ...]:
        """Every query it may check: the names, then the hybrid extras (the engine decides)."""
        return self.names + tuple(n for n in self.hybrid_extra if n not in self.names)

    @property
    def hybrid_queries(self) -> tuple[str, ...]:
        """The queries it checks if the engine is (or "auto" picks) hybrid."""
        return tuple(n for n in self.names if n not in self.hybrid_skip) + self.hybrid_extra


DD_MEMORY_RETRY = 4096  # MB: Storm's own default


def explores_first(job: Job) -> bool:
    """Whether a symbolic job ("auto", "hybrid", "dd") builds explicitly first, so that the
    guard can watch its states grow (see :mod:`afsmc.verify.engines.guard`): when it has a
    --max-states whose sparse matrices fit its memory budget. Storm's symbolic builder
    reports nothing until it is done, and a model that is deep rather than wide (a counter
    over [0..10^9]) takes it one BFS step per level: without this it runs for hours.
    "auto" then simply builds sparse, as it would pick sparse for any model within the
    limit; "hybrid" and "dd" count the states explicitly, then build symbolically."""
    if job.engine == "sparse" or job.max_states is None:
        return False
    return job.memory_budget is None or job.max_states * SPARSE_BYTES_PER_STATE <= job.memory_budget


@dataclass(frozen=True)
class StormFailure:
    stage: Stage
    message: str
    prop: str | None = None  # the property it concerns
    line: int | None = None  # line of the generated PRISM text (parse errors)
    states: int | None = None  # for too-big: the (estimated) number of states


@dataclass
class JobResult:
    states: int = 0
    transitions: int = 0
    choices: int = 0
    kind: str = ""  # "dtmc" | "mdp" as Storm built it
    parse_time: float = 0.0
    build_time: float = 0.0
    check_time: float = 0.0
    values: dict[str, float] = field(default_factory=dict)
    exact: dict[str, str] = field(default_factory=dict)  # --exact: each value as `num/den`
    seconds: dict[str, float] = field(default_factory=dict)  # each query's check, wall time
    engine: str = ""  # the engine that checked ("auto" resolves to sparse or hybrid)
    engine_reason: str = ""  # why "auto" chose it
    solver: str = ""  # how the equation systems were solved (solver_for)
    quotient_states: int | None = None  # states after bisimulation
    quotient_transitions: int | None = None
    bisimulation_time: float = 0.0
    dd_retried: bool = False  # Sylvan's tables were full: the guard reran it with DD_MEMORY_RETRY
    elapsed: float = 0.0  # wall time of a process that failed (its answers may still count)
    failure: StormFailure | None = None
    extracted: Extracted | None = None  # what Job.extract asked for
    uniform: Any = None  # explicit.Uniform: what Job.uniform asked, where the pass gave it


def _quiet() -> None:
    # Storm logs to stdout, which must stay clean for --json; its errors reach us as exceptions.
    from stormpy import developer

    developer.set_log_level(developer.LogLevel.OFF)


def _give_back() -> None:
    """Return the heap a check has freed to the system. glibc keeps it otherwise: 2.3 GB
    after a check of scenario 1, on top of the next check's own peak in the same process
    (the complement of `emergency` then passed 85% of the free memory; with this, the
    whole group peaked at 17.7 GB)."""
    import contextlib
    import ctypes

    with contextlib.suppress(OSError, AttributeError):  # not glibc: nothing to do
        ctypes.CDLL("libc.so.6").malloc_trim(0)


def _message(exc: BaseException) -> str:
    """Storm's message without the C++ exception class and trailing whitespace."""
    text = str(exc).strip()
    for prefix in ("WrongFormatException: ", "InvalidArgumentException: ",
                   "InvalidPropertyException: ", "NotSupportedException: ",
                   "InvalidOperationException: ", "InvalidStateException: ",
                   "OutOfRangeException: ", "FileIoException: ", "InvalidJaniException: ",
                   "IllegalArgumentException: "):
        if text.startswith(prefix):
            return text[len(prefix):]
    return text


def _parse_line(message: str) -> int | None:
    """`Parsing error at 5:1: ...` -> 5."""
    import re

    m = re.search(r"[Pp]arsing error at (\d+):(\d+)", message)
    return int(m.group(1)) if m else None


def execute(job: Job, notify: Notify | None = None) -> JobResult:
    """Parse, build and check `job` with Storm. Never raises for Storm's errors."""
    try:
        return _execute(job, notify or (lambda _e, _d: None))
    except MemoryError:
        return JobResult(failure=StormFailure("memory", f"ran out of memory building the {job.what}"))
    except Exception as exc:  # stormpy raises more than RuntimeError; never a traceback
        return JobResult(failure=StormFailure("internal", f"{type(exc).__name__}: {exc}"))


def _execute(job: Job, notify: Notify) -> JobResult:
    res = JobResult()
    if job.fair is not None:  # Storm's sparse engine, its model with choice labels
        assert not job.exact and job.extract is None  # refused (verify.engines.jobs.unfair)
        job = replace(job, explicit=None, bisimulation=False)
    if job.explicit is not None:
        left = explicit.fill(job, res, notify, too_big)
        if left is None:
            return res
        job = left
    mixed = bool(res.values)
    import stormpy

    _quiet()
    t0 = time.perf_counter()
    notify("phase", "parse")
    parsed = _parse(stormpy, job)
    if isinstance(parsed, StormFailure):
        res.failure = parsed
        return res
    program, props = parsed
    res.parse_time = time.perf_counter() - t0

    notify("phase", "build")
    t0 = time.perf_counter()
    try:
        built = _build(stormpy, job, program, props, res, notify)
    except RuntimeError as exc:
        res.failure = StormFailure("build", _message(exc))
        return res
    except TooBig as exc:
        res.states = exc.states
        res.failure = too_big(job, exc.states)
        return res
    res.engine = built.engine
    res.solver = solver_for(job.solver, built.engine)
    check_env = (value_iteration(stormpy, job.dd_memory_mb)
                 if res.solver == "value-iteration" else None)
    if job.exact:
        res.solver, check_env = "exact", precision.exact_environment(stormpy)
    elif job.precision is not None:
        res.solver = "sound-value-iteration"
        check_env = precision.sound_environment(stormpy, job.precision, job.dd_memory_mb)
    notify("engine", built.engine)  # a process that dies later still says which engine ran
    res.build_time = time.perf_counter() - t0
    model = built.model
    res.states, res.transitions = int(model.nr_states), int(model.nr_transitions)
    res.choices = (int(getattr(model, "nr_choices", res.transitions) or 0)
                   if not built.symbolic else 0)
    res.kind = "mdp" if str(model.model_type).upper().endswith("MDP") else "dtmc"
    del model  # built.model alone holds it: a bisimulation quotient replaces it there
    notify("built", (res.states, res.transitions, res.build_time))
    if built.deferred is not None:
        notify("refused", tuple(built.refused))
    if built.symbolic and res.states == 0:
        # A model whose variables all keep their values: Storm's symbolic builder counts no
        # state, and its hybrid engine then crashes (segmentation fault) on some properties.
        res.failure = StormFailure("build", f"Storm's symbolic build of the {job.what} has no "
                                   "states (no variable ever changes its value, which Storm's "
                                   "decision diagrams do not represent)")
        return res
    if job.max_states is not None and res.states > job.max_states:
        res.failure = too_big(job, res.states)
        return res
    if job.bisimulation and not built.symbolic and not _bisimulation(built, res, notify):
        return res
    t0 = time.perf_counter()
    if check_env is None and res.solver == "topological" and job.solver == "auto" \
            and job.fair is None:
        if job.extract is None:
            _acyclic(stormpy, built, res, notify, job, program)
        elif _lean(job, built.props):  # strategies from the backward pass, if acyclic
            strategy_arrays.run(stormpy, built, res, notify, job, program,
                                lambda: _sparse(stormpy, program, built.props, job, lean=False))
    if built.names and not _check_each(stormpy, built, check_env, res, notify, job, program):
        return res
    res.check_time = time.perf_counter() - t0
    res.failure = built.deferred
    if mixed:  # some queries by afsmc's own exploration, the others by Storm
        res.solver = f"acyclic (explicit) and {res.solver}"
    return res


def too_big(job: Job, states: int, partial: bool = False) -> StormFailure:
    """`partial`: `states` were found before the exploration stopped, the model has more."""
    return StormFailure("too-big", f"the {job.what} has {'at least ' if partial else ''}"
                        f"{states:,} states, more than --max-states {job.max_states:,}",
                        states=states)


def _parse(stormpy: Any, job: Job) -> tuple[Any, list[Any]] | StormFailure:
    """The model and the properties the job may check, as Storm parsed them, or why Storm
    rejected one of them."""
    if job.via == "prism":
        with tempfile.TemporaryDirectory(prefix="afsmc-") as tmp:
            path = os.path.join(tmp, "model.prism")
            with open(path, "w", encoding="utf-8") as f:
                f.write(job.model_text)
            try:
                program: Any = stormpy.parse_prism_program(path)
            except RuntimeError as exc:
                msg = _message(exc)
                return StormFailure("parse", msg, line=_parse_line(msg))
        props, failure = _prism_properties(stormpy, program, job.props_text, job.wanted)
    else:
        try:
            program, all_props = stormpy.parse_jani_model_from_string(job.model_text)
        except RuntimeError as exc:
            return StormFailure("parse", _message(exc))
        by_name = {p.get_name(): p for p in all_props}
        missing = [n for n in job.wanted if n not in by_name]
        failure = StormFailure("property", "the JANI model has no property named "
                               + ", ".join(missing), prop=missing[0]) if missing else None
        props = [by_name[n] for n in job.wanted if n in by_name]
    return failure if failure is not None else (program, props)


class TooBig(Exception):
    """The explicit count before a symbolic build exceeds --max-states."""

    def __init__(self, states: int):
        super().__init__(states)
        self.states = states


@dataclass
class _Built:
    """A built model and what this process checks on it."""

    model: Any
    engine: str  # the engine that checks: "auto" resolved to sparse or hybrid
    names: list[str]  # the queries this process checks, in the order of `props`
    props: list[Any]
    symbolic: bool  # a decision-diagram model (dd, hybrid), not sparse matrices
    deferred: StormFailure | None = None  # the failure to report after the other checks
    refused: list[str] = field(default_factory=list)  # ... of these queries, which the
    # hybrid engine cannot check


def _build(stormpy: Any, job: Job, program: Any, props: list[Any], res: JobResult,
           notify: Notify) -> _Built:
    """Build the model for the job's engine. "auto" builds symbolically first, which counts
    the states exactly at little memory, then keeps that model for the hybrid engine or
    builds sparse matrices if they fit (see :func:`_choose`)."""
    names = list(job.wanted)  # the extras go once the engine is known
    if job.engine == "sparse" or (job.engine == "auto" and explores_first(job)):
        names, props = _keep(names, props, job.hybrid_extra)
        if job.engine == "auto":
            assert job.max_states is not None
            res.engine_reason = (f"--max-states {job.max_states:,} fits as sparse matrices "
                                 f"(about {job.max_states * SPARSE_BYTES_PER_STATE / 1e9:.1f} "
                                 "GB): built sparse, its states counted as it ran")
            notify("phase", "explore")
        return _Built(_sparse(stormpy, program, props, job), "sparse", names, props,
                      symbolic=False)
    if explores_first(job):
        # hybrid or dd: count the states explicitly, under the guard's watch, first
        notify("phase", "explore")
        explored = int(stormpy.build_model(program, _for_builder(props, job)).nr_states)
        assert job.max_states is not None
        if explored > job.max_states:
            raise TooBig(explored)
        notify("phase", "build")
    # Labels and guards that mention constants fail in the symbolic builder otherwise.
    sprog = program.substitute_constants()
    if hasattr(sprog, "substitute_formulas"):
        # PRISM: a formula in a label or reward has no decision diagram otherwise
        sprog = sprog.substitute_formulas()
    if hasattr(sprog, "substitute_functions"):
        sprog.substitute_functions()  # JANI: in place
    env = stormpy.Environment()
    env.dd().sylvan().maximal_memory = job.dd_memory_mb
    model: Any = stormpy.build_symbolic_model(sprog, _for_builder(props, job), environment=env)
    if job.engine != "auto":
        return _Built(model, job.engine, names, props, symbolic=True)
    built = _choose(job, int(model.nr_states), names, props, res)
    if built.symbolic:
        built.model = model
        return built
    notify("phase", "build")
    del model  # before the sparse build: only one of the two models in memory at a time
    built.model = _sparse(stormpy, program, built.props, job)
    return built


def _sparse(stormpy: Any, program: Any, props: list[Any], job: Job, lean: bool = True) -> Any:
    """The sparse model: over rationals for an exact job; if the job extracts, with choice
    labels and either state valuations (Storm's route) or, where the backward pass may
    answer (`lean`), one label per bit of each variable (strategy_arrays)."""
    if job.exact:
        return precision.build_exact(stormpy, program, _for_builder(props, job), job.extract)
    if job.fair is not None:
        opts = stormpy.BuilderOptions([p.get_raw_formula() for p in _for_builder(props, job)])
        opts.set_build_choice_labels()
        return stormpy.build_model(program, options=opts)
    if job.extract is not None:
        opts = strategy_arrays.options(stormpy, [p.get_raw_formula() for p in _for_builder(
            props, job)], program) if lean and _lean(job, props) else None
        return stormpy.build_model(program, options=opts or builder_options(
            stormpy, _for_builder(props, job), program, job.extract))
    return stormpy.build_model(program, _for_builder(props, job))


def _lean(job: Job, props: list[Any]) -> bool:
    """Whether the job's extraction may come from the backward pass (strategy_arrays)."""
    return job.extract is not None and job.solver == "auto" and not job.exact \
        and job.precision is None and strategy_arrays.fits(
            job.extract, [p.get_name() for p in props], props)


def _choose(job: Job, states: int, names: list[str], props: list[Any],
            res: JobResult) -> _Built:
    """The engine "auto" picks for a model of `states` states: sparse if its matrices fit
    in the job's memory budget, else hybrid; the reason goes to `res.engine_reason`. The
    model is for the caller to set."""
    # The sparse engine is much faster to check but needs ~260 bytes per state.
    need = states * SPARSE_BYTES_PER_STATE
    budget = job.memory_budget
    if budget is None or need <= budget:
        names, props = _keep(names, props, job.hybrid_extra)
        res.engine_reason = (f"{states:,} states need about {need / 1e9:.1f} GB as sparse "
                             "matrices" + (f", within the {budget / 1e9:.1f} GB available"
                                           if budget else ""))
        return _Built(None, "sparse", names, props, symbolic=False)
    res.engine_reason = (f"{states:,} states would need about {need / 1e9:.1f} GB as sparse "
                         f"matrices, more than the {budget / 1e9:.1f} GB available")
    if job.hybrid_skip:
        names, props = _keep(names, props, job.hybrid_skip)
        res.engine_reason += "; queries grouped by the tables they need"
    refused = [n for n in names if n in job.symbolic_refused]
    deferred = None
    if refused:
        # not a second build for the others: they are checked here
        deferred = StormFailure(
            "check", f"its {states:,} states are too many for the sparse engine (about "
            f"{need / 1e9:.1f} GB as sparse matrices), and the hybrid engine cannot check "
            "this property (docs/verification.md, \"Engines and routes\")", prop=refused[0])
        names, props = _keep(names, props, tuple(refused))
    return _Built(None, "hybrid", names, props, True, deferred, refused)


def _bisimulation(built: _Built, res: JobResult, notify: Notify) -> bool:
    """Replace the sparse model by its strong-bisimulation quotient; False, with
    `res.failure` set, if Storm fails."""
    notify("phase", "bisimulation")
    t0 = time.perf_counter()
    try:
        import stormpy.transformations as transformations

        built.model = transformations.perform_bisimulation(
            built.model, built.props, bisimulation_type=transformations.BisimulationType.STRONG)
    except RuntimeError as exc:
        res.failure = StormFailure("build", "bisimulation failed: " + _message(exc))
        return False
    res.bisimulation_time = time.perf_counter() - t0
    res.quotient_states = int(built.model.nr_states)
    res.quotient_transitions = int(built.model.nr_transitions)
    return True


def _check_each(stormpy: Any, built: _Built, check_env: Any, res: JobResult,
                notify: Notify, job: Job, program: Any) -> bool:
    """Check the queries one at a time, each value sent as soon as it is known; False,
    with `res.failure` set, at the first that fails."""
    model = built.model
    engine = {"dd": stormpy.Engine.DD, "hybrid": stormpy.Engine.HYBRID}.get(built.engine)
    for name, prop in zip(built.names, built.props, strict=True):
        notify("phase", f"check {name}")
        started = time.perf_counter()
        try:
            if built.symbolic:
                r = stormpy.model_checking(model, prop, only_initial_states=True, engine=engine,
                                           environment=check_env)
                # The value of the (one) initial state: not the maximum over all states, and
                # not the filtered result's get_max, which counts the 0 of every state outside
                # the filter (a negative expected reward would read 0).
                value = None if r is None else stormpy.filter_initial_states(r, model).average()
            else:
                wanted = job.extract is not None and name in job.extract.queries
                r = stormpy.model_checking(model, prop, environment=check_env)
                value = r.get_value(model.initial_states[0])
                if job.fair is not None:
                    fair = fairness.check(stormpy, model, prop, float(value), dict(job.fair),
                                          job.agents, check_env)
                    value = value if fair is None else fair
                if wanted and res.kind == "mdp":
                    # Storm solves again to give a scheduler, by another method whose
                    # value differs in the last digits: the value stays the one asked
                    # without it, as every other front-end gets it (one answer)
                    r = stormpy.model_checking(model, prop, environment=check_env,
                                               extract_scheduler=True)
                if wanted:
                    assert job.extract is not None
                    res.extracted = res.extracted or Extracted()
                    analyse(stormpy, program, model, name, prop, r, job.extract, res.extracted)
        except RuntimeError as exc:
            res.failure = StormFailure("check", _message(exc), prop=name)
            return False
        except fairness.Refused as exc:
            res.failure = StormFailure("check", str(exc), prop=name)
            return False
        if value is None:
            res.failure = StormFailure("check", f"the {built.engine} engine does not support "
                                       "this property (Storm returned no result)", prop=name)
            return False
        res.values[name] = float(value)
        if not isinstance(value, float) and (text := precision.exact_text(value)) is not None:
            res.exact[name] = text
            res.values[name] = precision.nearest(text)  # Storm's float() is off by an ulp
        del r  # before the next check: the result holds decision diagrams of this model
        _give_back()
        res.seconds[name] = time.perf_counter() - started
        # A process that dies later (memory) has still answered this one: the watcher keeps it.
        notify("value", (name, float(value), res.seconds[name]))
    return True


def _acyclic(stormpy: Any, built: _Built, res: JobResult, notify: Notify, job: Job,
             program: Any) -> None:
    """Answer what one backward pass can (afsmc.verify.arrays.acyclic) if the sparse model is
    acyclic but for self-loops; the rest stays in `built` for Storm's solver."""
    p = acyclic.plan(built.names, built.props, res.kind == "mdp")
    if not p.queries:
        return
    notify("phase", "acyclic")
    started = time.perf_counter()
    raw = umb.read(stormpy, built.model, p)
    if raw is not None and not p.left:
        built.model = None  # one model in memory at a time: the arrays hold all it needs
        _give_back()
    arrays = None if raw is None else umb.arrange(raw)
    del raw
    if arrays is None:
        notify("solver", f"the {job.what} has cycles: Storm's topological solver checks it")
        if built.model is None:  # built again, rather than kept for a case this rare
            notify("phase", "build")
            built.model = _sparse(stormpy, program, built.props, job)
        return
    notify("solver", f"the {job.what} is acyclic but for self-loops ({len(arrays.layers) - 1:,} "
           "layers): each query by one exact backward pass")
    notify("phase", "check " + ", ".join(q.name for q in p.queries))
    values = acyclic.solve_many(arrays, p.queries)
    # the passes share their work: each query is given an equal share of the time
    secs = (time.perf_counter() - started) / len(p.queries)
    for q in p.queries:
        res.values[q.name], res.seconds[q.name] = values[q.name], secs
        notify("value", (q.name, values[q.name], secs))
    del arrays
    _give_back()
    left = [(n, prop) for n, prop in zip(built.names, built.props, strict=True) if n in p.left]
    built.names, built.props = [n for n, _ in left], [prop for _, prop in left]
    res.solver = "acyclic" if not left else "acyclic and topological"


def _for_builder(props: list[Any], job: Job) -> list[Any]:
    """The properties to build for: a single one twice under `all_states` (Storm derives
    absorbing target states only from exactly one)."""
    return props * 2 if job.all_states and len(props) == 1 else props


def _keep(names: list[str], props: list[Any],
          drop: tuple[str, ...]) -> tuple[list[str], list[Any]]:
    kept = [(n, p) for n, p in zip(names, props, strict=True) if n not in drop]
    return [n for n, _ in kept], [p for _, p in kept]


def _prism_properties(stormpy: Any, program: Any, props_text: str,
                      names: tuple[str, ...]) -> tuple[list[Any], StormFailure | None]:
    try:
        parsed = stormpy.parse_properties(props_text, program)
    except RuntimeError:
        parsed = None
    if parsed is not None:
        by_name = {p.get_name(): p for p in parsed}
        if all(n in by_name for n in names):
            return [by_name[n] for n in names], None
    # Find the property Storm rejects, so the diagnostic can point at it.
    lines = {n: line for line in props_text.splitlines()
             for n in [line.split('"', 2)[1] if line.startswith('"') else ""] if n}
    out = []
    for n in names:
        try:
            out.append(stormpy.parse_properties(lines.get(n, ""), program)[0])
        except (RuntimeError, IndexError) as exc:
            return [], StormFailure("property", _message(exc) if isinstance(exc, RuntimeError)
                                    else "Storm did not parse this property", prop=n)
    return out, None


def finite(v: float | None) -> float | None:
    """JSON has no infinity: an infinite expected reward is reported as null."""
    return v if v is not None and math.isfinite(v) else None
