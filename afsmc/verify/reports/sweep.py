"""Sweeps: a property over a range of one open constant or of the properties' step bound.

The paper's Figure 2 is such a sweep: the probability of completing the mission by the
deadline T, with min and max over the floor/ceil choices and the uniform resolution.
`sweep()` checks the whole sweep's errors once, cuts the points into tasks
(afsmc.verify.reports.sweep_tasks), runs them in this process, in a local process pool or on a Dask
cluster, and gathers their points into a :class:`SweepResult` (afsmc.verify.reports.sweep_result).
"""

from __future__ import annotations

import dataclasses
import itertools
import json
import math
import os
import time
from collections.abc import Mapping, Sequence
from concurrent.futures import ProcessPoolExecutor, as_completed
from typing import Any

from afsmc.diagnostics import CompileError, Diagnostic, Severity, codes
from afsmc.files import read_source
from afsmc.interrupt import Stopped
from afsmc.lifetime import die_with_parent, without_main, worker_died
from afsmc.model import expr as E
from afsmc.model.limits import INT64
from afsmc.stack import deep
from afsmc.text import literal, plural
from afsmc.verify.core.api import load_with_formulas, select
from afsmc.verify.core.options import VerifyOptions, check_choice
from afsmc.verify.engines.guard import Progress
from afsmc.verify.reports.sweep_result import SweepPoint, SweepResult
from afsmc.verify.reports.sweep_tasks import (
    Task,
    evaluate,
    independent,
    make_tasks,
    unbounded,
    user_words,
)
from afsmc.verify.reports.sweep_values import Kind, Number

Finished = dict[int, tuple[list[SweepPoint], list[Diagnostic]]]  # task index -> its outcome


@deep
def sweep(path: str, variable: str | Mapping[str, Sequence[Number]],
          values: Sequence[Number] = (), *, kind: Kind = "const",
          consts: Mapping[str, str | bool | int | float] | None = None,
          properties: Sequence[str] = (), formulas: Sequence[str] = (),
          jobs: int | None = None, dask: Any = None, progress: Progress | None = None,
          text: str | None = None, options: VerifyOptions | None = None,
          **option_values: Any) -> SweepResult:
    """Evaluate the properties at every value; see the package docstring. `variable` a
    mapping {name: values, ...} sweeps the grid of several constants (every combination;
    the first constant varies slowest). `options` (or its fields as keywords): how each
    point is verified (VerifyOptions; not --strategy or --witness, which are verify's).
    Raises CompileError, or ValueError for an unknown `kind`, `via`, `engine` or
    `solver`, a grid of the step bound, or a strategy or witness asked of a sweep."""
    check_choice("kind", kind, Kind)
    o = VerifyOptions.of(options, option_values)
    if o.strategy or o.witness is not None:
        raise ValueError("a sweep gives values and verdicts: --strategy and --witness are "
                         "verify's, at one point")
    t0 = time.perf_counter()
    ranges: list[tuple[str, list[Number]]] = []
    if not isinstance(variable, str):
        ranges = [(n, list(v)) for n, v in variable.items()]
        if kind != "const" or not ranges:
            raise ValueError("a grid sweeps constants: give each a list of values")
        if len(ranges) == 1:  # one constant: the usual sweep
            (variable, values), ranges = ranges[0], []
        else:
            variable, values = ranges[-1]
    if not values or any(not v for _, v in ranges):
        raise CompileError([Diagnostic(codes.E410, Severity.ERROR, "the sweep has no values", None)])
    source = read_source(path) if text is None else text
    texts = {k: literal(v) for k, v in (consts or {}).items()}  # as run() takes them
    if ranges:
        for name, _ in ranges:
            texts.pop(name, None)
        for name, vals in ranges:
            others = {n: literal(v[0]) for n, v in ranges if n != name}
            _check_names(path, source, texts | others, name, vals, properties, formulas)
    elif kind == "const":
        texts.pop(variable, None)
        _check_names(path, source, texts, variable, values, properties, formulas)
    else:
        _check_bounds(path, source, texts, properties, formulas, values)
    jobs = jobs or os.cpu_count() or 1
    # Dask workers are daemon processes, which cannot start the guard's child process.
    o = dataclasses.replace(o, isolate=False if dask is not None else o.isolate)
    base = Task(path=path, text=source, consts=tuple(sorted(texts.items())),
                properties=tuple(properties), formulas=tuple(formulas), variable=variable,
                kind=kind, xs=(), options=o)
    tasks = grid_tasks(base, ranges, jobs, dask, progress) if ranges else \
        make_tasks(base, values, jobs, dask, progress)
    total = math.prod(len(v) for _, v in ranges) if ranges else len(values)
    finished: Finished = {}
    try:
        _run(tasks, jobs, dask, progress, total, finished)
    except KeyboardInterrupt as exc:
        # The points of the tasks that finished are not lost: the CLI prints the note and
        # the errors, in place of check()'s (their properties have internal names, NAME__atI),
        # and for --json the points as data.
        result, errors, notes = _gather(tasks, finished, t0, ranges)
        inner = exc.errors if isinstance(exc, Stopped) else []
        raise Stopped([*user_words(inner), *errors], [d.message for d in notes],
                      result) from exc
    except Exception as exc:
        if not worker_died(exc):
            raise
        result, errors, notes = _gather(tasks, finished, t0, ranges)
        got = len(result.points) if result else 0
        raise CompileError([Diagnostic(
            codes.E414, Severity.ERROR, f"a process of the sweep died before it finished: "
            f"{got} of {total} points were evaluated", None,
            hint="was it killed, or out of memory? --jobs 1 runs one point at a time; "
                 "--max-states stops a model that is too large before it is built"),
            *errors, *notes], result) from None
    # Every error names its points. The points evaluated, whole or in part, are kept: in
    # the error (the CLI writes them as it would have written the result) and in a note,
    # for whoever reads only the message.
    result, errors, notes = _gather(tasks, finished, t0, ranges)
    if errors:
        raise CompileError(errors + notes, result)
    assert result is not None  # every task returned points, or failed
    return result


def grid_tasks(base: Task, ranges: list[tuple[str, list[Number]]], jobs: int, dask: Any,
               progress: Progress | None) -> list[Task]:
    """A grid cut into tasks: for each combination of all constants but one (the inner),
    the tasks of a one-constant sweep of the inner one (chunks on one shared model if the
    model does not read it). The inner one is the last that only the properties read (a
    deadline), else the last given."""
    firsts = {n: literal(v[0]) for n, v in ranges}
    consts = dict(base.consts)

    def shared(name: str, vals: list[Number]) -> bool:
        others = {n: t for n, t in firsts.items() if n != name}
        return independent(base.path, base.text, consts | others, name, vals)

    inner = next((n for n, v in reversed(ranges) if shared(n, v)), ranges[-1][0])
    outer = [(n, v) for n, v in ranges if n != inner]
    combos = list(itertools.product(*(v for _, v in outer)))
    # the local processes (or Dask's chunks) shared among the combinations
    per = max(1, -(-jobs // len(combos)))
    tasks: list[Task] = []
    for combo in combos:
        at = tuple((n, x) for (n, _), x in zip(outer, combo, strict=True))
        these = consts | {n: literal(x) for n, x in at}
        tasks += make_tasks(dataclasses.replace(base, consts=tuple(sorted(these.items())),
                                                variable=inner, at=at),
                            dict(ranges)[inner], per, dask, progress)
    return tasks


def _gather(tasks: list[Task], finished: Finished, t0: float,
            ranges: Sequence[tuple[str, Sequence[Number]]] = (),
            ) -> tuple[SweepResult | None, list[Diagnostic], list[Diagnostic]]:
    """The tasks finished so far: a result of their points (in order; a failed task's
    too, None where a query failed) and their errors, each with the points it covers
    and once (an error that does not depend on the value, say an undeclared label,
    came once per point: 37 copies for 0:900:25), and the note of the points as CSV."""
    path, variable, kind = tasks[0].path, tasks[0].variable, tasks[0].kind
    name = variable if kind == "const" else "bound"
    points: list[SweepPoint] = []
    failed: dict[str, tuple[Diagnostic, list[str]]] = {}
    for i in sorted(finished):
        task, (pts, diags) = tasks[i], finished[i]
        first, last = literal(task.xs[0]), literal(task.xs[-1])
        where = (f"bounds {first}..{last}" if kind != "const" else
                 task.where(task.xs[0]) if len(task.xs) == 1 else
                 f"{task.where(task.xs[0])}..{last}")  # a shared model
        for d in diags:
            key = json.dumps(d.to_json(), sort_keys=True)
            failed.setdefault(key, (d, []))[1].append(where)
        points += pts

    def at(wheres: list[str]) -> str:
        if len(wheres) == len(tasks) > 1:
            return ("at every point of the grid" if ranges else f"at every value of {variable}"
                    if kind == "const" else "at every bound")
        sep = "; " if ranges else ", "  # a grid's point is itself `A=1, B=2`
        return "at " + (sep.join(wheres) if len(wheres) <= 5 else
                        f"{sep.join(wheres[:5])} and {len(wheres) - 5} more")
    errors = [dataclasses.replace(d, message=f"{at(wheres)}: {d.message}")
              for d, wheres in failed.values()]
    in_part = any(pts and diags for pts, diags in finished.values())
    grid = [n for n, _ in ranges]
    if ranges:  # in the order of the grid, whatever the tasks' order
        index = [{v: i for i, v in enumerate(vals)} for _, vals in ranges]
        where_in = {n: i for i, n in enumerate(grid)}

        def order(pt: SweepPoint) -> tuple[int, ...]:
            at = dict(pt.at) | {variable: pt.x}
            return tuple(index[where_in[n]][at[n]] for n in grid)
        points.sort(key=order)
    result = SweepResult(path, name, kind, _type(points), points,
                         [r.name for r in points[0].properties],
                         time.perf_counter() - t0, grid) if points else None
    return result, errors, _kept(path, name, kind, points, in_part, grid)


def _type(points: list[SweepPoint]) -> str:
    """"mdp" if any point has a min or max (a failed query has neither), else "dtmc"."""
    return "mdp" if any(r.min is not None or r.max is not None
                        for pt in points for r in pt.properties) else "dtmc"


def without_kept_note(exc: CompileError) -> list[Diagnostic]:
    """A failed sweep's diagnostics without its note of the points kept (the last), for a
    caller that writes those points itself (`exc.partial`, a SweepResult)."""
    if isinstance(exc.partial, SweepResult) and exc.partial.points and exc.diagnostics \
            and exc.diagnostics[-1].code == codes.N412:
        return exc.diagnostics[:-1]
    return exc.diagnostics


def _check_bounds(path: str, text: str, consts: dict[str, str], properties: Sequence[str],
                  formulas: Sequence[str], values: Sequence[Number]) -> None:
    """A bound sweep's errors, once and before any point is computed (every chunk would
    otherwise find them, after the others' points were checked)."""
    # the values that are wrong whatever their spelling first; `1.0` only if that is all
    bad = [literal(x) for x in values if x < 0 or x != int(x) or x > INT64[1]] \
        or [literal(x) for x in values if isinstance(x, float)]
    if bad:
        # (Storm reads a bound as a 64-bit integer: one beyond it would fail every point, E402)
        raise CompileError([Diagnostic(codes.E410, Severity.ERROR,
                                       f"--bound {', '.join(bad)}: step bounds are integers "
                                       f"from 0 to 2^63 - 1 ({INT64[1]:,})", None)])
    loaded = load_with_formulas(path, consts, formulas, text=text)
    diags = [d for p in select(loaded.model, properties, loaded.adhoc)
             if (d := unbounded(p)) is not None]
    if diags:
        raise CompileError(diags)


def _check_names(path: str, text: str, consts: dict[str, str], variable: str,
                 values: Sequence[Number], properties: Sequence[str],
                 formulas: Sequence[str]) -> None:
    """E407 (no such property, none declared), an int constant given doubles, and a bool
    given numbers or a number given bools (E208), once, before any point: none of them
    depends on the point, and every point would report them. Other errors may depend on
    it; the points report those."""
    loaded = None
    for value in (values[0], None):  # the file's own value if the first one fails
        try:
            loaded = load_with_formulas(
                path, consts if value is None else consts | {variable: literal(value)}, formulas,
                text=text, run_checks=False)
            break
        except CompileError:
            continue
    if loaded is None:
        return
    const = next((c for c in loaded.model.constants if c.name == variable), None)
    doubles = [literal(x) for x in values if isinstance(x, float)]
    if const is not None and const.type is E.Type.INT and doubles:
        raise CompileError([Diagnostic(
            codes.E208, Severity.ERROR, f"--const {variable}: {', '.join(doubles[:5])}"
            f"{', ...' if len(doubles) > 5 else ''} "
            f"{'is not an int' if len(doubles) == 1 else 'are not ints'}", const.span,
            hint=f"{variable} is declared int: write its values as integers (1, not 1.0 "
                 "or 1e0)")])
    if const is not None and (const.type is E.Type.BOOL) != all(
            isinstance(x, bool) for x in values):
        # a bool swept as 0:1 (or a number as false,true): every point would say so
        if const.type is E.Type.BOOL:
            wrong = [literal(x) for x in values if not isinstance(x, bool)]
            listed = ", ".join(wrong[:5]) + (", ..." if len(wrong) > 5 else "")
            message = f"{listed} {'is not a bool' if len(wrong) == 1 else 'are not bools'}"
            hint = f"{variable} is declared bool: sweep it as 'false,true'"
        else:
            message = "true and false are not numbers"
            hint = f"{variable} is declared {const.type.value}: sweep it over numbers, e.g. '0:10'"
        raise CompileError([Diagnostic(
            codes.E208, Severity.ERROR, f"--const {variable}: {message}", const.span, hint=hint)])
    select(loaded.model, properties, loaded.adhoc)


def _kept(path: str, variable: str, kind: Kind, points: list[SweepPoint],
          in_part: bool = False, grid: list[str] | None = None) -> list[Diagnostic]:
    """A note with the points evaluated before a failure or a Ctrl-C, as CSV."""
    if not points:
        return []
    if not grid:  # (a grid's points are in order already)
        points = sorted(points, key=lambda pt: pt.x)
    part = SweepResult(path, variable, kind, "", points, grid=list(grid or []))
    return [Diagnostic(codes.N412, Severity.NOTE, f"{plural(len(points), 'point')} "
                       f"{'were' if len(points) != 1 else 'was'} evaluated before "
                       "this" + (", some in part (the cells of the queries that failed are "
                                 "empty)" if in_part else "") + ":\n"
                       + part.to_csv().rstrip("\n"), None)]


def _run(tasks: list[Task], jobs: int, dask: Any, progress: Progress | None, total: int,
         results: Finished) -> None:
    """Evaluate the tasks into `results`, as they finish (a Ctrl-C keeps what it has)."""
    start = time.monotonic()
    last = [0.0]

    def done(i: int, r: tuple[list[SweepPoint], list[Diagnostic]]) -> None:
        results[i] = r
        now = time.monotonic()
        if progress is not None and (now - last[0] >= 2.0 or len(results) == len(tasks)):
            last[0] = now
            finished = sum(len(t.xs) for j, t in enumerate(tasks) if j in results)
            progress(f"sweep: {finished}/{total} points in {now - start:.0f} s")

    if dask is not None:
        import distributed

        dd: Any = distributed  # untyped
        client = dask if isinstance(dask, dd.Client) else dd.Client(dask)
        try:
            futures = client.map(evaluate, tasks, pure=False)
            index = {f.key: i for i, f in enumerate(futures)}
            for fut in dd.as_completed(futures):
                done(index[fut.key], fut.result())
        finally:
            if client is not dask:
                client.close()
    elif jobs <= 1 or len(tasks) == 1:
        for i, t in enumerate(tasks):
            done(i, evaluate(t))
    else:
        import multiprocessing

        ctx = multiprocessing.get_context("spawn")  # safe even if the caller has threads
        with ProcessPoolExecutor(max_workers=min(jobs, len(tasks)), mp_context=ctx,
                                 initializer=die_with_parent, initargs=(os.getpid(),)) as pool:
            with without_main():  # the workers start here: not the caller's script again
                futs = {pool.submit(evaluate, t): i for i, t in enumerate(tasks)}
            for f in as_completed(futs):
                done(futs[f], f.result())
