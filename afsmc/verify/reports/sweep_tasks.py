"""A sweep's units of work: :class:`Task` values, and evaluating one into points.

A task is plain data (the source text included), so it runs the same in this process, in
a local process pool or on a Dask cluster. A const sweep whose constant only the properties
and the labels read (a deadline) shares one model between its points (see
:func:`independent`): each task then checks a chunk of points on one build, with the
constant inlined into each point's properties, and the labels that read a constant written
out in them (labels are state predicates: `F "on_time"` at DEADLINE=200 is `F (... && t <=
200)`). A bound sweep checks a chunk of step bounds on one build.
"""

from __future__ import annotations

import dataclasses
import re
import time
from collections import Counter
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

from afsmc.backends.prism import emit as prism_emit
from afsmc.diagnostics import CompileError, Diagnostic, Severity, codes
from afsmc.lower.lowering import lower
from afsmc.model import expr as E
from afsmc.model import ir
from afsmc.model.semantics import inline
from afsmc.stack import deep
from afsmc.text import literal
from afsmc.verify.core.api import check, load_with_formulas, select
from afsmc.verify.core.options import VerifyOptions
from afsmc.verify.engines.guard import Progress
from afsmc.verify.outcome.results import Checks, Partial, PropertyResult, shown, symmetry_words
from afsmc.verify.reports.sweep_result import SweepPoint
from afsmc.verify.reports.sweep_values import Kind, Number


@dataclass(frozen=True)
class Task:
    """One unit of work: a constant's value, or a chunk of step bounds on one model."""

    path: str
    text: str
    consts: tuple[tuple[str, str], ...]
    properties: tuple[str, ...]
    formulas: tuple[str, ...]
    variable: str
    kind: Kind
    xs: tuple[Number, ...]
    options: VerifyOptions  # how each point is verified (its isolate: False on Dask)
    shared: bool = False  # const sweep whose constant only the properties read: one build
    # Every value of the whole sweep (shared builds): the reductions keep each of them
    # exact, so every chunk builds the same model whatever the number of jobs.
    sweep_xs: tuple[Number, ...] = ()
    # A sweep over several constants: the values of the others at this task's points
    # (in `consts` too), in the order the sweep was given them.
    at: tuple[tuple[str, Number], ...] = ()

    def where(self, x: Number) -> str:
        """The point in the user's words: `T=5`, `bound 5`, `N=2, T=5`."""
        if self.kind != "const":
            return f"bound {literal(x)}"
        return ", ".join(f"{n}={literal(v)}" for n, v in (*self.at, (self.variable, x)))


def unbounded(p: ir.Property) -> Diagnostic | None:
    """E410 if `p` has no step bound for --bound to sweep. Only a bound that is there is
    swept: giving `F "done"` one would answer another question (`F<=k "done"`)."""
    # X, R[F] and I have no optional bound; F, G, U and C have one only if written.
    if p.path.bound is not None:
        return None
    return Diagnostic(
        codes.E410, Severity.ERROR, f"property '{p.name}' has no step bound to sweep", p.span,
        hint="--bound sweeps the k of F<=k, G<=k, U<=k, C<=k and I=k; write a bound "
             "(F<=K, any K) or choose other properties with --property")


def _with_bound(p: ir.Property, k: int, name: str) -> ir.Property:
    bad = unbounded(p)
    if bad is not None:
        raise CompileError([bad])
    text = ""  # the formula as written, with k for its bound
    if p.bound_site is not None:
        a, b = p.bound_site
        op = "=" if isinstance(p.path, ir.RewardPath) and p.path.kind == "I" else "<="
        text = f"{p.text[:a]}{op}{k}{p.text[b:]}"
    return dataclasses.replace(p, name=name,
                               path=dataclasses.replace(p.path, bound=E.Lit(k, E.Type.INT)),
                               text=text, bound_site=None)


@deep  # in a worker process too: deep expressions get the room they have in one process
def evaluate(task: Task) -> tuple[list[SweepPoint], list[Diagnostic]]:
    """Run one task; failures are returned (diagnostics pickle, CompileError does not)."""
    try:
        return _stamped(_evaluate(task), task), []
    except CompileError as exc:
        # the points it answered in part (a query failed) are kept, their values None there
        kept = exc.partial if isinstance(exc.partial, list) else []
        return _stamped(kept, task), user_words(exc.diagnostics, task)


def _stamped(points: list[SweepPoint], task: Task) -> list[SweepPoint]:
    """The points with the other swept constants' values of a grid sweep."""
    if task.at:
        for pt in points:
            pt.at = task.at
    return points


def user_words(diags: list[Diagnostic], task: Task | None = None) -> list[Diagnostic]:
    """A task's diagnostics in the user's words: its properties are checked as NAME__atI,
    one per point (the I-th of `task.xs`). An error names the property (once, if it is the
    same at every point); the note of the values answered names the point of each."""
    def point(m: re.Match[str]) -> str:
        i = int(m.group(2))
        if task is None or i >= len(task.xs):
            return m.group(1) + (m.group(3) or "")
        return f"{m.group(1)}{m.group(3) or ''} at {task.where(task.xs[i])}"

    out: list[Diagnostic] = []
    for d in diags:
        message = (_POINT_NAME.sub(point, d.message) if d.code == codes.N412 else
                   _POINT_NAME.sub(r"\1\3", d.message))
        d = dataclasses.replace(d, message=message)
        if d not in out:  # the same failure at every point of a shared model: once
            out.append(d)
    return out


_POINT_NAME = re.compile(r"\b(\w+?)__(?:at|keep)(\d+)(_min|_max)?\b")


def _evaluate(task: Task) -> list[SweepPoint]:
    t0 = time.perf_counter()
    if task.kind == "const" and task.shared:
        return _shared_points(task, t0)
    consts = dict(task.consts)
    if task.kind == "const":
        (x,) = task.xs
        consts[task.variable] = literal(x)
    loaded = load_with_formulas(task.path, consts, task.formulas, text=task.text)
    model = loaded.model
    props = select(model, task.properties, loaded.adhoc)
    return _points(model, props, task, t0)


def _points(model: ir.Model, props: list[ir.Property], task: Task, t0: float) -> list[SweepPoint]:
    if task.kind == "const":
        try:
            c = _checks(model, props, task)
        except CompileError as exc:
            if (got := _answered(exc)) is None:
                raise
            point = _point(task.xs[0], got[0].properties, got[0], time.perf_counter() - t0)
            raise CompileError(got[1], [point]) from None
        return [_point(task.xs[0], c.properties, c, time.perf_counter() - t0)]
    bounded = []
    for i, x in enumerate(task.xs):
        assert isinstance(x, int) and x >= 0  # sweep() checked
        bounded += [(i, p.name, "", _with_bound(p, x, f"{p.name}__at{i}")) for p in props]
    return _regroup(model, bounded, task, t0)


def _regroup(model: ir.Model, bounded: list[tuple[int, str, str, ir.Property]], task: Task,
             t0: float, preserve: Sequence[ir.Property] = ()) -> list[SweepPoint]:
    """Check every (point, property) on one model and split the results by point."""
    errors: list[Diagnostic] = []
    c: Checks | Partial
    try:
        c = _checks(model, [b for _, _, _, b in bounded], task, preserve)
    except CompileError as exc:
        if (got := _answered(exc)) is None:
            raise
        c, errors = got
    per_point: dict[int, list[PropertyResult]] = {}
    for (i, name, formula, _), r in zip(bounded, c.properties, strict=True):
        per_point.setdefault(i, []).append(
            dataclasses.replace(r, name=name, formula=formula or r.formula))
    secs = (time.perf_counter() - t0) / max(1, len(task.xs))
    points = [_point(x, per_point[i], c, secs) for i, x in enumerate(task.xs)]
    if errors:
        raise CompileError(errors, points)
    return points


def _point(x: Number, properties: list[PropertyResult], c: Checks | Partial,
           secs: float) -> SweepPoint:
    m, u = c.model, c.uniform_model
    return SweepPoint(x, properties, m.states if m else None, m.transitions if m else None,
                      u.states if u else None, u.transitions if u else None, secs,
                      symmetry=symmetry_words(c.symmetry) if isinstance(c, Checks) else None)


def inlined(model: ir.Model, ref: E.LabelRef | E.FormulaRef) -> E.Expr | None:
    """What a label or formula stands for (formulas, labels and weights inlined), if a
    shared sweep writes it out in the properties: if it reads a constant, and only constants
    with one value (an interval constant's or an interval probability's is no number to
    write in; the checks refuse both in labels and properties, so this only guards). None:
    the reference stays, and its declaration stays in the model text that
    :func:`independent` compares."""
    body = inline(ref, model)
    reads = E.consts_read(body)
    if not reads or any(model.constant(n).is_interval or model.constant(n).is_prob_interval
                        for n in reads):
        return None
    return body


def _inline_consts(p: ir.Property, model: ir.Model, name: str) -> ir.Property:
    """The property with every constant replaced by its value in `model`, and every label
    or formula that reads one by what it stands for there (:func:`inlined`)."""
    def written_out(n: E.Expr) -> E.Expr | None:
        if isinstance(n, (E.LabelRef, E.FormulaRef)):
            return inlined(model, n)
        return None

    def lit(n: E.Expr) -> E.Expr | None:
        if isinstance(n, E.ConstRef):
            return E.Lit(model.constant(n.name).value, n.type)
        return None

    def sub(e: E.Expr | None) -> E.Expr | None:
        return None if e is None else E.transform(E.transform(e, written_out), lit)

    path = p.path
    if isinstance(path, ir.Path):
        target = sub(path.target)
        assert target is not None
        new: ir.Path | ir.RewardPath = dataclasses.replace(
            path, target=target, left=sub(path.left), bound=sub(path.bound))
    else:
        new = dataclasses.replace(path, target=sub(path.target), bound=sub(path.bound))
    return dataclasses.replace(p, name=name, path=new)


def _shared_points(task: Task, t0: float) -> list[SweepPoint]:
    bounded = []
    preserve: list[ir.Property] = []
    first: Any = None
    mine = set(task.xs)
    others = [x for x in task.sweep_xs if x not in mine]
    for i, x in enumerate([*task.xs, *others]):
        consts = dict(task.consts) | {task.variable: literal(x)}
        # The model is the same at every point (sweep() checked): check it once.
        try:
            loaded = load_with_formulas(task.path, consts, task.formulas, text=task.text,
                                        run_checks=first is None)
        except CompileError:
            if i < len(task.xs):
                raise
            continue  # another chunk's point: that chunk reports it
        first = first or loaded
        for p in select(loaded.model, task.properties, loaded.adhoc):
            if i < len(task.xs):
                bounded.append((i, p.name, shown(p),
                                _inline_consts(p, loaded.model, f"{p.name}__at{i}")))
            else:  # another chunk's point: kept exact by the reductions, not checked here
                preserve.append(_inline_consts(p, loaded.model, f"{p.name}__keep{i}"))
    return _regroup(first.model, bounded, task, t0, preserve)


def model_text(path: str, text: str, consts: dict[str, str]) -> str:
    """The PRISM model as a shared sweep builds it: without properties, without the labels
    and formulas it writes out in the properties (:func:`inlined`), and without the
    declarations of the formulas and constants nothing else then reads."""
    model = load_with_formulas(path, consts, text=text, run_checks=False).model
    gone = {f'label "{lb.name}"' for lb in model.labels
            if inlined(model, E.LabelRef(lb.name)) is not None}
    droppable = {f.name for f in model.formulas
                 if inlined(model, E.FormulaRef(f.name, f.value.type)) is not None}
    lines = [line for line in prism_emit(lower(model, "nondet")).model.splitlines()
             if line.split(" = ")[0] not in gone]
    while True:  # again: a formula that only a dropped one read is dropped in turn
        uses: Counter[str] = Counter()
        for line in lines:
            uses.update(_NAME.findall(line.split("//")[0]))
        unused = [line for line in lines if (d := _declared(line)) is not None
                  and uses[d[1]] == 1 and (d[0] == "const" or d[1] in droppable)]
        if not unused:
            return "\n".join(lines)
        lines = [line for line in lines if line not in unused]


_NAME = re.compile(r"[A-Za-z_][A-Za-z0-9_]*")
_DECLARATION = re.compile(r"(const|formula) (?:(?:int|double|bool) )?([A-Za-z_][A-Za-z0-9_]*)")


def _declared(line: str) -> tuple[str, str] | None:
    """("const" or "formula", the name) if the line declares one, else None."""
    m = _DECLARATION.match(line)
    return None if m is None else (m.group(1), m.group(2))


def independent(path: str, text: str, consts: dict[str, str], variable: str,
                values: Sequence[Number]) -> bool:
    """Whether the model (not its properties) is the same at every value. Every one is
    compared (about 0.015 s each for the UAV, the parse cached): a model can be equal at
    both ends and differ between them (a range `[0..1 + K * (2 - K)]` over K = 0..2)."""
    if len(values) < 2:
        return False
    try:
        first = model_text(path, text, consts | {variable: literal(values[0])})
        return all(model_text(path, text, consts | {variable: literal(v)}) == first
                   for v in values[1:])
    except CompileError:
        return False  # the points report it


def make_tasks(base: Task, values: Sequence[Number], jobs: int, dask: Any,
               progress: Progress | None) -> list[Task]:
    """The sweep cut into tasks, each `base` with its points: chunks of points on one shared
    model (one chunk per job), or one task per value of a constant the model reads, or chunks
    of step bounds (one per job locally, four per job on Dask)."""
    if base.kind == "const" and progress is not None and len(values) > 100:
        # about 0.015 s per value for the UAV: 15 s before the first point at 1,000
        progress(f"sweep: comparing the model at the {len(values):,} values of {base.variable}")
    if base.kind == "const" and independent(base.path, base.text, dict(base.consts),
                                            base.variable, values):
        # Only the properties read the constant (a deadline): one build per chunk.
        chunks = _chunks(values, 1 if dask is None and jobs == 1 else jobs)
        return [dataclasses.replace(base, xs=c, shared=True, sweep_xs=tuple(values))
                for c in chunks]
    if base.kind == "const":
        return [dataclasses.replace(base, xs=(x,)) for x in values]
    parallel = 1 if dask is None and jobs == 1 else (jobs if dask is None else 4 * jobs)
    return [dataclasses.replace(base, xs=c) for c in _chunks(values, parallel)]


def _chunks(xs: Sequence[Number], n: int) -> list[tuple[Number, ...]]:
    n = max(1, min(n, len(xs)))
    size = -(-len(xs) // n)
    return [tuple(xs[i:i + size]) for i in range(0, len(xs), size)]


def _checks(model: ir.Model, props: list[ir.Property], task: Task,
            preserve: Sequence[ir.Property] = ()) -> Checks:
    # A shared model serves every value of the constant. Saturation stays exact for all of
    # them: the properties arrive with the constant inlined per point (`_inline_consts`),
    # and the reductions preserve these and `preserve` (the sweep's other points), so a
    # counter is capped above the largest deadline of the sweep, not the one the model was
    # loaded with.
    return check(model, props, task.options, preserve=preserve,
                 all_states=True)  # the same states whatever the chunks


def _answered(exc: CompileError) -> tuple[Partial, list[Diagnostic]] | None:
    """What check() answered before it failed, and its errors: the values are kept in the
    points (None where a query failed), so its note of them (internal names) is not."""
    if not isinstance(exc.partial, Partial):
        return None
    return exc.partial, [d for d in exc.diagnostics if d.code != codes.N412]
