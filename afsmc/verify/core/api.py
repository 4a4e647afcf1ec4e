"""The verification API: `run` (a file), `check` (a loaded model), and the loading of a
file with ad-hoc formulas (`load_with_formulas`, `select`); `ask` answers PRISM queries of
the caller's own on a lowered model (the diagram's reachability of each mode).

See the package docstring (afsmc/verify/__init__.py) for the API.
"""

from __future__ import annotations

import dataclasses
import re
import time
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

from afsmc.backends.prism import emit as prism_emit
from afsmc.compiler import Checked, load, with_properties
from afsmc.diagnostics import CompileError, Diagnostic, Severity, codes
from afsmc.lower.lowering import Lowered
from afsmc.lower.reduce import Reductions
from afsmc.lower.symmetry import decide
from afsmc.model import ir
from afsmc.model.names import did_you_mean
from afsmc.stack import deep
from afsmc.syntax import ast
from afsmc.syntax.parser import parse_property
from afsmc.text import count, literal
from afsmc.verify.core import conditioning
from afsmc.verify.core.model_loop import ModelLoop
from afsmc.verify.core.options import VerifyOptions
from afsmc.verify.core.runner import CheckRun, Options
from afsmc.verify.core.uncertainty import kept_at_midpoint, over_probabilities, sources
from afsmc.verify.engines.guard import Progress, default_max_states, run_job, upper_bound
from afsmc.verify.engines.storm import Engine, Job, StormFailure
from afsmc.verify.engines.strategy_storm import WitnessRequest
from afsmc.verify.outcome.results import Checks, PropertyResult, VerifyResult
from afsmc.verify.outcome.strategy import extras, witness_request
from afsmc.verify.outcome.verdicts import judge_all
from afsmc.verify.plan.precision import DEFAULT_PRECISION, check_options
from afsmc.verify.stream.scratch import unusable


def _fresh_name(text: str, base: str, taken: set[str]) -> str:
    """`base`, or `base2`, `base3`...: the first name neither taken nor a word of `text`."""
    n, name = 1, base
    while name in taken or re.search(rf"\b{name}\b", text):
        n += 1
        name = f"{base}{n}"
    taken.add(name)
    return name


@dataclass(frozen=True)
class Loaded:
    """A checked model with the ad-hoc formulas among its properties (`adhoc`: their
    names, in the order of the formulas), and the warnings of loading it."""

    model: ir.Model
    warnings: list[Diagnostic]
    adhoc: list[str]


def parse_formulas(formulas: Sequence[str], text: str,
                   taken: Sequence[str] = ()) -> list[tuple[str, ast.PQuery | ast.RQuery]]:
    """Each formula parsed on its own, so that a syntax error speaks of the formula alone,
    and named `adhoc`, `adhoc2`...: the first names that are no word of the file's `text`
    (nor in `taken`)."""
    names: set[str] = set(taken)
    out = []
    for f in formulas:
        if ";" in f:
            raise CompileError([Diagnostic(
                codes.E409, Severity.ERROR, f"--formula {f!r}: one property, without ';'", None,
                hint="repeat --formula for several properties")])
        out.append((_fresh_name(text, "adhoc", names), parse_property(f, "--formula")))
    return out


def load_with_formulas(path: str, overrides: Mapping[str, str] | None = None,
                       formulas: Sequence[str] = (), *, text: str | None = None,
                       run_checks: bool = True, checked: Checked | None = None) -> Loaded:
    """Load `path` (or use `checked`, that file loaded already) and resolve each formula
    against its model as a property of its own (afsmc.compiler.with_properties)."""
    from afsmc.files import read_source

    if checked is None:
        base = read_source(path) if text is None else text
        queries = parse_formulas(formulas, base)
        checked = load(path, overrides, text=base, run_checks=run_checks)
    else:
        queries = parse_formulas(formulas, checked.model.source.text)
    full = with_properties(checked, queries, run_checks=run_checks)
    return Loaded(full.model, list(full.diagnostics), [n for n, _ in queries])


def select(model: ir.Model, names: Sequence[str], adhoc: Sequence[str] = ()) -> list[ir.Property]:
    """The properties to check: those named (else every declared one) and the ad-hoc ones."""
    declared = [p for p in model.properties if p.name not in adhoc]
    if not names and not adhoc:
        if not declared:
            raise CompileError([Diagnostic(
                codes.E407, Severity.ERROR, f"{model.source.path} declares no properties", None,
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
            diags.append(Diagnostic(codes.E407, Severity.ERROR, f"--property {n}: no property named "
                                    f"'{n}' in {model.source.path}", None,
                                    hint=did_you_mean(n, by_name) or (
                                        "properties: " + ", ".join(by_name) if by_name else None)))
    if diags:
        raise CompileError(diags)
    out += [p for p in model.properties if p.name in adhoc]
    return out


def check(model: ir.Model, props: Sequence[ir.Property],
          options: VerifyOptions | None = None, *, progress: Progress | None = None,
          preserve: Sequence[ir.Property] = (), all_states: bool = False,
          witness: WitnessRequest | None = None, **option_values: Any) -> Checks:
    """Check `props` (uniquely named) on a loaded model; raises CompileError on failure.
    `options` (or its fields as keywords, `engine="hybrid"`): how (VerifyOptions); its
    `witness` is resolved against the properties by the caller and given as `witness`.

    `preserve`: further properties that the reductions keep exact but that are not checked
    (a sweep's other points, so that every chunk of it builds the same model).
    `all_states`: Storm builds every reachable state even for one property (Job.all_states),
    so that the state counts do not depend on how the properties are split over processes.
    `solver`: how Storm solves the equation systems (storm_solvers.Solver).
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
    out of memory, they follow one per process.

    `precision`: sound mode, every value within it of the true one (absolute); `exact`:
    exact arithmetic (sparse engine). A property with a threshold (a requirement) makes the
    check sound at `verdicts`' DEFAULT_PRECISION unless either is given; each requirement's
    result then has its `verdict` (afsmc.verify.outcome.verdicts)."""
    o = VerifyOptions.of(options, option_values)
    if o.scratch is not None and o.no_scratch:
        raise CompileError([Diagnostic(codes.E419, Severity.ERROR,
                                       "--scratch and --no-scratch together", None,
                                       hint="give --scratch DIR to stream through DIR, or "
                                            "--no-scratch to keep the model in memory")])
    if o.scratch is not None and (why := unusable(o.scratch)) is not None:
        raise CompileError([Diagnostic(codes.E419, Severity.ERROR, f"--scratch: {why}", None,
                                       hint="give an existing directory you can write to, "
                                            "or leave --scratch out (in memory, or the "
                                            "system temp directory if the model needs it)")])
    # the symmetry reduction, decided once for every front-end
    o = dataclasses.replace(o, reductions=decide(o.reductions, symmetry_hindrance(o, witness)))
    precision, engine = sound_mode(props, o.precision, o.exact, o.engine)
    # kappa, the expected number of steps, for the rounding's bound on the values in sound
    # mode (afsmc.verify.core.conditioning)
    asked = conditioning.ask(model, props) if precision is not None and not o.exact \
        else conditioning.Asked(model, None)
    checking = CheckRun(asked.model, asked.properties(props), list(preserve), engine,
                        o.uniform, progress, o.reductions,
                        Options.of(o, all_states, precision, witness))
    for resolution, low, what in checking.lows:
        ModelLoop(checking, resolution, low, what).check_all()
    # kappa too is bounded over the interval probabilities' box: its largest value there
    at_points = checking.finish()
    try:
        checks, box, errors = over_probabilities(
            at_points, asked.model, props, via=o.via, reductions=o.reductions,
            precision=None if o.exact else precision, preserve=preserve, progress=progress,
            beside=asked.properties(()))
    except CompileError as exc:  # the values at the midpoint are not lost with the bounds
        kept, partial = kept_at_midpoint(conditioning.steps(at_points, asked)[0])
        raise CompileError([*exc.diagnostics, *kept], partial) from None
    checks, kappa = conditioning.steps(checks, asked)
    box = conditioning.without_steps(box)
    judged = conditioning.ordered(
        judge_all(checks.properties, 0.0 if o.exact else precision, errors))
    if precision is not None and not o.exact:
        judged = _rounding_accounted(judged, kappa, model, props, o, checks, progress)
    return dataclasses.replace(checks, properties=judged, uncertainty=sources(model),
                               probability=box, symmetry=at_points.symmetry)


def symmetry_hindrance(o: VerifyOptions, witness: WitnessRequest | None) -> str | None:
    """What asked for stands in the way of the default symmetry reduction, in words
    (afsmc.lower.symmetry.decide): an output that names the agents, or a symbolic engine
    via PRISM (the reduced agents write each other's variables, which Storm's symbolic
    PRISM builder gets wrong)."""
    shown = [name for name, asked in (("--strategy", o.strategy),
                                      ("--witness", witness is not None)) if asked]
    if shown:
        return (f"{' and '.join(shown)} name{'s' if len(shown) == 1 else ''} the agents, "
                "which the reduction's canonical order would turn into slots "
                "(--symmetry forces it)")
    if o.engine in ("dd", "hybrid") and o.via == "prism":
        return (f"the {o.engine} engine via PRISM: the reduced agents write each other's "
                "variables, which Storm's symbolic builder gets wrong (--via jani allows it)")
    return None


def _rounding_accounted(judged: list[PropertyResult], kappa: float | None, model: ir.Model,
                        props: Sequence[ir.Property], o: VerifyOptions, checks: Checks,
                        progress: Progress | None) -> list[PropertyResult]:
    """The requirements judged with the rounding of the built model accounted for, and
    those whose verdict it could change decided again: exactly, where the model is small
    enough and has no interval probabilities, else `undecided`."""
    acc = conditioning.account(judged, kappa)
    if not acc.redecide:
        return acc.results
    small = checks.model.states <= conditioning.EXACT_STATES and not model.prob_intervals

    def exact(names: list[str]) -> list[PropertyResult]:
        if progress is not None:
            progress(f"deciding {', '.join(names)} again with exact arithmetic: the "
                     "rounding of the model Storm built could change the verdict")
        again = dataclasses.replace(o, exact=True, precision=None, engine="sparse",
                                    uniform=False, strategy=False, witness=None)
        try:
            return check(model, [p for p in props if p.name in names], again,
                         progress=progress).properties
        except CompileError:
            return []  # the exact engine could not: undecided, with the widened error

    return conditioning.redecided(acc.results, acc.redecide, exact if small else None)


def sound_mode(props: Sequence[ir.Property], precision: float | None, exact: bool,
               engine: Engine) -> tuple[float | None, Engine]:
    """The precision to check at (a requirement's default if none is given) and the engine
    (exact: sparse); ValueError for a precision outside (0, 1), CompileError (E404) for an
    engine that cannot give what is asked."""
    requirement = next((p for p in props if p.threshold is not None), None)
    if precision is None and not exact and requirement is not None:
        precision = DEFAULT_PRECISION
    if precision is not None and not 0 < precision < 1:
        raise ValueError(f"precision must lie strictly between 0 and 1; got {precision!r}")
    why = check_options(precision, exact, engine)
    if why is not None:
        at = requirement.span if requirement is not None and not exact else None
        raise CompileError([Diagnostic(
            codes.E404, Severity.ERROR, why, at,
            hint="requirements and --precision need Storm's sound methods; --exact needs "
                 "exact arithmetic (docs/verification.md, \"Requirements\")")])
    return precision, "sparse" if exact else engine


@deep
def run(path: str, options: VerifyOptions | None = None, *,
        consts: Mapping[str, str | bool | int | float] | None = None,
        properties: Sequence[str] = (), formulas: Sequence[str] = (),
        progress: Progress | None = None, text: str | None = None,
        checked: Checked | None = None, **option_values: Any) -> VerifyResult:
    """Verify one .afsm file; see the package docstring. `options` (or its fields as
    keywords, `precision=1e-9`): how (VerifyOptions). `checked`: the file loaded already
    with these `consts` (afsmc.compiler.load; a Mission's), so that it is not loaded again.
    Raises CompileError, ValueError for an unknown `via`, `engine` or `solver`, TypeError
    for an unknown option."""
    o = VerifyOptions.of(options, option_values)
    t0 = time.perf_counter()
    texts = None if consts is None else {k: literal(v) for k, v in consts.items()}
    loaded = load_with_formulas(path, texts, formulas, text=text, checked=checked)
    model = loaded.model
    props = select(model, properties, loaded.adhoc)
    wanted = witness_request(model, props, o.strategy, o.witness, o.witness_dir,
                             o.witness_target)
    load_time = time.perf_counter() - t0
    limit = default_max_states() if o.max_states is None else o.max_states
    bound = upper_bound(model)
    if progress is not None:
        progress(f"state space: at most {count(bound)} states (modes × variable ranges); "
                 f"--max-states {limit:,}" + (" for the sparse engine" if o.max_states is None
                                               and o.engine != "sparse" else ""))
    checks = check(model, props, o, progress=progress, witness=wanted)
    if o.strategy or wanted is not None:
        checks = extras(checks, check, model, props, o.strategy, wanted,
                        max_states=o.max_states, progress=progress,
                        reductions=o.reductions, via=o.via)
    if wanted is not None and wanted.avoid:
        checks = dataclasses.replace(checks, properties=[
            dataclasses.replace(r, witness_avoids=r.witnesses is not None)
            for r in checks.properties])
    consts_used: dict[str, object] = {c.name: c.value for c in model.constants if c.is_param}
    return VerifyResult(path, model.name, consts_used, o.via, o.engine, bound, limit, checks.model,
                        checks.uniform_model, checks.properties, load_time,
                        time.perf_counter() - t0,
                        [*loaded.warnings, *symmetry_refused(checks, o.reductions)],
                        None if model.composition is None else model.composition.text,
                        checks.uncertainty, checks.probability, checks.symmetry)


def symmetry_refused(checks: Checks, reductions: Reductions | None) -> list[Diagnostic]:
    """N421 where `--symmetry` was asked and the mission or a property checked tells its
    alike agents apart (afsmc.lower.symmetry): the model was checked without it. (Where
    the default "auto" is not applied, the output's header says why instead.)"""
    note = checks.symmetry
    if reductions is None or reductions.symmetry != "on" or note is None \
            or note.reason is None:
        return []
    return [Diagnostic(codes.N421, Severity.NOTE, "no symmetry reduction (the model was "
                       f"checked whole): {note.reason}", note.where,
                       hint="docs/language.md, \"Symmetry\": every label, reward and "
                       "property must treat the alike agents alike")]


@dataclass
class Answers:
    """What Storm answered for :func:`ask`: the model's kind and size, and a value per
    query; or `failure`, why it answered none (the caller words it)."""

    kind: str  # "dtmc" | "mdp"
    states: int
    transitions: int
    values: dict[str, float] = field(default_factory=dict)
    failure: StormFailure | None = None


def ask(low: Lowered, queries: Mapping[str, str], *, bound: int, what: str,
        max_states: int | None = None, progress: Progress | None = None) -> Answers:
    """Answer `queries` (name -> a PRISM property of the generated model, such as
    `Pmin=? [ F mode=3 ]`) on the lowered model, built once by Storm's sparse engine under
    verify's guard: stopped at `max_states` (default: what the free memory holds) or when
    the memory runs short. `bound`: the model's upper bound (`upper_bound`), which decides
    whether Storm runs in a watched child process; `what` names the model in Storm's
    messages."""
    props = "".join(f'"{name}": {formula};\n' for name, formula in queries.items())
    limit = default_max_states() if max_states is None else max_states
    job = Job("prism", prism_emit(low).model, props, tuple(queries), "sparse", limit, what)
    res = run_job(job, bound, isolate=None, progress=progress)
    return Answers(res.kind, res.states, res.transitions, dict(res.values), res.failure)
