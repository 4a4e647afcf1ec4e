"""`afsmc regions FILE --param NAME=LO:HI ... --require 'P>=0.6 [ F "success" ]'`: the
parameter box split into regions where the requirement holds for every value, fails for
every value, or is undecided (afsmc.verify.reports.regions)."""

from __future__ import annotations

import argparse
import os
import re
import sys
import time
from typing import Any, Literal

from afsmc.commands.common import (
    JOBS_HELP,
    MAX_JOB_TASKS,
    add_consts,
    add_file,
    answer_json,
    dask_address,
    fail,
    integer,
    number,
    overrides,
    refuse_jobs,
    usage_error,
)
from afsmc.compiler import lowered
from afsmc.diagnostics import CompileError, Diagnostic, Severity, codes
from afsmc.files import PLOT_SUFFIXES, check_writable, write_atomic
from afsmc.lower.lowering import Lowered
from afsmc.model import expr as E
from afsmc.model import ir
from afsmc.text import num
from afsmc.verify.core.api import load_with_formulas
from afsmc.verify.core.uncertainty import LIFTING, bound_error
from afsmc.verify.engines.guard import default_max_states
from afsmc.verify.engines.parametric import extreme_queries, extremes_on, with_parameters
from afsmc.verify.engines.storm import VIAS
from afsmc.verify.lifting import bounds as lifting_bounds
from afsmc.verify.lifting import model as lifting_model
from afsmc.verify.lifting import order as lifting_order
from afsmc.verify.outcome.verdicts import judge
from afsmc.verify.plan.deep import refuse_deep_build
from afsmc.verify.plan.precision import PARAMETER_PRECISION
from afsmc.verify.reports import regions as R

MAX_ROUNDS = 24  # rounds of halving; each may double the undecided boxes checked in the next


def add_arguments(p: argparse.ArgumentParser) -> None:
    add_file(p)
    add_consts(p)
    p.add_argument("--param", action="append", default=[], metavar="NAME=LO:HI",
                   help="a parameter and its range; repeatable. A 'param double', a "
                        "'const prob' or an interval probability, used only in probabilities. "
                        "Interval probabilities of the file not named here vary over their "
                        "interval as further parameters (the output names them)")
    p.add_argument("--require", required=True, metavar="PROPERTY",
                   help="a bounded property in .afsm syntax, e.g. 'P>=0.6 [ F \"success\" ]'")
    p.add_argument("--coverage", type=number(0, 1), default=0.95,
                   help="refine until this fraction of the box's volume is decided, in "
                        "(0, 1] (default 0.95)")
    p.add_argument("--max-rounds", type=integer(1, MAX_ROUNDS), default=12,
                   help="stop refining after this many rounds of halving, 1 to "
                        f"{MAX_ROUNDS} (default 12)")
    p.add_argument("--jobs", "-j", type=integer(1, MAX_JOB_TASKS), default=1,
                   help="local processes checking the boxes of a round (default 1; "
                        f"{JOBS_HELP}); each builds the parametric model once, which on the "
                        "UAV costs more than the checks it shares out")
    p.add_argument("--dask", metavar="ADDRESS", type=dask_address,
                   help="check the boxes on a Dask cluster (scheduler address) instead")
    p.add_argument("--via", choices=VIAS, default="prism",
                   help="Storm's input language: PRISM text (default) or JANI JSON")
    p.add_argument("--feasible", action="store_true",
                   help="also find one valuation that meets the requirement "
                        "(Storm's feasibility check) and print it as --const flags")
    p.add_argument("--plot", metavar="FILE.png|.svg",
                   help="draw the regions over two parameters (see --axes); with more "
                        "parameters, each cell shows the verdict over the others")
    p.add_argument("--axes", metavar="X,Y",
                   help="the two parameters the plot shows (default: the first two)")
    p.add_argument("--summary", action="store_true",
                   help="print the summary only, not the table of regions (the text "
                        "output; --json always lists the regions)")
    p.add_argument("--json", action="store_true", help="print the regions as JSON")


def _error(code: object, message: str, span: object = None, hint: str | None = None
           ) -> CompileError:
    return CompileError([Diagnostic(code, Severity.ERROR, message, span,  # type: ignore[arg-type]
                                    hint=hint)])


def parse_params(items: list[str]) -> dict[str, tuple[float, float]]:
    out: dict[str, tuple[float, float]] = {}
    for item in items:
        m = re.fullmatch(r"\s*([A-Za-z_][A-Za-z0-9_]*)\s*=\s*([^:]+):([^:]+)\s*", item)
        try:
            lo, hi = (float(m.group(2)), float(m.group(3))) if m else (None, None)
        except ValueError:
            lo = hi = None
        if m is None or lo is None or hi is None:
            raise _error(codes.E441, f"--param {item!r}: expected NAME=LO:HI",
                         hint="e.g. --param ALPHA=0.05:0.2")
        if not lo <= hi:
            raise _error(codes.E441, f"--param {item}: the range is empty",
                         hint="write NAME=LO:HI with LO <= HI")
        out[m.group(1)] = (lo, hi)
    return out


def _reads(e: E.Expr, name: str, model: ir.Model) -> bool:
    for n in E.walk(e):
        if isinstance(n, E.ConstRef) and n.name == name:
            return True
        if isinstance(n, E.FormulaRef) and _reads(model.formula(n.name).value, name, model):
            return True
    return False


def misuse(low: Lowered, name: str) -> str | None:
    """Where `name` is read other than in a probability: Storm's parametric models allow
    parameters in transition probabilities only."""
    model = low.model
    for cmd in low.commands:
        if _reads(cmd.guard, name, model):
            return f"the guard or weight of {cmd.action}"
        for b in cmd.branches:
            if any(_reads(v, name, model) for _, v in b.updates):
                return f"an update of {cmd.action}"
    for lb in model.labels:
        if _reads(lb.value, name, model):
            return f"label {lb.name}"
    for r in model.rewards:
        if any(_reads(it.guard, name, model) or _reads(it.value, name, model) for it in r.items):
            return f"reward structure {r.name}"
    for c in model.constants:
        text = c.span.source.text[c.span.start:c.span.end]
        if c.name != name and re.search(rf"\b{re.escape(name)}\b", text.split("=", 1)[-1]):
            return f"the value of constant {c.name}"
    return None


def check_params(low: Lowered, box: dict[str, tuple[float, float]]) -> None:
    model = low.model
    names = {c.name: c for c in model.constants}
    variables = {v.name for v in model.variables} | {v.display for v in model.variables}
    for n, (lo, hi) in box.items():
        c = names.get(n)
        if c is None:
            labels = {lb.name for lb in model.labels}
            what = ("a variable" if n in variables else "a label" if n in labels
                    else "not declared")
            raise _error(codes.E441, f"--param {n}: '{n}' is {what}, not a constant",
                         hint="parameters are 'param double', 'const prob' or interval-"
                              "probability constants: " + ", ".join(
                                  k for k, v in names.items() if v.type is E.Type.DOUBLE))
        if c.type is not E.Type.DOUBLE:
            art = "an" if c.declared_type[:1] in ("a", "e", "i", "o", "u") else "a"
            raise _error(codes.E441, f"--param {n}: '{n}' is {art} {c.declared_type} constant; "
                         "a parameter is a probability or a double", c.span,
                         hint="an integer figure is an interval constant [lo, hi] "
                              "(floor/ceil), or swept with `afsmc sweep`")
        where = misuse(low, n)
        if where is not None:
            raise _error(codes.E441, f"--param {n}: '{n}' is read in {where}, not only in "
                         "probabilities", c.span,
                         hint="Storm's parametric engine takes parameters in transition "
                              "probabilities only; sweep it with `afsmc sweep` instead")
        if c.declared_type == "prob" and not (lo >= 0.0 and hi <= 1.0):
            raise _error(codes.E441, f"--param {n}={lo:g}:{hi:g}: a probability's range lies "
                         "within [0, 1]", c.span,
                         hint=f"e.g. --param {n}={max(lo, 1e-6):g}:{min(hi, 0.999999):g}")


def run(args: argparse.Namespace) -> int:
    t0 = time.perf_counter()
    refuse_jobs(args.jobs, args.dask)
    if args.plot and os.path.splitext(args.plot)[1].lower() not in PLOT_SUFFIXES:
        # matplotlib draws other formats, or fails after the whole computation
        usage_error(f"--plot {args.plot}: the name must end in .png or .svg")
    say = None if args.json else (lambda s: print(f"afsmc: {s}", file=sys.stderr, flush=True))
    try:
        if args.plot is not None:  # said before the run, not after it
            check_writable(args.plot, protect=(args.file,))
        req = R.parse_requirement(args.require)
        box = parse_params(args.param)
        loaded = load_with_formulas(args.file, overrides(args), [req.query()])
        model = loaded.model
        from_file = []
        for c in model.prob_intervals:
            if c.prob_interval is not None and c.name not in box:
                box[c.name] = c.prob_interval
                from_file.append(c.name)
        if not box:
            raise _error(codes.E441, "no parameters: pass --param NAME=LO:HI",
                         hint="or declare an interval probability, const prob P = [lo, hi]")
        low = lowered(model, "nondet")
        # the parametric build has no state limit: a counter too deep is refused before it
        refuse_deep_build(low, "Storm's parametric build", default_max_states(),
                          hint="check a smaller instance with --const",
                          limit_name="the state limit (what the free memory holds)")
        check_params(low, box)
        axes = args.axes.split(",") if args.axes else list(box)[:2]
        if args.plot is not None and (not 1 <= len(axes) <= 2 or any(a not in box for a in axes)
                          or len(set(axes)) < len(axes)):
            usage_error(f"--axes {args.axes}: name one or two different parameters of "
                        + ", ".join(box))
        prop = next(p for p in model.properties if p.name == loaded.adhoc[0])
        res = solve(args, low, req, prop, box, say)
        res.from_file = from_file
        res.seconds = time.perf_counter() - t0
        if args.plot is not None:
            from afsmc.commands.render.regions_plot import plot

            write_atomic(args.plot, plot(res, axes, os.path.splitext(args.plot)[1].lstrip(".")),
                         protect=(args.file,))
    except CompileError as exc:
        return fail(exc, args.json, wrapped=True)
    except OSError as exc:  # the Dask scheduler is unreachable, or no process could start
        return fail(CompileError([Diagnostic(
            codes.E413, Severity.ERROR, f"the region checks' workers: {exc}", None,
            hint=f"is a Dask scheduler running at {args.dask}?" if args.dask else None)]),
            args.json, wrapped=True)
    if args.json:
        print(answer_json("regions", res.to_json()))
    else:
        fixed = [c.name for c in model.constants if c.name in box and not c.is_param]
        print(render(res, fixed, summary=args.summary))
    return 0


def solve_lifted(args: argparse.Namespace, low: Lowered, req: R.Requirement,
                 prop: ir.Property, box: dict[str, tuple[float, float]], say: Any
                 ) -> R.RegionResult | None:
    """The regions and the verdict over the whole box by parameter lifting on afsmc's
    explorer (afsmc.verify.lifting); None where it does not take the mission (Storm's
    parametric engine then answers, `solve`)."""
    qs, targets, rewards, left = lifting_model.queries(low, [prop])
    if left:
        return None
    try:
        lifted = lifting_model.build(low, box, targets, rewards)
    except lifting_model.NotLiftable as why:
        if say is not None:
            say(f"parameter lifting on afsmc's explorer does not take it ({why}): Storm's "
                "parametric engine checks the regions")
        return None
    # renumbered once, for the corners' point passes (afsmc.verify.lifting.order), and
    # the original let go: the bounds below give the same values on either
    lifted = lifting_order.dependent_first(lifted)
    if say is not None:
        say(f"afsmc's explorer: {lifted.states:,} states; each box decided by exact corner "
            "values where the value is proven monotone over it, else by parameter lifting")
    regions, rounds = R.refine_lifted(lifted, R.lifted_query(req, qs[0], low.kind == "mdp"),
                                      req, box, coverage=args.coverage,
                                      max_rounds=args.max_rounds, progress=say)
    res = R.RegionResult(req.text, box, regions, 0.0, args.coverage, rounds,
                         states=lifted.states, engine=LIFTING)
    (e,), gaps = lifting_bounds.extremes(lifted, qs, PARAMETER_PRECISION)
    error = max(bound_error(None), gaps[prop.name])
    res.bounds = (e.min_attained, e.max_attained, error)
    res.judged = judge(threshold_of(req), e.min_attained, e.max_attained, error)
    return res


def solve(args: argparse.Namespace, low: Lowered, req: R.Requirement, prop: ir.Property,
          box: dict[str, tuple[float, float]], say: Any) -> R.RegionResult:
    from afsmc.backends.prism import PrismPrinter, formula_text

    lifted = solve_lifted(args, low, req, prop, box, say)
    if lifted is not None:
        _meaning(lifted, low, req)
        if args.feasible:
            lifted.feasible, lifted.feasible_how = feasible(None, "", lifted)
        return lifted

    query = formula_text(prop, prop.opt, PrismPrinter({}, low))
    # the requirement's bounds over the whole box are asked of the same parametric build
    bound_queries = extreme_queries(with_parameters(low, box), [prop])
    src, formulas, built = R.prepare(low, list(box), req, query, args.via,
                                     also=sorted({q.text for q in bound_queries[prop.name]}))
    regions, rounds = R.refine(low, src, formulas, built, box, coverage=args.coverage,
                               jobs=max(1, args.jobs), dask=args.dask,
                               max_rounds=args.max_rounds, progress=say)
    res = R.RegionResult(req.text, box, regions, 0.0, args.coverage, rounds,
                         states=built.model.nr_states)
    _meaning(res, low, req)
    # the verdict over the whole box: the requirement's bounds over it, judged as verify
    # judges (docs/verification.md, "What a result means")
    (e,) = extremes_on(built, bound_queries, [prop], box, PARAMETER_PRECISION)
    error = bound_error(None)
    res.bounds = (e.min_attained, e.max_attained, error)
    res.judged = judge(threshold_of(req), e.min_attained, e.max_attained, error)
    if args.feasible:
        res.feasible, res.feasible_how = feasible(built, formulas[0], res)
    return res


def _meaning(res: R.RegionResult, low: Lowered, req: R.Requirement) -> None:
    """The coverage, and what a region's verdict means on an MDP with a bare requirement."""
    res.coverage = res.fraction("holds") + res.fraction("fails")
    if low.kind == "mdp" and not req.opt:
        worst, best = ("min", "max") if req.cmp in (">=", ">") else ("max", "min")
        res.meaning = (f"on this MDP a region holds where every floor/ceil choice meets the "
                       f"requirement (its {worst} does) and fails where some choice misses "
                       f"it: there `afsmc verify` says fails or depends, as its {best} "
                       "decides")


def threshold_of(req: R.Requirement) -> ir.Threshold:
    """The requirement's comparison as verify's IR holds it (the bound as written)."""
    ops: dict[str, Literal["<=", ">=", "<", ">"]] = {">=": ">=", ">": ">", "<=": "<=",
                                                     "<": "<"}
    return ir.Threshold(ops[req.cmp], req.bound, repr(req.bound))


def feasible(built: object, formula: str, res: R.RegionResult
             ) -> tuple[dict[str, float], str]:
    """One valuation meeting the requirement: Storm's feasibility check, or, where Storm
    refuses the box (its graph-preservation test fails on several parameters) or the
    regions came from afsmc's explorer (`built` None), the centre of the largest region
    proven to hold."""
    from afsmc.verify.engines.parametric import Parametric

    if isinstance(built, Parametric):
        try:
            found = built.feasible(formula, res.box)
            return (found, "Storm's feasibility check (parameter lifting)") if found \
                else ({}, "")
        except CompileError:
            pass
    holds = [r for r in res.regions if r.verdict == "holds"]
    if not holds:
        return {}, ""
    best = max(holds, key=lambda r: r.volume(res.box))
    return ({n: (lo + hi) / 2 for n, (lo, hi) in best.bounds.items()},
            "the centre of the largest region where it holds")


LONG = 20  # a table of more regions than this ends with a pointer to --summary


def render(res: R.RegionResult, fixed: list[str] | None = None, *,
           summary: bool = False) -> str:
    """The regions as a table (not with `summary`), then the shares of the volume and the
    verdict over the whole box; `fixed` names the parameters declared 'const' (not
    'param'), which a --const flag cannot set."""
    lines = [f"{res.requirement} over " + ", ".join(
        f"{n} in [{lo:g}, {hi:g}]" for n, (lo, hi) in res.box.items())]
    lines += from_file_lines(res)
    if not summary:
        lines += ["", *table(res)]
    if res.meaning:
        lines += ["", res.meaning]
    lines.append("")
    lines.append(f"holds on {res.fraction('holds'):.1%} of the volume, fails on "
                 f"{res.fraction('fails'):.1%}, unknown {res.fraction('unknown'):.1%}: "
                 f"coverage {res.coverage:.1%} (target {res.target:.0%}); "
                 f"{len(res.regions)} regions, {res.rounds} rounds, {res.states:,} states, "
                 f"{res.seconds:.1f} s")
    verdict, reason = res.verdict()
    if res.bounds is not None:
        lo, hi, error = res.bounds
        lines.append(f"over the whole box: min {num(lo)}, max {num(hi)}, each within "
                     f"{num(error)} ({res.engine}, as `afsmc verify`)")
    lines.append(f"over the whole box: {verdict} ({reason})")
    if res.feasible == {}:
        lines.append("feasible: Storm found no valuation that meets the requirement")
    elif res.feasible is not None:
        lines.append("feasible: " + " ".join(f"--const {n}={v:.6g}"
                                             for n, v in sorted(res.feasible.items()))
                     + f" ({res.feasible_how})")
        shown = [n for n in sorted(res.feasible) if n in (fixed or [])]
        if shown:
            lines.append(f"  --const sets only a 'param': {', '.join(shown)} "
                         f"{'is' if len(shown) == 1 else 'are'} declared 'const', so write "
                         "the value in the file, or declare it 'param double'")
    if not summary and len(res.regions) > LONG:
        lines.append(f"({len(res.regions)} regions listed above; --summary prints the "
                     "summary only)")
    return "\n".join(lines)


def from_file_lines(res: R.RegionResult) -> list[str]:
    """Which dimensions of the box no --param named: the file's interval probabilities."""
    if not res.from_file:
        return []
    one = len(res.from_file) == 1
    names = ", ".join(f"{n} in [{res.box[n][0]:g}, {res.box[n][1]:g}]" for n in res.from_file)
    what = ("an interval probability that no --param names, varied over its interval"
            if one else
            "interval probabilities that no --param names, varied over their intervals")
    return [f"from the file: {names} ({what}; --param NAME=LO:HI sets a range)"]


def table(res: R.RegionResult) -> list[str]:
    """One row per region: its side along each parameter, and its verdict."""
    names = list(res.box)
    rows = [[*names, "verdict"]]
    order = {"holds": 0, "fails": 1, "unknown": 2}
    for r in sorted(res.regions, key=lambda r: (order[r.verdict],
                                                [r.bounds[n] for n in names])):
        rows.append([f"[{r.bounds[n][0]:.6g}, {r.bounds[n][1]:.6g}]" for n in names]
                    + [r.verdict])
    widths = [max(len(r[i]) for r in rows) for i in range(len(rows[0]))]
    return ["  ".join(c.ljust(w) for c, w in zip(r, widths, strict=True)).rstrip()
            for r in rows]
