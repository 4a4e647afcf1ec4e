"""Storm's failures as afsmc diagnostics (E402-E406, E411), and what the symbolic engines
cannot be trusted with (E404 before any build).

`failure_diagnostic` words one failure; `after_failure` decides which of a process's
queries fail with it and which are asked again; `one_query` tells a failed query from a
failed model.
"""

from __future__ import annotations

import dataclasses
import os
import re
from collections.abc import Callable, Mapping, Sequence

from afsmc.backends.prism import property_variants
from afsmc.check.storm_refuses import signed_total
from afsmc.diagnostics import CompileError, Diagnostic, Severity, Span, codes
from afsmc.lower.lowering import Lowered
from afsmc.model import ir
from afsmc.verify.engines.stopping import large_variables
from afsmc.verify.engines.storm import Engine, Job, JobResult, StormFailure
from afsmc.verify.plan.queries import (
    REST,
    TERMINATES,
    Query,
    not_failed,
    query_text,
    readable,
    unanswered,
)


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
        return diag(codes.E411, f"Storm cannot read the generated {route} model: {first}", span,
                    f"this is a bug in afsmc's {route} backend; --via "
                    f"{'jani' if job.via == 'prism' else 'prism'} may work meanwhile")
    if f.stage == "property":
        return diag(codes.E402, f"Storm cannot check property '{prop.name if prop else f.prop}': "
                    f"{first}", prop.span if prop else None, engine_hint)
    if f.stage == "build":
        span = None
        for v in model.variables:
            if re.search(rf"\b{re.escape(v.name)}\b", f.message):
                span = v.span
                break
        return diag(codes.E403, f"Storm cannot build the {job.what}: {first}", span, engine_hint)
    if f.stage == "check":
        return diag(codes.E404, f"Storm failed to check '{prop.name if prop else f.prop}' on the "
                    f"{job.what}: {first}", prop.span if prop else None, engine_hint)
    if f.stage == "too-big":
        large = large_variables(model)
        return diag(codes.E405, first + (f"; the largest ranges: {large}" if large else ""),
                    None, "raise --max-states if the machine has the memory" + (
                        " (the sparse engine needs about 250 bytes per state)"
                        if job.engine in ("sparse", "auto") else "")
                    + ", or check a smaller instance with --const")
    if f.stage == "scratch":
        return diag(codes.E419, first, None, "free some space on that disk, give --scratch a "
                    "directory on a larger one, or give --no-scratch (in memory)")
    if f.stage == "memory":
        if job.engine in ("hybrid", "dd"):
            return diag(codes.E406, first, None, "this one check needs more memory than the "
                        "machine has, even symbolically; check a smaller instance with --const, "
                        "or leave this property out with --property")
        return diag(codes.E406, first, None, "check a smaller instance with --const, or try "
                    "--engine hybrid, which stores the model symbolically")
    return diag(codes.E406, f"internal error while running Storm: {first}", None)


def one_query(res: JobResult) -> bool:
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



def after_failure(res: JobResult, job: Job, unit: list[Query],
                   vals: dict[str, float], use: dict[str, ir.Property], failed: set[str],
                   owner: dict[str, str], texts: Mapping[str, str],
                   diagnose: Callable[[StormFailure], Diagnostic],
                   ) -> tuple[list[Diagnostic], list[Query], str | None]:
    """A process failed at one query (or at the model: the caller decides). Its errors,
    the queries of `unit` to ask again in a fresh process, and the query it failed at (None
    if it names none); adds to `failed` what is not to be asked again: the query, and all of
    its property when Storm cannot check it (min and max alike), or every open query when
    the failure names none."""
    f = res.failure
    assert f is not None
    # the guard's phase may still name a query that had been answered when the process died
    bad = f.prop if f.prop not in vals else None
    open_ = unanswered(unit, vals, use)
    # "auto" found hybrid and refused all these at once (Job.symbolic_refused)
    refused = ([n for _, n in open_ if n in job.symbolic_refused and n != bad]
               if res.engine == "hybrid" and bad in job.symbolic_refused else [])
    ds = [diagnose(x) for x in [f, *(dataclasses.replace(f, prop=n) for n in refused)]]
    ds = [dataclasses.replace(d, message=readable(d.message, texts)) for d in ds]
    if f.stage in ("memory", "internal") and (bad is not None or open_):
        # the same words for every process stopped at this size: say which query it was
        what = (f" while checking {query_text(bad, texts)}" if bad is not None else
                "; not answered: " + ", ".join(query_text(n, texts) for _, n in open_))
        ds[0] = dataclasses.replace(ds[0], message=ds[0].message + what)
    if bad is None:
        failed.update(n for _, n in open_)
        return ds, [], None
    failed.update([bad, *refused])
    if f.stage in ("check", "property") and not bad.startswith(REST):
        # what Storm cannot check of a property's min, it cannot of its max (the complement
        # of a Pmax is another formula: it only fails itself)
        failed.update(n for n, o in owner.items() if o == owner.get(bad, ""))
    retry = not_failed(open_, failed, use)
    if len(retry) == len(open_):
        # nothing answered and nothing left out: the same process would fail the same way
        failed.update(n for _, n in open_)
        return ds, [], bad
    return ds, retry, bad



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


def refuse_symbolic(props: Sequence[ir.Property], model: ir.Model, engine: Engine,
                    via: str = "prism") -> None:
    """E404 before any build, for what Storm's symbolic engines cannot check (symbolic_gap),
    which they would say only after building, or not at all ("auto" learns its engine in
    the Storm process: Job.symbolic_refused); and, on every engine, for a total reward that
    may be negative, which Storm refuses on an MDP and may answer with the wrong sign on a
    DTMC (+inf where the runs lose without end). Also E404 for a symbolic engine via
    PRISM on a mission whose agents write shared variables (writes_shared)."""
    signed = [(p, name) for p in props if (name := signed_total(p, model)) is not None]
    if signed:
        raise CompileError([Diagnostic(
            codes.E404, Severity.ERROR, f"afsmc does not ask Storm for '{p.name}', the total "
            f"reward of \"{name}\", which may be negative: Storm refuses it on an MDP and may "
            "answer +inf on a DTMC whose runs lose without end", p.span,
            hint=f"ask R{{\"{name}\"}}=? [ C<=k ] for the first k steps, or R{{\"{name}\"}}=? "
                 "[ F ... ] up to the mission's end; or keep every reward >= 0")
            for p, name in signed])
    if engine not in ("hybrid", "dd"):
        return
    if via == "prism" and writes_shared(model):
        raise symbolic_globals(engine, model.composition)
    bad = [(p, why) for p in props if (why := symbolic_gap(p, model, engine)) is not None]
    if bad:
        raise CompileError([Diagnostic(
            codes.E404, Severity.ERROR, f"the {engine} engine cannot check '{p.name}', {why}",
            p.span, hint=_symbolic_hint(p)) for p, why in bad])



def symbolic_globals(engine: str, composition: ir.Composition | None,
                     what: str = "shared variables") -> CompileError:
    """E404: the symbolic `engine` via PRISM on a mission whose agents write `what`."""
    return CompileError([Diagnostic(
        codes.E404, Severity.ERROR, f"the {engine} engine cannot check this mission: its "
        f"agents write {what}, which afsmc's PRISM writes as global variables updated by "
        "labelled commands, and Storm's symbolic builder builds those wrongly (too few "
        "states)", composition.span if composition else None,
        hint="use --engine sparse (or auto, which builds it sparse), or --via jani")])


def writes_shared(model: ir.Model) -> bool:
    """Whether a composed mission's agents write shared variables, which its PRISM
    declares global and updates in labelled commands: Storm's sparse builder builds those
    right, its symbolic one (dd, hybrid, and the count before "auto" picks) with too few
    states. (The symmetry reduction's own globals: afsmc.verify.core.runner.)"""
    c = model.composition
    return c is not None and any(who for _, who in c.writers)


def _symbolic_hint(p: ir.Property) -> str:
    if _total_reward(p):
        return "use --engine sparse, a step bound (C<=k), or R [ F target ]"
    return "use --engine sparse or --engine dd"
