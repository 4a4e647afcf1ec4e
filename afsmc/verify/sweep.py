"""Sweeps: a property over a range of one open constant or of the properties' step bound.

The paper's Figure 2 is such a sweep: the probability of completing the mission by the
deadline T, with min and max over the floor/ceil choices and the uniform resolution.
Points are independent :class:`Task` values (plain data, source text included), so they run
the same in this process, in a local process pool or on a Dask cluster.
"""

from __future__ import annotations

import csv
import dataclasses
import io
import json
import os
import re
import time
from collections.abc import Mapping, Sequence
from concurrent.futures import ProcessPoolExecutor, as_completed
from dataclasses import dataclass, field
from decimal import Decimal, InvalidOperation
from typing import Any, Literal

from afsmc.backends.prism import emit as prism_emit
from afsmc.diagnostics import CompileError, Diagnostic, Severity
from afsmc.files import read_source, write_atomic
from afsmc.interrupt import Stopped
from afsmc.lifetime import die_with_parent, worker_died
from afsmc.lower.lowering import lower
from afsmc.lower.reduce import Reductions
from afsmc.model import expr as E
from afsmc.model import ir
from afsmc.model.limits import INT64
from afsmc.stack import deep
from afsmc.text import literal as const_text
from afsmc.verify.api import check, check_choice, load_with_formulas, select
from afsmc.verify.guard import Progress
from afsmc.verify.results import Checks, Partial, PropertyResult, find_property, shown
from afsmc.verify.storm import Engine, Solver, Via, finite

Kind = Literal["const", "bound"]
Number = int | float
MAX_POINTS = 10_000


def parse_values(text: str) -> list[Number]:
    """`start:stop:step` (stop included when the steps reach it) or `a,b,c` (sorted; a
    value given twice is an error).

    Integers stay integers; decimals are stepped exactly (0:1:0.1 has 11 points); `false,true`
    sweeps a bool constant."""
    text = text.strip()
    if not text:
        raise ValueError("no values")
    words = [part.strip() for part in text.split(",")]
    if any(w in ("true", "false") for w in words):
        if not all(w in ("true", "false") for w in words):
            raise ValueError(f"mixes true/false with numbers: {text!r}")
        if len(set(words)) < len(words):
            raise ValueError(f"a value is given twice in {text!r}")
        return sorted(w == "true" for w in words)
    if ":" in text:
        parts = text.split(":")
        if len(parts) not in (2, 3):
            raise ValueError(f"expected start:stop:step, got {text!r}")
        try:
            start, stop = Decimal(parts[0]), Decimal(parts[1])
            step = Decimal(parts[2]) if len(parts) == 3 else Decimal(1)
        except InvalidOperation:
            raise ValueError(f"expected numbers in start:stop:step, got {text!r}") from None
        if not all(d.is_finite() for d in (start, stop, step)):
            raise ValueError(f"expected finite numbers in start:stop:step, got {text!r}")
        if step <= 0:
            raise ValueError(f"the step of {text!r} must be positive")
        if stop < start:
            raise ValueError(f"{text!r} is empty: stop is below start")
        count = int((stop - start) / step) + 1
        if count > MAX_POINTS:
            raise ValueError(f"{text!r} has {count:,} points; at most {MAX_POINTS:,}")
        whole = all(_INT.fullmatch(x.strip()) for x in parts)
        return [_number(start + i * step, whole) for i in range(count)]
    out = []
    for part in text.split(","):
        try:
            d = Decimal(part.strip())
        except InvalidOperation:
            raise ValueError(f"not a number: {part.strip()!r}") from None
        if not d.is_finite():
            raise ValueError(f"not a finite number: {part.strip()!r}")
        out.append(_number(d, bool(_INT.fullmatch(part.strip()))))
    seen: set[Number] = set()
    for x in out:
        if x in seen:
            raise ValueError(f"{fmt(x)} is given twice in {text!r}")
        seen.add(x)
    # In increasing order, as a range: the curves join neighbouring points.
    return sorted(out)


# A value is an int only as written so (`1e0` and `2.0` are doubles), as verify's --const
# reads it: an int constant swept over `1e0:2` is refused (E208) there too.
_INT = re.compile(r"[+-]?[0-9]+")


def _number(d: Decimal, whole: bool) -> Number:
    return int(d) if whole and d == d.to_integral_value() else float(d)


def fmt(x: Number) -> str:
    if isinstance(x, bool):  # a bool constant, as the language writes it
        return "true" if x else "false"
    return str(x) if isinstance(x, int) else repr(x)


@dataclass
class SweepPoint:
    x: Number
    properties: list[PropertyResult]  # a value is None where its query failed (a partial result)
    states: int | None  # None: the model's every process failed (a partial result)
    transitions: int | None
    uniform_states: int | None = None
    uniform_transitions: int | None = None
    seconds: float = 0.0  # wall time of the point (not written to the outputs)

    def property(self, name: str) -> PropertyResult:
        return find_property(self.properties, name)


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
    via: Via
    engine: Engine
    max_states: int | None  # None: the default, for the sparse engine only (see check)
    uniform: bool
    isolate: bool | None
    shared: bool = False  # const sweep whose constant only the properties read: one build
    # Every value of the whole sweep (shared builds): the reductions keep each of them
    # exact, so every chunk builds the same model whatever the number of jobs.
    sweep_xs: tuple[Number, ...] = ()
    reductions: Reductions | None = None
    bisimulation: bool = False
    split: bool = False  # one Storm process per query
    solver: Solver = "auto"


def _unbounded(p: ir.Property) -> Diagnostic | None:
    """E410 if `p` has no step bound for --bound to sweep. Only a bound that is there is
    swept: giving `F "done"` one would answer another question (`F<=k "done"`)."""
    # X, R[F] and I have no optional bound; F, G, U and C have one only if written.
    if p.path.bound is not None:
        return None
    return Diagnostic(
        "E410", Severity.ERROR, f"property '{p.name}' has no step bound to sweep", p.span,
        hint="--bound sweeps the k of F<=k, G<=k, U<=k, C<=k and I=k; write a bound "
             "(F<=K, any K) or choose other properties with --property")


def _with_bound(p: ir.Property, k: int, name: str) -> ir.Property:
    bad = _unbounded(p)
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
        return _evaluate(task), []
    except CompileError as exc:
        # the points it answered in part (a query failed) are kept, their values None there
        kept = exc.partial if isinstance(exc.partial, list) else []
        return kept, _user_words(exc.diagnostics, task)


def _user_words(diags: list[Diagnostic], task: Task | None = None) -> list[Diagnostic]:
    """A task's diagnostics in the user's words: its properties are checked as NAME__atI,
    one per point (the I-th of `task.xs`). An error names the property (once, if it is the
    same at every point); the note of the values answered names the point of each."""
    def point(m: re.Match[str]) -> str:
        i = int(m.group(2))
        if task is None or i >= len(task.xs):
            return m.group(1) + (m.group(3) or "")
        x = fmt(task.xs[i])
        where = f"{task.variable}={x}" if task.kind == "const" else f"bound {x}"
        return f"{m.group(1)}{m.group(3) or ''} at {where}"

    out: list[Diagnostic] = []
    for d in diags:
        message = (_POINT_NAME.sub(point, d.message) if d.code == "N412" else
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
        consts[task.variable] = fmt(x)
    loaded = load_with_formulas(task.path, consts, task.formulas, text=task.text)
    model = loaded.model
    props = select(model, task.properties, loaded.adhoc)
    try:
        return _points(model, props, task, t0)
    except CompileError as exc:
        raise loaded.remap_error(exc) from None


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
                      u.states if u else None, u.transitions if u else None, secs)


def _inline_consts(p: ir.Property, model: ir.Model, name: str) -> ir.Property:
    """The property with every constant replaced by its value in `model`."""
    def lit(n: E.Expr) -> E.Expr | None:
        if isinstance(n, E.ConstRef):
            return E.Lit(model.constant(n.name).value, n.type)
        return None

    def sub(e: E.Expr | None) -> E.Expr | None:
        return None if e is None else E.transform(e, lit)

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
        consts = dict(task.consts) | {task.variable: fmt(x)}
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
    try:
        return _regroup(first.model, bounded, task, t0, preserve)
    except CompileError as exc:
        raise first.remap_error(exc) from None


def model_text(path: str, text: str, consts: dict[str, str]) -> str:
    """The PRISM model without properties and without unused constants' declarations."""
    import re

    model = load_with_formulas(path, consts, text=text, run_checks=False).model
    lines = prism_emit(lower(model, "nondet")).model.splitlines()
    body = "\n".join(line.split("//")[0] for line in lines if not line.startswith("const "))
    used = set(re.findall(r"[A-Za-z_][A-Za-z0-9_]*", body))
    return "\n".join(line for line in lines if not line.startswith("const ")
                     or line.split()[2] in used)


def independent(path: str, text: str, consts: dict[str, str], variable: str,
                values: Sequence[Number]) -> bool:
    """Whether the model (not its properties) is the same at every value. Every one is
    compared (about 0.015 s each for the UAV, the parse cached): a model can be equal at
    both ends and differ between them (a range `[0..K * (2 - K)]` over K = 0..2)."""
    if len(values) < 2:
        return False
    try:
        first = model_text(path, text, consts | {variable: fmt(values[0])})
        return all(model_text(path, text, consts | {variable: fmt(v)}) == first
                   for v in values[1:])
    except CompileError:
        return False  # the points report it


def _checks(model: ir.Model, props: list[ir.Property], task: Task,
            preserve: Sequence[ir.Property] = ()) -> Checks:
    # A shared model serves every value of the constant. Saturation stays exact for all of
    # them: the properties arrive with the constant inlined per point (`_inline_consts`),
    # and the reductions preserve these and `preserve` (the sweep's other points), so a
    # counter is capped above the largest deadline of the sweep, not the one the model was
    # loaded with.
    return check(model, props, via=task.via, engine=task.engine, max_states=task.max_states,
                 uniform=task.uniform, isolate=task.isolate, reductions=task.reductions,
                 bisimulation=task.bisimulation, split=task.split, preserve=preserve,
                 all_states=True,  # the same states whatever the chunks
                 solver=task.solver)


def _answered(exc: CompileError) -> tuple[Partial, list[Diagnostic]] | None:
    """What check() answered before it failed, and its errors: the values are kept in the
    points (None where a query failed), so its note of them (internal names) is not."""
    if not isinstance(exc.partial, Partial):
        return None
    return exc.partial, [d for d in exc.diagnostics if d.code != "N412"]


@dataclass
class SweepResult:
    path: str
    variable: str  # the constant's name, or "bound"
    kind: Kind
    type: str  # "mdp" | "dtmc"
    points: list[SweepPoint]
    names: list[str] = field(default_factory=list)  # the properties, in order
    seconds: float = 0.0

    def curve(self, name: str, key: str) -> list[float | None]:
        """The values of one property: key is "min", "max", "uniform" or "value"."""
        out: list[float | None] = [getattr(pt.property(name), key) for pt in self.points]
        return out

    @property
    def xs(self) -> list[Number]:
        return [pt.x for pt in self.points]

    def to_csv(self) -> str:
        buf = io.StringIO()
        w = csv.writer(buf, lineterminator="\n")
        w.writerow([self.variable, "property", "min", "max", "uniform", "value", "states",
                    "transitions", "uniform_states", "uniform_transitions"])

        def cell(v: float | int | None) -> str:
            return "" if v is None else str(v) if isinstance(v, int) else repr(float(v))

        for pt in self.points:
            for r in pt.properties:
                w.writerow([fmt(pt.x), r.name, cell(r.min), cell(r.max), cell(r.uniform),
                            cell(r.value), pt.states, pt.transitions, cell(pt.uniform_states),
                            cell(pt.uniform_transitions)])
        return buf.getvalue()

    def to_json(self) -> dict[str, object]:
        first = self.points[0].properties if self.points else []
        return {
            "file": self.path,
            "variable": self.variable,
            "kind": self.kind,
            "type": self.type,
            "properties": [{"name": r.name, "formula": r.formula} for r in first]
            if self.kind == "const" else [{"name": r.name} for r in first],
            "points": [{
                "x": pt.x,
                "states": pt.states,
                "transitions": pt.transitions,
                "uniform_states": pt.uniform_states,
                "uniform_transitions": pt.uniform_transitions,
                # no check times: a sweep's output is the same however it was split
                "properties": [{k: v for k, v in r.to_json().items()
                                if k != "seconds" and (k != "formula" or self.kind == "bound")}
                               for r in pt.properties],
            } for pt in self.points],
        }

    def plot(self, path: str, *, protect: tuple[str, ...] = ()) -> None:
        """Min, max and uniform curves (or the value) per property, as PNG or SVG."""
        from matplotlib import rc_context
        from matplotlib.backends.backend_agg import FigureCanvasAgg
        from matplotlib.figure import Figure
        from matplotlib.ticker import MaxNLocator

        ext = os.path.splitext(path)[1].lower()
        if ext not in (".png", ".svg"):
            raise CompileError([Diagnostic("E003", Severity.ERROR,
                                           f"--plot {path}: the name must end in .png or .svg",
                                           None)])
        n = max(1, len(self.names))
        with rc_context({"svg.hashsalt": "afsmc", "font.size": 9}):
            fig = Figure(figsize=(6.4, 3.6 * n), layout="constrained")
            FigureCanvasAgg(fig)
            xs = [float(x) for x in self.xs]
            for i, name in enumerate(self.names):
                ax = fig.add_subplot(n, 1, i + 1)
                first = self.points[0].property(name) if self.points else None
                if self.type == "mdp":
                    lo = [_nan(v) for v in self.curve(name, "min")]
                    hi = [_nan(v) for v in self.curve(name, "max")]
                    ax.fill_between(xs, lo, hi, color="tab:blue", alpha=0.12, linewidth=0)
                    ax.plot(xs, hi, color="tab:blue", label="max", linewidth=1.6)
                    ax.plot(xs, lo, color="tab:red", label="min", linewidth=1.6)
                    un = self.curve(name, "uniform")
                    if any(v is not None for v in un):
                        ax.plot(xs, [_nan(v) for v in un], color="black", linestyle="--",
                                label="uniform", linewidth=1.2)
                else:
                    ax.plot(xs, [_nan(v) for v in self.curve(name, "value")],
                            color="tab:blue", label="value", linewidth=1.6)
                what = "probability" if first is None or first.kind == "P" else "expected reward"
                title = name if first is None or self.kind == "bound" else \
                    f"{name}: {first.formula}"
                ax.set_title(title)
                ax.set_xlabel(self.variable if self.kind == "const" else "step bound k")
                ax.set_ylabel(what)
                if what == "probability":
                    ax.set_ylim(-0.02, 1.02)
                if any(isinstance(x, bool) for x in self.xs):
                    ax.set_xticks(xs, [fmt(x) for x in self.xs])
                elif all(isinstance(x, int) for x in self.xs):  # no tick at ROUNDS = 1.5
                    ax.xaxis.set_major_locator(MaxNLocator(integer=True))
                ax.grid(True, alpha=0.3)
                ax.legend(loc="best")
            buf = io.BytesIO()
            if ext == ".png":
                fig.savefig(buf, format="png", dpi=120, metadata={"Software": None})
            else:
                fig.savefig(buf, format="svg", metadata={"Date": None, "Creator": None})
        write_atomic(path, buf.getvalue(), protect=protect)


def _nan(v: float | None) -> float:
    return float("nan") if v is None or finite(v) is None else v


def _chunks(xs: Sequence[Number], n: int) -> list[tuple[Number, ...]]:
    n = max(1, min(n, len(xs)))
    size = -(-len(xs) // n)
    return [tuple(xs[i:i + size]) for i in range(0, len(xs), size)]


@deep
def sweep(path: str, variable: str, values: Sequence[Number], *, kind: Kind = "const",
          consts: Mapping[str, str | bool | int | float] | None = None,
          properties: Sequence[str] = (),
          formulas: Sequence[str] = (), via: Via = "prism", engine: Engine = "sparse",
          max_states: int | None = None, jobs: int | None = None, dask: Any = None,
          uniform: bool = True, progress: Progress | None = None,
          text: str | None = None, reductions: Reductions | None = None,
          bisimulation: bool = False, split: bool = False,
          solver: Solver = "auto") -> SweepResult:
    """Evaluate the properties at every value; see the package docstring. Raises CompileError,
    or ValueError for an unknown `kind`, `via`, `engine` or `solver`."""
    check_choice("kind", kind, Kind)
    check_choice("via", via, Via)
    check_choice("engine", engine, Engine)
    check_choice("solver", solver, Solver)
    t0 = time.perf_counter()
    if not values:
        raise CompileError([Diagnostic("E410", Severity.ERROR, "the sweep has no values", None)])
    source = read_source(path) if text is None else text
    texts = {k: const_text(v) for k, v in (consts or {}).items()}  # as run() takes them
    if kind == "const":
        texts.pop(variable, None)
        _check_names(path, source, texts, variable, values, properties, formulas)
    else:
        _check_bounds(path, source, texts, properties, formulas, values)
    jobs = jobs or os.cpu_count() or 1
    # Dask workers are daemon processes, which cannot start the guard's child process.
    isolate: bool | None = False if dask is not None else None
    base = dict(path=path, text=source, consts=tuple(sorted(texts.items())),
                properties=tuple(properties), formulas=tuple(formulas), variable=variable,
                kind=kind, via=via, engine=engine, max_states=max_states, uniform=uniform,
                isolate=isolate, reductions=reductions, bisimulation=bisimulation,
                split=split, solver=solver)
    if kind == "const" and progress is not None and len(values) > 100:
        # about 0.015 s per value for the UAV: 15 s before the first point at 1,000
        progress(f"sweep: comparing the model at the {len(values):,} values of {variable}")
    if kind == "const" and independent(path, source, texts, variable, values):
        # Only the properties read the constant (a deadline): one build per chunk.
        chunks = _chunks(values, 1 if dask is None and jobs == 1 else jobs)
        tasks = [Task(xs=c, shared=True, sweep_xs=tuple(values), **base)  # type: ignore[arg-type]
                 for c in chunks]
    elif kind == "const":
        tasks = [Task(xs=(x,), **base) for x in values]  # type: ignore[arg-type]
    else:
        parallel = 1 if dask is None and jobs == 1 else (jobs if dask is None else 4 * jobs)
        tasks = [Task(xs=c, **base) for c in _chunks(values, parallel)]  # type: ignore[arg-type]
    name = variable if kind == "const" else "bound"
    finished: dict[int, tuple[list[SweepPoint], list[Diagnostic]]] = {}

    def gathered() -> tuple[SweepResult | None, list[Diagnostic], list[Diagnostic]]:
        """The tasks finished so far: a result of their points (in order; a failed task's
        too, None where a query failed) and their errors, each with the points it covers
        and once (an error that does not depend on the value, say an undeclared label,
        came once per point: 37 copies for 0:900:25), and the note of the points as CSV."""
        points: list[SweepPoint] = []
        failed: dict[str, tuple[Diagnostic, list[str]]] = {}
        for i in sorted(finished):
            task, (pts, diags) = tasks[i], finished[i]
            where = (f"bounds {fmt(task.xs[0])}..{fmt(task.xs[-1])}" if kind != "const" else
                     f"{variable}={fmt(task.xs[0])}" if len(task.xs) == 1 else
                     f"{variable}={fmt(task.xs[0])}..{fmt(task.xs[-1])}")  # a shared model
            for d in diags:
                key = json.dumps(d.to_json(), sort_keys=True)
                failed.setdefault(key, (d, []))[1].append(where)
            points += pts

        def at(wheres: list[str]) -> str:
            if len(wheres) == len(tasks) > 1:
                return f"at every value of {variable}" if kind == "const" else \
                    "at every bound"
            return "at " + (", ".join(wheres) if len(wheres) <= 5 else
                            f"{', '.join(wheres[:5])} and {len(wheres) - 5} more")
        errors = [dataclasses.replace(d, message=f"{at(wheres)}: {d.message}")
                  for d, wheres in failed.values()]
        in_part = any(pts and diags for pts, diags in finished.values())
        result = SweepResult(path, name, kind, _type(points), points,
                             [r.name for r in points[0].properties],
                             time.perf_counter() - t0) if points else None
        return result, errors, _kept(path, name, kind, points, in_part)

    try:
        _run(tasks, jobs, dask, progress, len(values), finished)
    except KeyboardInterrupt as exc:
        # The points of the tasks that finished are not lost: the CLI prints the note and
        # the errors, in place of check()'s (their properties have internal names, NAME__atI),
        # and for --json the points as data.
        result, errors, notes = gathered()
        inner = exc.errors if isinstance(exc, Stopped) else []
        raise Stopped([*_user_words(inner), *errors], [d.message for d in notes],
                      result) from exc
    except Exception as exc:
        if not worker_died(exc):
            raise
        result, errors, notes = gathered()
        got = len(result.points) if result else 0
        raise CompileError([Diagnostic(
            "E414", Severity.ERROR, f"a process of the sweep died before it finished: "
            f"{got} of {len(values)} points were evaluated", None,
            hint="was it killed, or out of memory? --jobs 1 runs one point at a time; "
                 "--max-states stops a model that is too large before it is built"),
            *errors, *notes], result) from None
    # Every error names its points. The points evaluated, whole or in part, are kept: in
    # the error (the CLI writes them as it would have written the result) and in a note,
    # for whoever reads only the message.
    result, errors, notes = gathered()
    if errors:
        raise CompileError(errors + notes, result)
    assert result is not None  # every task returned points, or failed
    return result


def _type(points: list[SweepPoint]) -> str:
    """"mdp" if any point has a min or max (a failed query has neither), else "dtmc"."""
    return "mdp" if any(r.min is not None or r.max is not None
                        for pt in points for r in pt.properties) else "dtmc"


def without_kept_note(exc: CompileError) -> list[Diagnostic]:
    """A failed sweep's diagnostics without its note of the points kept (the last), for a
    caller that writes those points itself (`exc.partial`, a SweepResult)."""
    if isinstance(exc.partial, SweepResult) and exc.partial.points and exc.diagnostics \
            and exc.diagnostics[-1].code == "N412":
        return exc.diagnostics[:-1]
    return exc.diagnostics


def _check_bounds(path: str, text: str, consts: dict[str, str], properties: Sequence[str],
                  formulas: Sequence[str], values: Sequence[Number]) -> None:
    """A bound sweep's errors, once and before any point is computed (every chunk would
    otherwise find them, after the others' points were checked)."""
    # the values that are wrong whatever their spelling first; `1.0` only if that is all
    bad = [fmt(x) for x in values if x < 0 or x != int(x) or x > INT64[1]] \
        or [fmt(x) for x in values if isinstance(x, float)]
    if bad:
        # (Storm reads a bound as a 64-bit integer: one beyond it failed every point, E402)
        raise CompileError([Diagnostic("E410", Severity.ERROR,
                                       f"--bound {', '.join(bad)}: step bounds are integers "
                                       f"from 0 to 2^63 - 1 ({INT64[1]:,})", None)])
    loaded = load_with_formulas(path, consts, formulas, text=text)
    diags = [d for p in select(loaded.model, properties, loaded.adhoc)
             if (d := _unbounded(p)) is not None]
    if diags:
        raise loaded.remap_error(CompileError(diags))


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
                path, consts if value is None else consts | {variable: fmt(value)}, formulas,
                text=text, run_checks=False)
            break
        except CompileError:
            continue
    if loaded is None:
        return
    const = next((c for c in loaded.model.constants if c.name == variable), None)
    doubles = [fmt(x) for x in values if isinstance(x, float)]
    if const is not None and const.type is E.Type.INT and doubles:
        raise loaded.remap_error(CompileError([Diagnostic(
            "E208", Severity.ERROR, f"--const {variable}: {', '.join(doubles[:5])}"
            f"{', ...' if len(doubles) > 5 else ''} "
            f"{'is not an int' if len(doubles) == 1 else 'are not ints'}", const.span,
            hint=f"{variable} is declared int: write its values as integers (1, not 1.0 "
                 "or 1e0)")]))
    if const is not None and (const.type is E.Type.BOOL) != all(
            isinstance(x, bool) for x in values):
        # a bool swept as 0:1 (or a number as false,true): every point would say so
        if const.type is E.Type.BOOL:
            wrong = [fmt(x) for x in values if not isinstance(x, bool)]
            listed = ", ".join(wrong[:5]) + (", ..." if len(wrong) > 5 else "")
            message = f"{listed} {'is not a bool' if len(wrong) == 1 else 'are not bools'}"
            hint = f"{variable} is declared bool: sweep it as 'false,true'"
        else:
            message = "true and false are not numbers"
            hint = f"{variable} is declared {const.type.value}: sweep it over numbers, e.g. '0:10'"
        raise loaded.remap_error(CompileError([Diagnostic(
            "E208", Severity.ERROR, f"--const {variable}: {message}", const.span, hint=hint)]))
    try:
        select(loaded.model, properties, loaded.adhoc)
    except CompileError as exc:
        raise loaded.remap_error(exc) from None


def _kept(path: str, variable: str, kind: Kind, points: list[SweepPoint],
          in_part: bool = False) -> list[Diagnostic]:
    """A note with the points evaluated before a failure or a Ctrl-C, as CSV."""
    if not points:
        return []
    points = sorted(points, key=lambda pt: pt.x)
    part = SweepResult(path, variable, kind, "", points)
    return [Diagnostic("N412", Severity.NOTE, f"{len(points)} point{'s' if len(points) != 1 else ''} "
                       f"{'were' if len(points) != 1 else 'was'} evaluated before "
                       "this" + (", some in part (the cells of the queries that failed are "
                                 "empty)" if in_part else "") + ":\n"
                       + part.to_csv().rstrip("\n"), None)]


def _run(tasks: list[Task], jobs: int, dask: Any, progress: Progress | None, total: int,
         results: dict[int, tuple[list[SweepPoint], list[Diagnostic]]]) -> None:
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
            futs = {pool.submit(evaluate, t): i for i, t in enumerate(tasks)}
            for f in as_completed(futs):
                done(futs[f], f.result())
