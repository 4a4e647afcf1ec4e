"""`run`: load an .afsm file, lower it, let Storm check its properties, explain the results.

See the package docstring (afsmc/verify/__init__.py) for the API.
"""

from __future__ import annotations

import dataclasses
import functools
import importlib
import math
import os
import re
import time
import typing
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

from afsmc.backends.prism import emit as prism_emit
from afsmc.backends.prism import formula_text, property_variants
from afsmc.compiler import load, lowered
from afsmc.diagnostics import CompileError, Diagnostic, Related, Severity, Source, Span
from afsmc.interrupt import Stopped
from afsmc.lower.lowering import Lowered
from afsmc.lower.reduce import Reductions
from afsmc.model import expr as E
from afsmc.model import ir
from afsmc.model.evaluate import Env, EvalError, evaluate
from afsmc.model.names import did_you_mean
from afsmc.model.pretty import show
from afsmc.model.semantics import bounded_globally, globally_dual, inline, static_value
from afsmc.stack import deep
from afsmc.syntax.parser import parse, parse_property
from afsmc.text import count as human
from afsmc.verify.guard import (
    Interrupted,
    Progress,
    default_max_states,
    mem_available,
    run_job,
    upper_bound,
)
from afsmc.verify.storm import (
    DD_MEMORY_RETRY,
    Engine,
    Job,
    JobResult,
    Solver,
    StormFailure,
    Via,
    finite,
)


@dataclass
class ModelStats:
    """One model Storm built: the min/max MDP, the uniform DTMC, or the only DTMC."""

    type: str  # "dtmc" | "mdp"
    resolution: str  # "nondet" | "uniform" (how interval constants were lowered)
    states: int
    transitions: int
    choices: int
    parse_time: float
    build_time: float
    check_time: float
    engine: str = ""  # the engine that checked (what "auto" chose)
    engine_reason: str = ""
    quotient_states: int | None = None  # after --bisim
    quotient_transitions: int | None = None
    bisimulation_time: float = 0.0
    processes: int = 1  # Storm runs that built this model (--split: one per query)
    solver: str = ""  # "topological" | "value-iteration" (storm.solver_for)

    def to_json(self) -> dict[str, object]:
        out: dict[str, object] = {
            "states": self.states, "transitions": self.transitions, "choices": self.choices,
            "type": self.type, "resolution": self.resolution, "engine": self.engine,
            "processes": self.processes}
        if self.solver:  # not for the dd engine
            out["solver"] = self.solver
        if self.engine_reason:
            out["engine_reason"] = self.engine_reason
        if self.quotient_states is not None:
            out["quotient_states"] = self.quotient_states
            out["quotient_transitions"] = self.quotient_transitions
        return out


@dataclass
class PropertyResult:
    """min/max (an MDP: the interval constants' floor/ceil chosen adversarially or
    cooperatively), uniform (chosen at random), or value (a DTMC). None where not asked."""

    name: str
    formula: str  # in .afsm syntax
    kind: str  # "P" | "R"
    min: float | None = None
    max: float | None = None
    uniform: float | None = None
    value: float | None = None
    # Storm's time for each of the above, s: its check, or that of the query asked instead
    # (a Pmax as 1 - Pmin, a bounded G as its dual). Builds are in the model's build time.
    seconds: dict[str, float] = field(default_factory=dict)

    def to_json(self) -> dict[str, object]:
        out: dict[str, object] = {"name": self.name, "formula": self.formula}
        infinite = []
        for key in ("min", "max", "uniform", "value"):
            v = getattr(self, key)
            out[key] = finite(v)
            if v is not None and finite(v) is None:
                infinite.append(key)
        if infinite:
            out["infinite"] = infinite  # JSON has no infinity: these are null above
        out["seconds"] = {k: round(v, 3) for k, v in self.seconds.items()}
        return out


def find_property(results: Sequence[PropertyResult], name: str) -> PropertyResult:
    """Raises KeyError naming the properties there are (a bare StopIteration did)."""
    for p in results:
        if p.name == name:
            return p
    raise KeyError(f"no property {name!r}; there are " + ", ".join(repr(p.name) for p in results))


@dataclass
class Checks:
    """What :func:`check` returns: the models built and one result per property."""

    model: ModelStats
    uniform_model: ModelStats | None
    properties: list[PropertyResult]


@dataclass
class Partial:
    """What :func:`check` had answered when it failed (`CompileError.partial`): a min, max,
    uniform or value is None where its query failed or was not asked, and a model's stats
    are None if none of its processes finished."""

    model: ModelStats | None
    uniform_model: ModelStats | None
    properties: list[PropertyResult]

    def to_json(self) -> dict[str, object]:
        u = self.uniform_model
        return {"model": self.model.to_json() if self.model is not None else None,
                "uniform_model": u.to_json() if u is not None else None,
                "properties": [p.to_json() for p in self.properties]}


@dataclass
class VerifyResult:
    path: str
    machine: str
    constants: dict[str, object]  # the open constants' values used
    via: str
    engine: str
    upper_bound: int  # modes × product of variable ranges
    max_states: int
    model: ModelStats
    uniform_model: ModelStats | None
    properties: list[PropertyResult]
    load_time: float
    total_time: float
    warnings: list[Diagnostic] = field(default_factory=list)

    @property
    def kind(self) -> str:
        return self.model.type

    def property(self, name: str) -> PropertyResult:
        return find_property(self.properties, name)

    def to_json(self) -> dict[str, object]:
        u = self.uniform_model
        timings: dict[str, float] = {
            "load": self.load_time, "parse": self.model.parse_time,
            "build": self.model.build_time, "check": self.model.check_time}
        if u is not None:
            timings |= {"uniform_build": u.build_time, "uniform_check": u.check_time}
        timings["total"] = self.total_time
        return {
            "file": self.path,
            "machine": self.machine,
            "model": self.model.to_json(),
            "uniform_model": u.to_json() if u is not None else None,
            "properties": [p.to_json() for p in self.properties],
            "timings": {k: round(v, 6) for k, v in timings.items()},
            "via": self.via,
            "engine": self.engine,
            "constants": self.constants,
            "state_space": {"upper_bound": self.upper_bound, "max_states": self.max_states},
            "warnings": [d.to_json() for d in self.warnings],
        }


def shown(p: ir.Property) -> str:
    """A property's formula for people, in afsm syntax: as written where it was written."""
    return p.text or formula_text(p, p.opt, show)


# ---- loading with ad-hoc formulas --------------------------------------------------


def _fresh_name(text: str, base: str, taken: set[str]) -> str:
    n, name = 1, base
    while name in taken or re.search(rf"\b{name}\b", text):
        n += 1
        name = f"{base}{n}"
    taken.add(name)
    return name


@dataclass
class Loaded:
    """A model loaded with ad-hoc formulas; `remap` moves a diagnostic about a formula
    from the end of the (extended) file into the formula itself (file `--formula`)."""

    model: ir.Model
    warnings: list[Diagnostic]
    adhoc: list[str]  # the generated property names, in the order of the formulas
    limit: int = 0
    where: list[tuple[int, int, int, str]] = field(default_factory=list)

    def remap(self, d: Diagnostic) -> Diagnostic:
        return _remap(d, self.limit, self.where)

    def remap_error(self, exc: CompileError) -> CompileError:
        return CompileError([self.remap(d) for d in exc.diagnostics], exc.partial)


def load_with_formulas(path: str, overrides: Mapping[str, str] | None = None,
                       formulas: Sequence[str] = (), *, text: str | None = None,
                       run_checks: bool = True) -> Loaded:
    """Load `path` with each formula appended as `property adhocN = <formula>;`."""
    from afsmc.files import read_source

    base = read_source(path) if text is None else text
    full = base if base.endswith("\n") else base + "\n"
    where: list[tuple[int, int, int, str]] = []  # (head, start, end, formula) offsets in `full`
    names: list[str] = []
    taken: set[str] = set()
    for f in formulas:
        if ";" in f:
            raise CompileError([Diagnostic(
                "E409", Severity.ERROR, f"--formula {f!r}: one property, without ';'", None,
                hint="repeat --formula for several properties")])
        # Parsed on its own first, so a syntax error speaks of the formula alone and not
        # of the declaration it is wrapped in below.
        parse_property(f, "--formula")
        name = _fresh_name(base, "adhoc", taken)
        names.append(name)
        head = f"property {name} = "
        where.append((len(full), len(full) + len(head), len(full) + len(head) + len(f), f))
        full += f"{head}{f};\n"
    try:
        checked = load(path, overrides, text=full, run_checks=run_checks)
    except CompileError as exc:
        if where and any(d.code.startswith("E1") for d in exc.diagnostics):
            parse(base, path)  # a syntax error of the file: its own, without the formulas
        raise CompileError([_remap(d, len(base), where) for d in exc.diagnostics]) from None
    return Loaded(checked.model, [_remap(d, len(base), where) for d in checked.diagnostics],
                  names, len(base), where)


def _remap(d: Diagnostic, limit: int, where: list[tuple[int, int, int, str]]) -> Diagnostic:
    def span(s: Span | None) -> Span | None:
        if s is None or s.start < limit or not where:
            return s
        if limit == 0 and s.start == 0:  # the whole of an empty file (E213)
            return Span.at_offset(Source(s.source.path, ""), 0, 0)
        for head, start, end, f in where:
            if head <= s.start <= end:  # the formula, its `property NAME =` head, or ';'
                src = Source("--formula", f)
                if s.start < start:  # the whole declaration: the whole formula
                    return Span.at_offset(src, 0, len(f))
                a = min(s.start - start, len(f))
                return Span.at_offset(src, a, min(max(a + 1, s.end - start), max(len(f), a + 1)))
        return None

    related = tuple(Related(r.message, span(r.span) or r.span) for r in d.related)
    return dataclasses.replace(d, span=span(d.span), related=related)


def select(model: ir.Model, names: Sequence[str], adhoc: Sequence[str] = ()) -> list[ir.Property]:
    """The properties to check: those named (else every declared one) and the ad-hoc ones."""
    declared = [p for p in model.properties if p.name not in adhoc]
    if not names and not adhoc:
        if not declared:
            raise CompileError([Diagnostic(
                "E407", Severity.ERROR, f"{model.source.path} declares no properties", None,
                hint="declare one ('property ok = P=? [ F \"done\" ];') or pass --formula")])
        return declared
    by_name = {p.name: p for p in declared}
    diags = []
    out = []
    for n in names:
        if n in by_name:
            if by_name[n] not in out:
                out.append(by_name[n])
        else:
            diags.append(Diagnostic("E407", Severity.ERROR, f"--property {n}: no property named "
                                    f"'{n}' in {model.source.path}", None,
                                    hint=did_you_mean(n, by_name) or (
                                        "properties: " + ", ".join(by_name) if by_name else None)))
    if diags:
        raise CompileError(diags)
    out += [p for p in model.properties if p.name in adhoc]
    return out


# ---- Storm jobs and their failures -------------------------------------------------


def make_job(low: Lowered, props: Sequence[ir.Property], via: Via, engine: Engine,
             max_states: int | None, what: str, bisimulation: bool = False,
             memory_budget: int | None = None, only: tuple[str, ...] | None = None,
             hybrid_skip: tuple[str, ...] = (),
             hybrid_extra: tuple[str, ...] = ()) -> Job:
    """The Storm input for a lowered model whose `properties` are exactly `props`.
    `memory_budget`: what "auto" may give the sparse engine (default: 70% of free memory);
    `only`: check just these queries (property variants, e.g. `success_min`);
    `hybrid_skip`: queries "auto" leaves to another process if it picks hybrid;
    `hybrid_extra`: queries (of `low`'s properties) it checks only if it picks hybrid."""
    names = tuple(n for p in props for n, _ in property_variants(low, p)
                  if only is None or n in only)
    avail = mem_available()
    budget = memory_budget
    if budget is None:
        budget = int(avail * 0.7) if avail is not None else None
    skip, extra = (hybrid_skip, hybrid_extra) if engine == "auto" else ((), ())
    if via == "prism":
        out = prism_emit(low)
        return Job("prism", out.model, out.properties, names, engine, max_states, what,
                   bisimulation, budget, skip, extra)
    try:
        jani: Any = importlib.import_module("afsmc.backends.jani")
    except ImportError:
        raise CompileError([Diagnostic("E408", Severity.ERROR,
                                       "the JANI backend (afsmc.backends.jani) is not available",
                                       None, hint="use --via prism")]) from None
    return Job("jani", jani.dumps(jani.emit(low)), "", names, engine, max_states, what,
               bisimulation, budget, skip, extra)


def _source_line_span(model: ir.Model, generated: str, line: int) -> Span | None:
    """The .afsm line a line of generated PRISM comes from (its `// file.afsm:N` comment)."""
    lines = generated.splitlines()
    base = re.escape(os.path.basename(model.source.path))
    for i in range(min(line, len(lines)) - 1, -1, -1):
        m = re.search(rf"// (?:.*, )?{base}:(\d+)", lines[i])
        if m:
            n = int(m.group(1))
            text = model.source.text
            start = 0
            for _ in range(n - 1):
                start = text.find("\n", start) + 1
            end = text.find("\n", start)
            return Span.at_offset(model.source, start, end if end >= 0 else len(text))
    return None


def failure_diagnostic(f: StormFailure, model: ir.Model, low: Lowered,
                       props: Sequence[ir.Property], job: Job) -> Diagnostic:
    """A Storm failure as an afsmc diagnostic, pointing at the .afsm source if possible."""
    prop = None
    if f.prop is not None:
        prop = next((p for p in props if f.prop in
                     [n for n, _ in property_variants(low, p)]), None)
    route = "PRISM" if job.via == "prism" else "JANI"
    first = " ".join(line.strip() for line in f.message.splitlines()
                     if line.strip() and set(line.strip()) != {"^"}) or "no message"
    engine_hint = (f"the {job.engine} engine supports fewer properties: try --engine sparse"
                   if job.engine != "sparse" else None)
    if engine_hint and prop is not None and _total_reward(prop):
        engine_hint = ("use a step bound (C<=k) or R [ F target ]; --engine sparse checks "
                       "R [ C ] where the machine has the memory")
    elif engine_hint and prop is not None and symbolic_gap(prop, model, job.engine):
        engine_hint = ("--engine dd checks it (slowly), --engine sparse where the machine has "
                       "the memory")
    elif engine_hint and job.via == "jani" and prop is not None and isinstance(prop.path, ir.Path) \
            and prop.path.kind == "X":
        # JANI writes X as a step-bounded until ([1, 1]), which only Storm's sparse engine
        # takes; from PRISM the symbolic engines check X.
        engine_hint = (f"JANI has no X: afsmc writes it as an until bounded to one step, which "
                       f"the {job.engine} engine cannot check; use --via prism or --engine sparse")

    def diag(code: str, msg: str, span: Span | None, hint: str | None = None) -> Diagnostic:
        return Diagnostic(code, Severity.ERROR, msg, span, hint)

    if f.stage == "parse":
        span = (_source_line_span(model, job.model_text, f.line)
                if f.line is not None and job.via == "prism" else None)
        return diag("E411", f"Storm cannot read the generated {route} model: {first}", span,
                    f"this is a bug in afsmc's {route} backend; --via "
                    f"{'jani' if job.via == 'prism' else 'prism'} may work meanwhile")
    if f.stage == "property":
        return diag("E402", f"Storm cannot check property '{prop.name if prop else f.prop}': "
                    f"{first}", prop.span if prop else None, engine_hint)
    if f.stage == "build":
        span = None
        for v in model.variables:
            if re.search(rf"\b{re.escape(v.name)}\b", f.message):
                span = v.span
                break
        return diag("E403", f"Storm cannot build the {job.what}: {first}", span, engine_hint)
    if f.stage == "check":
        return diag("E404", f"Storm failed to check '{prop.name if prop else f.prop}' on the "
                    f"{job.what}: {first}", prop.span if prop else None, engine_hint)
    if f.stage == "too-big":
        return diag("E405", first, None,
                    "raise --max-states if the machine has the memory" + (
                        " (the sparse engine needs about 250 bytes per state)"
                        if job.engine in ("sparse", "auto") else "")
                    + ", or check a smaller instance with --const")
    if f.stage == "memory":
        if job.engine in ("hybrid", "dd"):
            return diag("E406", first, None, "this one check needs more memory than the "
                        "machine has, even symbolically; check a smaller instance with --const, "
                        "or leave this property out with --property")
        return diag("E406", first, None, "check a smaller instance with --const, or try "
                    "--engine hybrid, which stores the model symbolically")
    return diag("E406", f"internal error while running Storm: {first}", None)


# ---- checking ----------------------------------------------------------------------


def _one_query(res: JobResult) -> bool:
    """Whether a process failed at one query rather than at the model: a check Storm could
    not do, a property it could not read, or a check that ran out of memory or crashed
    after the model was built. The model's other queries may still be answered."""
    f = res.failure
    assert f is not None
    if f.prop == TERMINATES:
        # a graph analysis every Pmax of the model depends on: as if the model failed
        return False
    if f.stage in ("check", "property"):
        return True
    return f.stage in ("memory", "internal") and res.states > 0


def _stats(res: JobResult, resolution: str) -> ModelStats:
    return ModelStats(res.kind, resolution, res.states, res.transitions, res.choices,
                      res.parse_time, res.build_time, res.check_time, res.engine,
                      res.engine_reason, res.quotient_states, res.quotient_transitions,
                      res.bisimulation_time, solver=res.solver)


# ---- Pmax as 1 - Pmin ------------------------------------------------------------------
# The hybrid engine needs far more memory for Pmax than for Pmin: for a maximum Storm
# removes end components from the explicit matrix of the "maybe" states, a second copy of
# it (on the paper's scenario 1 one such check passed 19 GB; its Pmin fitted). When the
# target lies inside the final (absorbing) modes and every path ends in a final mode
# (Pmin [F final] = 1, which Storm decides by graph analysis alone), the events "F target"
# and "F (final & !target)" are complementary under every scheduler, so
# Pmax [F target] = 1 - Pmin [F (final & !target)], exactly.

TERMINATES = "__afsmc_terminates"
REST = "__afsmc_rest_"
DUAL = "__afsmc_dual_"  # P[G<=k φ] asked as 1 - P[F<=k !φ]


def dual(p: ir.Property) -> ir.Property:
    return globally_dual(p, DUAL + p.name)


def _conjuncts(e: E.Expr) -> list[E.Expr]:
    if isinstance(e, E.Binary) and e.op == "&&":
        return _conjuncts(e.left) + _conjuncts(e.right)
    return [e]


def _within_final(target: E.Expr, model: ir.Model) -> bool:
    """Whether a conjunct of `target` that reads only the mode is false in every
    non-final mode."""
    others = [m.number for m in model.modes if not m.final]
    for c in _conjuncts(inline(target, model)):
        if E.vars_read(c) or not E.reads_mode(c):
            continue
        try:
            if not any(bool(evaluate(c, Env(mode=m, consts=model.const_values)))
                       for m in others):
                return True
        except EvalError:
            continue
    return False


def complements(model: ir.Model, props: Sequence[ir.Property]) -> dict[str, ir.Property]:
    """`NAME_max` -> the property Pmin [F (final & !target)] that gives it as 1 - value."""
    finals = {m.number for m in model.modes if m.final}
    if not finals or not model.is_nondeterministic:
        return {}
    final = E.mode_in(finals, model.mode_names)
    out = {}
    for p in props:
        path = p.path
        if p.kind != "P" or p.opt == "min" or not isinstance(path, ir.Path) \
                or path.kind != "F" or path.bound is not None \
                or not _within_final(path.target, model):
            continue
        name = p.name if p.opt == "max" else f"{p.name}_max"
        out[name] = ir.Property(f"{REST}{p.name}", "P", "min",
                                ir.Path("F", E.conj(final, E.neg(path.target))), None, p.span)
    if out:
        out[TERMINATES] = ir.Property(TERMINATES, "P", "min", ir.Path("F", final), None,
                                      props[0].span)
    return out


def _rewrite(queries: list[tuple[ir.Property, str]],
             comp: dict[str, ir.Property]) -> list[tuple[ir.Property, str]]:
    """Ask the complementary Pmin (and whether every path ends) instead of each Pmax."""
    out: list[tuple[ir.Property, str]] = []
    for p, n in queries:
        if n in comp:
            if TERMINATES not in [m for _, m in out]:
                out.append((comp[TERMINATES], TERMINATES))
            out.append((comp[n], comp[n].name))
        else:
            out.append((p, n))
    return out


def _unanswered(queries: list[tuple[ir.Property, str]], vals: dict[str, float],
                comp: dict[str, ir.Property]) -> list[tuple[ir.Property, str]]:
    """The queries without an answer yet; a Pmax whose complementary Pmin has one (and
    termination, which decides how it is used) counts as answered."""
    return [(p, n) for p, n in queries if n not in vals
            and not (n in comp and comp[n].name in vals and TERMINATES in vals)]


def _after_failure(res: JobResult, job: Job, unit: list[tuple[ir.Property, str]],
                   vals: dict[str, float], use: dict[str, ir.Property], failed: set[str],
                   owner: dict[str, str], texts: Mapping[str, str],
                   diagnose: Callable[[StormFailure], Diagnostic],
                   ) -> tuple[list[Diagnostic], list[tuple[ir.Property, str]], str | None]:
    """A process failed at one query (or at the model: the caller decides). Its errors,
    the queries of `unit` to ask again in a fresh process, and the query it failed at (None
    if it names none); adds to `failed` what is not to be asked again: the query, and all of
    its property when Storm cannot check it (min and max alike), or every open query when
    the failure names none."""
    f = res.failure
    assert f is not None
    # the guard's phase may still name a query that had been answered when the process died
    bad = f.prop if f.prop not in vals else None
    open_ = _unanswered(unit, vals, use)
    # "auto" found hybrid and refused all these at once (Job.symbolic_refused)
    refused = ([n for _, n in open_ if n in job.symbolic_refused and n != bad]
               if res.engine == "hybrid" and bad in job.symbolic_refused else [])
    ds = [diagnose(x) for x in [f, *(dataclasses.replace(f, prop=n) for n in refused)]]
    ds = [dataclasses.replace(d, message=_readable(d.message, texts)) for d in ds]
    if f.stage in ("memory", "internal") and (bad is not None or open_):
        # the same words for every process stopped at this size: say which query it was
        what = (f" while checking {_query_text(bad, texts)}" if bad is not None else
                "; not answered: " + ", ".join(_query_text(n, texts) for _, n in open_))
        ds[0] = dataclasses.replace(ds[0], message=ds[0].message + what)
    if bad is None:
        failed.update(n for _, n in open_)
        return ds, [], None
    failed.update([bad, *refused])
    if f.stage in ("check", "property") and not bad.startswith(REST):
        # what Storm cannot check of a property's min, it cannot of its max (the complement
        # of a Pmax is another formula: it only fails itself)
        failed.update(n for n, o in owner.items() if o == owner.get(bad, ""))
    retry = _not_failed(open_, failed, use)
    if len(retry) == len(open_):
        # nothing answered and nothing left out: the same process would fail the same way
        failed.update(n for _, n in open_)
        return ds, [], bad
    return ds, retry, bad


def _not_failed(queries: list[tuple[ir.Property, str]], failed: set[str],
                comp: dict[str, ir.Property]) -> list[tuple[ir.Property, str]]:
    """The queries to ask still: not one that failed, nor a Pmax whose complementary Pmin
    failed (Pmax itself needs more memory)."""
    return [(p, n) for p, n in queries
            if n not in failed and not (n in comp and comp[n].name in failed)]


def _duals(props: Sequence[ir.Property]) -> dict[str, tuple[str, str]]:
    """The queries of the duals (`dual`) -> the query of the bounded-G property whose value
    each gives, as 1 - value, and the progress lines' wording of it (from the property
    itself: its own name may end in `_min`)."""
    out = {}
    for p in props:
        if bounded_globally(p):
            # a DTMC, or an MDP property with Pmin/Pmax: the dual asks the other bound
            asked = {"min": "max", "max": "min"}.get(p.opt or "", "")
            out[DUAL + p.name] = (p.name, f"{p.name} as 1 - P{asked} [F<=k !φ]")
            if not p.opt:
                out[f"{DUAL}{p.name}_min"] = (f"{p.name}_max",
                                              f"{p.name}_max as 1 - Pmin [F<=k !φ]")
                out[f"{DUAL}{p.name}_max"] = (f"{p.name}_min",
                                              f"{p.name}_min as 1 - Pmax [F<=k !φ]")
    return out


def _kept(done: Sequence[tuple[str, dict[str, float]]], comp: Mapping[str, ir.Property],
          duals: Mapping[str, str] | None = None,
          heading: str = "answered before this") -> list[Diagnostic]:
    """A note with the values answered before a failure: a long run keeps what it got."""
    gives = {p.name: name for name, p in comp.items()}  # complementary Pmin -> its Pmax
    lines = []
    for what, vals in done:
        ends = vals.get(TERMINATES) == 1.0
        for name, value in vals.items():
            if name == TERMINATES or (name in gives and not ends):
                continue
            if name in gives:
                name, value = gives[name], 1.0 - value
            if duals and name in duals:
                name, value = duals[name], 1.0 - value
            lines.append(f"  {name} = {value!r} on the {what}")
    if not lines:
        return []
    return [Diagnostic("N412", Severity.NOTE, f"{heading}:\n" + "\n".join(lines), None)]


def _query_text(name: str, duals: Mapping[str, str]) -> str:
    """The one wording for a query, in every progress line: the queries afsmc asks instead
    of a Pmax or a bounded G are named by what they give, not by their internal names."""
    if name == TERMINATES:
        return "termination"
    if name.startswith(REST):
        return f"{name[len(REST):]}_max as 1 - Pmin"
    return duals.get(name, name)


def _unit_text(unit: list[tuple[ir.Property, str]], i: int,
               units: list[list[tuple[ir.Property, str]]], duals: Mapping[str, str]) -> str:
    """'query 3 of 14 (missed_min)' or 'process 1 of 2: 10 queries (success_min, ...)'."""
    if len(unit) == 1:
        order = list(dict.fromkeys(n for u in units for _, n in u))
        return (f"query {order.index(unit[0][1]) + 1} of {len(order)} "
                f"({_query_text(unit[0][1], duals)})")
    names = ", ".join(_query_text(n, duals) for _, n in unit)
    return f"process {i + 1} of {len(units)}: {len(unit)} queries ({names})"


def _readable(text: str, duals: Mapping[str, str]) -> str:
    """The guard's progress lines carry the internal names; say what they are."""
    return re.sub(re.escape(REST) + r"\w+|" + re.escape(DUAL) + r"\w+|" + re.escape(TERMINATES),
                  lambda m: _query_text(m.group(0), duals), text)


def _so_far(seconds: float) -> str:
    if seconds < 120:
        return f"{seconds:.0f} s so far"
    return f"{seconds / 60:.0f} min so far"


def _add(a: ModelStats, b: ModelStats) -> ModelStats:
    """Two Storm runs of one model (--split): times add up, sizes are the same."""
    return dataclasses.replace(
        a, parse_time=a.parse_time + b.parse_time, build_time=a.build_time + b.build_time,
        check_time=a.check_time + b.check_time,
        bisimulation_time=a.bisimulation_time + b.bisimulation_time,
        processes=a.processes + b.processes)


# Below this upper bound (modes × variable ranges) "auto" goes straight to the sparse
# engine. The bound overestimates reachable states by 10^3-10^4 on missions like the UAV,
# so such models are small; if one is not, the memory guard stops the build. Above it, a
# symbolic build counts the states first (a few seconds of fixed cost).
AUTO_SPARSE_BOUND = 1_000_000_000


def choose_engine(engine: Engine, bound: int) -> tuple[Engine, str]:
    """`auto` with a small upper bound is simply sparse; otherwise the job decides."""
    if engine == "auto" and bound <= AUTO_SPARSE_BOUND:
        return "sparse", (f"at most {human(bound)} states by the variables' ranges: the sparse "
                          "engine is fastest at this size")
    return engine, ""


def _total_reward(p: ir.Property) -> bool:
    """An unbounded `R [ C ]`: Storm's symbolic engines return no result for it."""
    return isinstance(p.path, ir.RewardPath) and p.path.kind == "C" and p.path.bound is None


def _bounded_state_cumulative(p: ir.Property, model: ir.Model) -> bool:
    """`R [ C<=k ]` of a structure with state rewards on an MDP: Storm's hybrid engine
    returns a wrong minimum for it (the reward of the first step only; sparse and dd are
    right, and so is hybrid on a DTMC or with action rewards only)."""
    if not (model.is_nondeterministic and isinstance(p.path, ir.RewardPath)
            and p.path.kind == "C" and p.path.bound is not None):
        return False
    rs = next((r for r in model.rewards if r.name == p.reward), None)
    return rs is None or any(it.action is None for it in rs.items)


def symbolic_gap(p: ir.Property, model: ir.Model, engine: Engine) -> str | None:
    """Why Storm's `engine` (hybrid, dd; "auto" if it may pick hybrid) cannot be trusted
    with `p`, or None."""
    if engine not in ("hybrid", "dd", "auto"):
        return None
    if _total_reward(p):
        return "an unbounded total reward (R [ C ]): Storm returns no result for it"
    if engine != "dd" and _bounded_state_cumulative(p, model):
        return ("a step-bounded cumulative reward (R [ C<=k ]) of state rewards on an MDP: "
                "Storm's hybrid engine gets its minimum wrong")
    return None


def _refuse_symbolic(props: Sequence[ir.Property], model: ir.Model, engine: Engine) -> None:
    """E404 before any build, for what Storm's symbolic engines cannot check (symbolic_gap),
    which they would say only after building, or not at all. ("auto" learns its engine in
    the Storm process: Job.symbolic_refused.)"""
    if engine not in ("hybrid", "dd"):
        return
    bad = [(p, why) for p in props if (why := symbolic_gap(p, model, engine)) is not None]
    if bad:
        raise CompileError([Diagnostic(
            "E404", Severity.ERROR, f"the {engine} engine cannot check '{p.name}', {why}",
            p.span, hint=_symbolic_hint(p)) for p, why in bad])


# Above this many state-steps (states x step bound), a check runs in a child process.
IN_PROCESS_WORK = 500_000_000


def _steps(p: ir.Property, model: ir.Model) -> int:
    """The step bound of `p` (F<=k, C<=k, I=k, ...), or 1 if it has none."""
    k = p.path.bound
    v = static_value(k, model) if k is not None else None
    return max(1, int(v)) if v is not None and math.isfinite(v) else 1


def _symbolic_hint(p: ir.Property) -> str:
    if _total_reward(p):
        return "use --engine sparse, a step bound (C<=k), or R [ F target ]"
    return "use --engine sparse or --engine dd"


def check(model: ir.Model, props: Sequence[ir.Property], *, via: Via = "prism",
          engine: Engine = "sparse", max_states: int | None = None, uniform: bool = True,
          isolate: bool | None = None, progress: Progress | None = None,
          reductions: Reductions | None = None, bisimulation: bool = False,
          split: bool = False, memory_budget: int | None = None,
          preserve: Sequence[ir.Property] = (), all_states: bool = False,
          solver: Solver = "auto") -> Checks:
    """Check `props` (uniquely named) on a loaded model; raises CompileError on failure.

    `preserve`: further properties that the reductions keep exact but that are not checked
    (a sweep's other points, so that every chunk of it builds the same model).
    `all_states`: Storm builds every reachable state even for one property (Job.all_states),
    so that the state counts do not depend on how the properties are split over processes.
    `solver`: how Storm solves the equation systems (storm.Solver).
    `max_states`: None is the default limit, which the sparse engine only has: there the
    state count predicts the memory. The symbolic engines' memory is held by the guard
    instead (85% of the free memory), and "auto" picks hybrid only for a model whose
    sparse matrices would not fit.

    `split`: one Storm process per query (a property, or an MDP property's min or max), each
    building the model afresh. Costs a build per query, but a process's memory is that of
    one check. Without it the hybrid engine (chosen, or picked by "auto") uses two processes
    per model: one for the expected rewards, one with larger decision-diagram tables for the
    probabilities (each Pmax as 1 - the complementary Pmin). If a process of several queries
    fills its tables, the queries it had not answered go on in a fresh process; if it runs
    out of memory, they follow one per process."""
    started = time.perf_counter()
    original = list(props)
    pairs = _duals(original)
    duals = {q: gives for q, (gives, _) in pairs.items()}
    texts = {q: text for q, (_, text) in pairs.items()}
    if progress is not None:
        say = progress
        progress = lambda text: say(_readable(text, texts))  # noqa: E731
    props = [dual(p) if bounded_globally(p) else p for p in props]
    preserve = [dual(p) if bounded_globally(p) else p for p in preserve]
    bound = upper_bound(model)
    engine, reason = choose_engine(engine, bound)
    _refuse_symbolic(props, model, engine)
    # Only the hybrid engine needs them ("auto" may still pick it after counting states).
    comp = complements(model, props) if engine in ("hybrid", "auto") else {}
    model = dataclasses.replace(model, properties=tuple(props) + tuple(
        p for n, p in sorted(comp.items())) + tuple(preserve))
    lows: list[tuple[str, Lowered, str]] = []
    if model.is_nondeterministic:
        lows.append(("nondet", lowered(model, "nondet", reductions), "MDP"))
        if uniform:
            lows.append(("uniform", lowered(model, "uniform", reductions), "uniform DTMC"))
    else:
        lows.append(("nondet", lowered(model, "nondet", reductions), "DTMC"))
    stats: list[ModelStats | None] = []  # None: every process of that model failed
    values: list[dict[str, float]] = []
    timings: list[dict[str, float]] = []  # each query's check time, as `values`
    model_queries: list[list[str]] = []  # each model's queries, as `values`
    # Failures of one query (not of the model): the other queries go on, and these are
    # raised at the end with every answer, so that one query does not cost an hour's others.
    errors: list[Diagnostic] = []

    def kept(what: str, vals: dict[str, float]) -> list[Diagnostic]:
        """The note of what the finished models and this one have answered."""
        done = [*zip([w for _, _, w in lows], values, strict=False), (what, vals)]
        return _kept(done, comp, duals)

    # a bounded G's query -> its dual's, whose value it is 1 minus (min and max swapped)
    asked_as = {query: its for its, query in duals.items()}

    def results() -> list[PropertyResult]:
        """One result per property from the models answered so far (None where not)."""
        out = []
        for p in original:
            r = PropertyResult(p.name, shown(p), p.kind)
            variants = ([(opt, 0, name) for name, opt in property_variants(lows[0][1], p)]
                        + ([("uniform", 1, p.name)] if len(lows) > 1 else [])
                        if lows[0][1].kind == "mdp" else [("value", 0, p.name)])
            for key, which, name in variants:
                if which >= len(values):
                    continue
                v = values[which].get(asked_as.get(name, name))
                if v is None:
                    continue
                setattr(r, key, 1.0 - v if name in asked_as else v)
                secs = timings[which].get(asked_as.get(name, name))
                if secs is not None:
                    r.seconds[key] = secs
            out.append(r)
        return out

    def partial(more: dict[str, float] | None = None, secs: dict[str, float] | None = None,
                built: ModelStats | None = None) -> Partial | None:
        """What to keep of a failed run (None if nothing was answered). `more`, `secs` and
        `built`: the values, times and stats of the model being checked, if it stops before
        the end of its loop (its Pmax still as complements: converted as `_kept` does)."""
        n = len(values)
        if more is not None:
            more = dict(more)
            if more.get(TERMINATES) == 1.0:
                more |= {name: 1.0 - more[rest.name] for name, rest in comp.items()
                         if name != TERMINATES and rest.name in more}
            values.append(more)
            timings.append(secs or {})
        try:
            rs = results()
        finally:
            del values[n:], timings[n:]
        if not any(getattr(r, k) is not None for r in rs for k in ("min", "max", "uniform",
                                                                    "value")):
            return None
        models = [*stats, built, None, None]
        return Partial(models[0], models[1], rs)
    for resolution, low, what in lows:
        # A query is one Storm check: a property, or an MDP property's min or its max.
        queries = [(p, n) for p in props for n, _ in property_variants(low, p)]
        model_queries.append([n for _, n in queries])
        by_name = {n: (p, n) for p, n in queries}
        use = comp if low.kind == "mdp" else {}
        # query -> its property's name (a complementary Pmin: that of the Pmax it gives)
        owner = {n: p.name for p, n in queries} | {
            use[n].name: p.name for p, n in queries if n in use}

        def plan(qs: list[tuple[ir.Property, str]], hybrid: bool,
                 use: dict[str, ir.Property] = use) -> list[list[tuple[ir.Property, str]]]:
            """Queries -> Storm processes. Hybrid: each Pmax as 1 - the complementary Pmin;
            the expected rewards in one process, with small decision-diagram tables (their
            minimum needs the most explicit memory: 18.8 GB on scenario 1), the probabilities
            in another, with large tables (their complementary targets need them)."""
            if not hybrid:
                return [[q] for q in qs] if split and len(qs) > 1 else [qs] if qs else []
            if split:
                return [[q] for q in _rewrite(qs, use)]
            rewards = [q for q in qs if q[0].kind != "P"]
            probabilities = _rewrite([q for q in qs if q[0].kind == "P"], use)
            return [u for u in (rewards, probabilities) if u]

        units = plan(queries, engine == "hybrid")
        merged: ModelStats | None = None
        vals: dict[str, float] = {}
        secs: dict[str, float] = {}
        job_engine = engine
        # Once the guard reran one complementary Pmin query with full tables, the later ones
        # start with them: they share their shape, Pmin [F final & !target] (on scenario 1
        # three of five outgrew 1 GB, 43-144 s into their processes). The other queries keep
        # the default: the expected rewards' minimum needs it to stay under 20 GB.
        rest_full_tables = False
        lost, lost_processes = 0.0, 0  # processes that failed after answering some queries
        # The model's sizes as a failed process reported them, should no process succeed
        # (their times are all in `lost`, counted as checking).
        built: ModelStats | None = None

        def sizes(res: JobResult, known: ModelStats | None,
                  resolution: str = resolution) -> ModelStats | None:
            if known is not None or not res.states:
                return known
            return dataclasses.replace(_stats(res, resolution), parse_time=0.0,
                                       build_time=0.0, check_time=0.0, processes=0)
        failed: set[str] = set()  # queries whose check failed (in `errors`)
        # Pmax -> its complementary Pmin, while a Pmax may still be answered that way (not
        # after termination is known: a Pmax asked then is asked itself)
        pending = use
        rest_errors: dict[str, Diagnostic] = {}  # a complementary Pmin's error
        i = 0
        while True:
            if i == len(units) and (TERMINATES in vals or TERMINATES in failed):
                # Pmax = 1 - Pmin of the rest, if every path ends; else (or if that could
                # not be checked) ask Pmax itself.
                ends = vals.pop(TERMINATES, None) == 1.0
                failed.discard(TERMINATES)
                secs.pop(TERMINATES, None)  # a graph analysis, shared by every Pmax
                pending = {}
                if not ends:  # the complements are not used: nor are their errors
                    errors[:] = [d for d in errors if d not in rest_errors.values()]
                direct = []
                for name, rest in use.items():
                    if name == TERMINATES or name in failed:
                        continue
                    v, t = vals.pop(rest.name, None), secs.pop(rest.name, 0.0)
                    if ends and v is not None:
                        vals[name], secs[name] = 1.0 - v, t
                    elif not ends and name in by_name:
                        direct.append(by_name[name])
                    # else the Pmin failed: its error says so (Pmax needs more memory still)
                if ends and progress is not None:
                    progress(f"every path of the {what} ends in a final mode: each Pmax [F target] "
                             "is 1 - Pmin [F (final & !target)], which needs less memory")
                # the complements are asked on the hybrid engine only: one process each
                units += [[q] for q in direct]
            if i == len(units):
                break
            unit = units[i]
            group = list(dict.fromkeys(p for p, _ in unit))
            if job_engine == "hybrid":
                # "auto" picked hybrid in an earlier process (--split): what the hybrid engine
                # cannot check is refused before building, and the rest goes on
                gaps = [n for p, n in unit if symbolic_gap(p, model, job_engine) is not None]
                if gaps:
                    try:
                        _refuse_symbolic(group, model, job_engine)
                    except CompileError as exc:
                        errors.extend(d for d in exc.diagnostics if d not in errors)
                    failed.update(gaps)
                    units[i] = unit = _not_failed(unit, failed, pending)
                    if not unit:
                        i += 1
                        continue
                    group = list(dict.fromkeys(p for p, _ in unit))
            limit = max_states if max_states is not None else (
                default_max_states() if job_engine == "sparse" else None)
            # "auto" checks what the hybrid engine would check first, if it picks that: with
            # probabilities only, that includes the queries standing in for each Pmax.
            first = [n for _, n in plan(unit, True)[0]] if job_engine == "auto" else []
            mine = [n for _, n in unit]
            extra = tuple(n for n in first if n not in mine)
            job = make_job(low, group, via, job_engine, limit, what, bisimulation,
                           memory_budget, only=tuple(mine),
                           hybrid_skip=tuple(n for n in mine if n not in first),
                           hybrid_extra=extra)
            job = dataclasses.replace(job, solver=solver, all_states=all_states)
            if job_engine == "auto":
                job = dataclasses.replace(job, symbolic_refused=tuple(
                    n for p, n in unit if symbolic_gap(p, model, "auto") is not None))
            complementary = any(n.startswith(REST) for _, n in unit) and all(
                n.startswith(REST) or n == TERMINATES for _, n in unit)
            # The probabilities' process (its complementary targets need the larger tables;
            # for "auto" they only take memory while the symbolic model lives).
            big_tables = (job_engine == "hybrid" and len(unit) > 1 and all(
                p.kind == "P" for p, _ in unit)) or bool(extra)
            if big_tables or (complementary and rest_full_tables):
                job = dataclasses.replace(job, dd_memory_mb=DD_MEMORY_RETRY)
            if big_tables and (extra or any(n.startswith(REST) for _, n in unit)):
                # should they fall back to a process each, they keep the larger tables
                rest_full_tables = True
            # A fresh process per unit when there are several, except where no child
            # process may be started (isolate=False: Dask workers).
            fresh = isolate if isolate is False or len(units) == 1 else True
            if fresh is None and bound * max(_steps(p, model) for p in group) > IN_PROCESS_WORK:
                # A small model with a huge step bound (F<=10^11) checks for hours, and a
                # check in this process ignores Ctrl-C and SIGTERM; a child can be stopped.
                fresh = True
            if progress is not None and len(units) > 1:
                # Long runs (scenario 1: over an hour) say how far they are.
                where = ("in its own Storm process" if len(unit) == 1 else
                         "in one Storm process" + (f" with {job.dd_memory_mb} MB decision-"
                                                   "diagram tables" if big_tables else ""))
                progress(f"{what}, {_unit_text(unit, i, units, texts)} {where}; "
                         f"{_so_far(time.perf_counter() - started)}")
            try:
                res = run_job(job, bound, isolate=fresh, progress=progress)
            except KeyboardInterrupt as exc:
                # An hour's answers are not lost to a Ctrl-C: the CLI prints the errors and
                # notes and, for --json, the answers as data.
                got = exc.values if isinstance(exc, Interrupted) else {}
                raise Stopped(errors, [d.message for d in kept(what, vals | got)],
                              partial(vals | got, secs, merged or built)) from exc
            failure = res.failure
            # What the process set out to check ("auto" adds and leaves some for hybrid).
            asked = len(job.hybrid_queries if res.engine == "hybrid" else job.names)
            if failure is not None and asked > 1 and fresh is not False and (
                    failure.stage == "tables" or (failure.stage in ("memory", "internal")
                    and "hybrid" in (job_engine, res.engine))):
                # A process for several queries failed: keep what it answered and plan the
                # others again.
                vals |= res.values
                secs |= res.seconds
                # its time counts as checking: it answered some of the queries
                lost, lost_processes = lost + res.elapsed, lost_processes + 1
                built = sizes(res, built)
                left = _unanswered(unit, vals, use)
                # "auto" leaves here only after a hybrid check (sparse fills no tables, and
                # a sparse process out of memory is not retried).
                head, *later = ([_unanswered(u, vals, use) for u in plan(left, True)]
                                if job_engine == "auto" else [left]) or [[]]
                job_engine = "hybrid"
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
                if progress is not None:
                    progress(f"{failure.message}; {len(res.values)} of its {asked} "
                             f"queries were answered, {then}")
                units = units[:i + 1] + [u for u in again if u] + later + units[i + 1:]
                i += 1
                continue
            if res.failure is not None:
                vals |= res.values
                secs |= res.seconds
                built = sizes(res, built)
                diagnose = functools.partial(failure_diagnostic, model=model, low=low,
                                             props=group, job=job)
                ds, retry, bad = _after_failure(res, job, unit, vals, pending, failed, owner,
                                                texts, diagnose)
                if bad is not None and bad.startswith(REST):
                    rest_errors[bad] = ds[0]  # no error if the complement is not used
                if not _one_query(res):
                    raise CompileError([*errors, *ds, *kept(what, vals)],
                                       partial(vals, secs, merged or built))
                for d in ds:
                    if d not in errors:  # a min and a max: one error
                        errors.append(d)
                lost, lost_processes = lost + res.elapsed, lost_processes + 1
                i += 1
                later = [u for u in (_not_failed(u, failed, pending) for u in units[i:]) if u]
                if job_engine == "auto" and res.engine == "hybrid":
                    job_engine = "hybrid"  # as after an answer (below)
                    units = units[:i] + [u for u in (_unanswered(u, vals, use) for u in plan(
                        retry + [q for u in later for q in u], True)) if u]
                else:
                    units = units[:i] + ([retry] if retry else []) + later
                if progress is not None:
                    more = len(units) > i or what != lows[-1][2]
                    progress(f"{ds[0].code}: {ds[0].message.rstrip('.')}; "
                             + ("the other queries go on, and " if more else "")
                             + "the error is reported at the end")
                continue
            if complementary and res.dd_retried and not rest_full_tables:
                rest_full_tables = True
                if progress is not None:
                    progress(f"the {what}'s further complementary Pmin queries start with "
                             f"{DD_MEMORY_RETRY} MB decision-diagram tables")
            if reason and not res.engine_reason:
                res.engine_reason = reason
            one = _stats(res, resolution)
            merged = one if merged is None else _add(merged, one)
            vals |= res.values
            secs |= res.seconds
            i += 1
            if job_engine == "auto" and res.engine == "hybrid":
                # "auto" chose hybrid: the queries it left (Job.hybrid_skip) and any later
                # ones follow as the hybrid engine wants them.
                job_engine = "hybrid"
                left = _unanswered([q for u in [unit, *units[i:]] for q in u], vals, use)
                units = units[:i] + [u for u in (_unanswered(u, vals, use)
                                                 for u in plan(left, True)) if u]
                if progress is not None and left:
                    progress(f"the {what} is checked with the hybrid engine: "
                             + ("one query per Storm process" if split else
                                "the other queries follow in one more Storm process"))
        # merged is None only when every process failed (then `errors`): the sizes a
        # failed one reported, if any
        merged = merged or built
        stats.append(None if merged is None else dataclasses.replace(
            merged, check_time=merged.check_time + lost,
            processes=merged.processes + lost_processes))
        values.append(vals)
        timings.append(secs)
    # every query without a value is named, whatever the reason it was not asked
    missing = [f"{_query_text(n, duals)} on the {what}"
               for (_, _, what), names, vals in zip(lows, model_queries, values, strict=True)
               for n in names if n not in vals]
    if missing and not errors:  # a bug: say so rather than fail below
        errors.append(Diagnostic("E406", Severity.ERROR, "internal error: no answer and no "
                                 f"error for {', '.join(missing)}", None))
    if errors:
        notes = _kept(list(zip([w for _, _, w in lows], values, strict=True)), comp, duals,
                      "the other queries were answered")
        if missing:
            text = "not answered: " + ", ".join(missing)
            notes = ([dataclasses.replace(notes[0], message=f"{notes[0].message}\n{text}")]
                     if notes else [Diagnostic("N412", Severity.NOTE, text, None)])
        raise CompileError([*errors, *notes], partial())
    main, *uniform_model = stats  # the MDP or only DTMC, then the uniform DTMC if any
    assert main is not None and None not in uniform_model  # else `errors` above
    return Checks(main, uniform_model[0] if uniform_model else None, results())


def const_text(v: object) -> str:
    """A constant's value as --const takes it and the language writes it (`true`, not
    Python's `True`): the API also takes Python numbers."""
    if isinstance(v, str):
        return v
    if isinstance(v, bool):
        return "true" if v else "false"
    return str(v) if isinstance(v, int) else repr(float(typing.cast(float, v)))


def check_choice(option: str, value: object, allowed: object) -> None:
    """The API's Literal options, checked: a misspelt engine or via ran as sparse/PRISM."""
    names = typing.get_args(allowed)
    if value not in names:
        raise ValueError(f"{option} must be one of " + ", ".join(map(repr, names))
                         + f"; got {value!r}")


@deep
def run(path: str, *, consts: Mapping[str, str | bool | int | float] | None = None,
        properties: Sequence[str] = (),
        formulas: Sequence[str] = (), via: Via = "prism", engine: Engine = "sparse",
        max_states: int | None = None, uniform: bool = True, isolate: bool | None = None,
        progress: Progress | None = None, text: str | None = None,
        reductions: Reductions | None = None, bisimulation: bool = False,
        split: bool = False, memory_budget: int | None = None,
        solver: Solver = "auto") -> VerifyResult:
    """Verify one .afsm file; see the package docstring. Raises CompileError, or
    ValueError for an unknown `via`, `engine` or `solver`."""
    check_choice("via", via, Via)
    check_choice("engine", engine, Engine)
    check_choice("solver", solver, Solver)
    t0 = time.perf_counter()
    texts = None if consts is None else {k: const_text(v) for k, v in consts.items()}
    loaded = load_with_formulas(path, texts, formulas, text=text)
    model = loaded.model
    props = select(model, properties, loaded.adhoc)
    load_time = time.perf_counter() - t0
    limit = default_max_states() if max_states is None else max_states
    bound = upper_bound(model)
    if progress is not None:
        progress(f"state space: at most {human(bound)} states (modes × variable ranges); "
                 f"--max-states {limit:,}" + (" for the sparse engine" if max_states is None
                                               and engine != "sparse" else ""))
    try:
        checks = check(model, props, via=via, engine=engine, max_states=max_states,
                       uniform=uniform, isolate=isolate, progress=progress, reductions=reductions,
                       bisimulation=bisimulation, split=split, memory_budget=memory_budget,
                       solver=solver)
    except CompileError as exc:
        raise loaded.remap_error(exc) from None
    consts_used: dict[str, object] = {c.name: c.value for c in model.constants if c.is_param}
    return VerifyResult(path, model.name, consts_used, via, engine, bound, limit, checks.model,
                        checks.uniform_model, checks.properties, load_time,
                        time.perf_counter() - t0, loaded.warnings)
