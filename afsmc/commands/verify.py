"""`afsmc verify FILE`: check the file's properties with Storm; min/max/uniform for an MDP."""

from __future__ import annotations

import argparse
import dataclasses
import sys
from collections.abc import Callable

from afsmc.api.results import verify_file
from afsmc.commands.common import (
    add_baseline_options,
    add_consts,
    add_file,
    add_reductions,
    answer_json,
    fail,
    integer,
    overrides,
    reductions,
    report,
    usage_error,
)
from afsmc.commands.render import verify_changes as changes
from afsmc.commands.render import verify_extras as extras
from afsmc.commands.render.requirements import (
    add_requirement_options,
    attained_lines,
    refuse_requirement_options,
    verdict_lines,
    with_verdicts,
)
from afsmc.diagnostics import CompileError
from afsmc.report import baseline as base
from afsmc.report.causes import split_file
from afsmc.text import literal, num
from afsmc.verify import VerifyResult
from afsmc.verify.core.options import VerifyOptions
from afsmc.verify.core.uncertainty import INTERVAL_CONSTANTS, described
from afsmc.verify.engines.guard import MAX_STATES_LIMIT
from afsmc.verify.engines.storm import ENGINES, VIAS
from afsmc.verify.engines.storm_solvers import SOLVERS
from afsmc.verify.outcome.results import ModelStats, PropertyResult, symmetry_words
from afsmc.verify.outcome.verdicts import failing
from afsmc.verify.reports.junit import write_junit

# --max-states N: 1 to MAX_STATES_LIMIT (the memory guard stops a build sooner)
positive = integer(1, MAX_STATES_LIMIT)


def add_storm_options(p: argparse.ArgumentParser) -> None:
    """Options `verify` and `sweep` share."""
    p.add_argument("--property", "-p", action="append", default=[], metavar="NAME",
                   help="check only this declared property; repeatable (default: all)")
    p.add_argument("--formula", "-f", action="append", default=[], metavar="PROPERTY",
                   help="check an ad-hoc property in .afsm syntax, e.g. "
                        "'P=? [ F \"done\" ]'; repeatable. With it, declared properties "
                        "are checked only if named with --property")
    p.add_argument("--via", choices=VIAS, default="prism",
                   help="Storm's input language: PRISM text (default) or JANI JSON")
    p.add_argument("--engine", choices=ENGINES, default="auto",
                   help="Storm's engine: auto (default: sparse when the model fits in memory "
                        "as sparse matrices, else hybrid, with the expected rewards and the "
                        "probabilities in two Storm processes; counts "
                        "the states symbolically first when they may be many), sparse "
                        "(explicit matrices), dd (decision diagrams throughout) or hybrid "
                        "(symbolic model, explicit vectors)")
    p.add_argument("--solver", choices=SOLVERS, default="auto",
                   help="how the equations (an MDP's min/max, a DTMC's linear) are "
                        "solved on the sparse and hybrid engines: auto (default: value "
                        "iteration on hybrid; on sparse one exact backward pass where the "
                        "model is acyclic but for self-loops, else topological), topological "
                        "(Storm's default: strongly connected components first) or "
                        "value-iteration (stops at a relative change of 1e-10)")
    p.add_argument("--bisim", action="store_true",
                   help="minimise the sparse model by strong bisimulation before checking "
                        "(exact; faster checks, more memory while building)")
    p.add_argument("--split", action="store_true",
                   help="run each query (a property; for an MDP its min and its max) in "
                        "its own Storm process, building the model again for each: slower, but "
                        "the memory is that of one check")
    add_reductions(p)
    p.add_argument("--max-states", type=positive, metavar="N",
                   help="stop (exit 1) if the model has more states than N, at most "
                        f"{MAX_STATES_LIMIT:,} (default, for "
                        "the sparse engine only: what 70%% of the free memory holds as sparse "
                        "matrices, at most 50 M; the symbolic engines are stopped by the "
                        "memory guard instead)")
    p.add_argument("--scratch", metavar="DIR",
                   help="afsmc's own exploration writes the model layer by layer to a "
                        "directory of its own in DIR (an existing, writable directory) and "
                        "reads it back for one backward pass: the memory is that of a window "
                        "of layers, not of the whole model; the directory is removed at the end "
                        "(default: in the system temp directory, once the exploration in "
                        "memory passes 2 M states or would take more than 65%% of the memory "
                        "available, going on from the states explored; "
                        "docs/verification.md#streaming-layers---scratch)")
    p.add_argument("--no-scratch", action="store_true",
                   help="keep afsmc's own exploration in memory, never streamed through "
                        "the disk (not with --scratch)")
    p.add_argument("--no-uniform", dest="uniform", action="store_false",
                   help="for an MDP, skip the uniform resolution of the interval constants")
    p.add_argument("--progress", action="store_true",
                   help="show progress on stderr even with --json")


def storm_options(args: argparse.Namespace) -> VerifyOptions:
    """The options `verify` and `sweep` share (add_storm_options), as one VerifyOptions."""
    return VerifyOptions(via=args.via, engine=args.engine, solver=args.solver,
                         max_states=args.max_states, uniform=args.uniform,
                         reductions=reductions(args), bisimulation=args.bisim,
                         split=args.split, scratch=args.scratch,
                         no_scratch=args.no_scratch)


def progress_printer(args: argparse.Namespace) -> Callable[[str], None] | None:
    if args.json and not args.progress:
        return None

    def say(text: str) -> None:
        print(f"afsmc: {text}", file=sys.stderr, flush=True)

    return say


def add_arguments(p: argparse.ArgumentParser) -> None:
    add_file(p)
    add_consts(p)
    add_storm_options(p)
    p.add_argument("--json", action="store_true",
                   help="print one JSON object: model, properties, timings")
    add_requirement_options(p)
    extras.add_arguments(p)
    p.add_argument("--causes", action="store_true",
                   help="split each probability of reaching a target (-p NAME: that one) "
                        "by cause: the hazard or action, and the mode, of the step that "
                        "first entered it (docs/report.md)")
    add_baseline_options(p)


def table(rows: list[list[str]], right: set[int]) -> list[str]:
    widths = [max(len(r[i]) for r in rows) for i in range(len(rows[0]))]
    out = []
    for r in rows:
        cells = [c.rjust(w) if i in right else c.ljust(w)
                 for i, (c, w) in enumerate(zip(r, widths, strict=True))]
        out.append("  ".join(cells).rstrip())
    return out


def _header(res: VerifyResult) -> str:
    """What the table's values are: the bounds over what is uncertain, or one value each."""
    over = described(res.uncertainty, res.probability, res.composition)
    if not over:
        who = (" (who moves next is uniform among the agents that can move)"
               if res.composition == "interleaving, uniform" else "")
        return f"{res.path}: a DTMC{who}: one value per property"
    refs = []
    if res.probability is not None:
        refs.append("midpoint has every interval probability at the middle of its interval")
    if any(_uniform(p) is not None for p in res.properties):
        refs.append(("midpoint_uniform" if res.probability is not None else "uniform")
                    + " picks floor or ceil at random")
    return (f"{res.path}: min and max bound every property over {over}"
            + (f"; reference points, never judged: {'; '.join(refs)}" if refs else ""))


def _uniform(p: PropertyResult) -> float | None:
    return p.uniform if p.reference is None else p.reference.uniform


def _midpoint(p: PropertyResult) -> str:
    """The answer at the interval probabilities' midpoint: min – max, or the value."""
    ref = p.reference
    if ref is None:
        return "-"
    if ref.value is not None:
        return num(ref.value)
    return f"{num(ref.min)}–{num(ref.max)}"


def _values_table(res: VerifyResult) -> list[list[str]]:
    if all(p.value is not None or p.min is None for p in res.properties) and \
            not res.uncertainty:
        return [["property", "formula", "value"]] + [
            [p.name, p.formula, num(p.value)] for p in res.properties]
    uniform = any(_uniform(p) is not None for p in res.properties)
    mid = res.probability is not None
    # with interval probabilities the uniform resolution is one at their midpoint: its
    # column says so, beside the midpoint's own min – max
    head = (["property", "formula", "min", "max"] + (["midpoint"] if mid else [])
            + (["midpoint_uniform" if mid else "uniform"] if uniform else []))
    return [head] + [[p.name, p.formula, num(p.min), num(p.max)]
                     + ([_midpoint(p)] if mid else [])
                     + ([num(_uniform(p))] if uniform else []) for p in res.properties]


def _model_name(res: VerifyResult, m: ModelStats) -> str:
    if m.resolution == "uniform":
        name = "uniform DTMC"
    elif m.type == "mdp":
        name = "floor/ceil MDP" if INTERVAL_CONSTANTS in res.uncertainty else "MDP"
    else:
        name = "DTMC"
    return name + (" (midpoint)" if res.probability is not None else "")


def render(res: VerifyResult) -> str:
    lines = [_header(res)]
    sym = symmetry_words(res.symmetry)
    if sym is not None:
        lines.append(sym)
    u = res.uniform_model
    rows = with_verdicts(_values_table(res), res.properties)
    lines.append("")
    lines += table(rows, set(range(2, len(rows[0]) - (rows[0][-1] == "verdict"))))
    lines += verdict_lines(res.properties)
    if res.probability is not None:
        lines += attained_lines(res.properties)
    lines.append("")
    models = [(_model_name(res, res.model), res.model)]
    if u is not None:
        models.append((_model_name(res, u), u))
    bisim = any(m.quotient_states is not None for _, m in models)
    mrows = [["model", "states", "transitions", "choices"] + (["quotient"] if bisim else [])
             + ["build", "check", "engine", "solver"]]
    for name, m in models:
        mrows.append([name, f"{m.states:,}", f"{m.transitions:,}",
                      f"{m.choices:,}" if m.choices else "-"]
                     + ([f"{m.quotient_states:,}" if m.quotient_states is not None else "-"]
                        if bisim else [])
                     + [f"{m.build_time + m.bisimulation_time:.3f} s"
                        + (f" ({m.processes} builds)" if m.processes > 1 else ""),
                        f"{m.check_time:.3f} s", m.engine,
                        m.solver.replace("-", " ") or "-"])
    lines += table(mrows, set(range(1, len(mrows[0]) - 2)))
    for name, m in models:
        if m.engine_reason and res.engine == "auto":
            lines.append(f"{name}: engine {m.engine} ({m.engine_reason})")
    if res.probability is not None:
        lines.append(f"the bounds over the interval probabilities: {res.probability.engine}, "
                     f"{res.probability.seconds:.3f} s")
    consts = ", ".join(f"{k}={literal(v)}" for k, v in res.constants.items())
    lines.append("")
    lines.append(f"engine {res.engine}, via {res.via}"
                 + (f", constants {consts}" if consts else "")
                 + f"; total {res.total_time:.2f} s")
    return "\n".join(lines)


def refuse_bisim_on_symbolic(args: argparse.Namespace) -> None:
    if args.bisim and args.engine in ("hybrid", "dd"):
        # Storm minimises only the sparse model; silently skipping it would mislead.
        usage_error(f"--bisim needs the sparse model: use it with --engine sparse or auto, "
                    f"not {args.engine}")


def run(args: argparse.Namespace) -> int:
    refuse_bisim_on_symbolic(args)
    refuse_requirement_options(args)
    if (args.strategy or args.witness is not None) and args.bisim:
        usage_error("--strategy and --witness need the built model's states: not with --bisim")
    if args.traces_out is not None and args.witness is None:
        usage_error("--traces-out writes the --witness paths: give --witness K as well")
    try:
        options = dataclasses.replace(
            storm_options(args), precision=args.precision, exact=args.exact,
            strategy=args.strategy, witness=extras.witness(args),
            witness_dir=args.witness_dir)
        done = verify_file(args.file, args.property, consts=overrides(args),
                           formulas=args.formula, progress=progress_printer(args),
                           options=options)
        res = done.raw
        if args.traces_out is not None:
            extras.write_traces(args.traces_out, res, args.file)
        splits = split_file(args.file, overrides(args), args.property, args.formula) \
            if args.causes else {}
        comparison = base.compare(base.read(args.baseline, res.machine), res.to_json(),
                                  args.tolerance, args.baseline) if args.baseline else None
        if args.junit is not None:
            write_junit(args.junit, res)
    except CompileError as exc:
        return fail(exc, args.json, wrapped=True)
    if args.json:
        print(answer_json("verify", changes.with_changes(done.to_json(), splits, comparison)))
    else:
        report(res.warnings)
        more = extras.render(res)
        more += "\n".join(changes.cause_lines(splits))
        if comparison is not None:
            more += "\n".join(changes.baseline_lines(comparison))
        print(render(res) + ("\n" + more if more else ""))
    worse = comparison is not None and bool(comparison.worse)
    return 1 if failing(res.properties) or worse else 0

