"""The result of a sweep: its points, and the CSV, JSON and plot that `afsmc sweep` writes."""

from __future__ import annotations

import csv
import io
import os
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

from afsmc.diagnostics import CompileError, Diagnostic, Severity, codes
from afsmc.files import write_atomic
from afsmc.text import literal
from afsmc.verify.engines.storm import finite
from afsmc.verify.outcome.results import PropertyResult, find_property
from afsmc.verify.reports import sweep_grid, sweep_verdicts
from afsmc.verify.reports.sweep_values import Kind, Number

if TYPE_CHECKING:
    from matplotlib.figure import Figure

RC: Any = {"svg.hashsalt": "afsmc", "font.size": 9}  # byte-identical SVGs; small print

REQUIREMENT_KEYS = ("threshold", "verdict", "error")
VALUES = ("min", "max", "uniform", "value")  # a property's values, as columns


@dataclass
class SweepPoint:
    x: Number
    properties: list[PropertyResult]  # a value is None where its query failed (a partial result)
    states: int | None  # None: the model's every process failed (a partial result)
    transitions: int | None
    uniform_states: int | None = None
    uniform_transitions: int | None = None
    seconds: float = 0.0  # wall time of the point (not written to the outputs)
    # A sweep over several constants: the others' values here (x is the last one's).
    at: tuple[tuple[str, Number], ...] = ()
    # the symmetry reduction of alike agents here, in verify's words (results.symmetry_words)
    symmetry: str | None = None

    def property(self, name: str) -> PropertyResult:
        return find_property(self.properties, name)


@dataclass
class SweepResult:
    path: str
    variable: str  # the constant's name, or "bound"
    kind: Kind
    type: str  # "mdp" | "dtmc"
    points: list[SweepPoint]
    names: list[str] = field(default_factory=list)  # the properties, in order
    seconds: float = 0.0
    # A sweep over several constants: their names in the order given (the first varies
    # slowest); `variable` is then the one each task steps through. Empty for one constant.
    grid: list[str] = field(default_factory=list)

    @property
    def swept(self) -> list[str]:
        """The swept constants' names (or ["bound"]): the CSV's first columns."""
        return self.grid or [self.variable]

    def coords(self, pt: SweepPoint) -> list[Number]:
        """The point's value of each swept constant, in the order of `swept`."""
        if not self.grid:
            return [pt.x]
        at = dict(pt.at) | {self.variable: pt.x}
        return [at[n] for n in self.grid]

    def curve(self, name: str, key: str) -> list[float | None]:
        """The values of one property: key is "min", "max", "uniform" or "value"."""
        out: list[float | None] = [getattr(pt.property(name), key) for pt in self.points]
        return out

    @property
    def xs(self) -> list[Number]:
        return [pt.x for pt in self.points]

    def columns(self) -> list[str]:
        """The CSV's columns (and `Sweep.to_pandas()`'s): the swept constants, the property,
        its values, the model's size, `verdict` if a swept property is a requirement, the
        values at the interval probabilities' midpoint if a property has them
        (`midpoint_min`, ...: the core's reference point, as `Results.to_pandas()` names
        it), and `symmetry` for a mission with alike agents: verify's line on the symmetry
        reduction at that point, applied (its `states` are then the reduced model's) or
        why not."""
        verdicts, references = self._extras()
        return [*self.swept, "property", *VALUES, "states", "transitions", "uniform_states",
                "uniform_transitions"] + (["verdict"] if verdicts else []) \
            + ([f"midpoint_{k}" for k in VALUES] if references else []) \
            + (["symmetry"] if self._reduced() else [])

    def rows(self) -> list[list[Number | str | None]]:
        """The CSV's rows as values, one per point and property: a missing value is None,
        a verdict its kind as the core judged it (`PropertyResult.verdict`), None for a
        requirement without one and for a property that is no requirement."""
        verdicts, references = self._extras()
        reduced = self._reduced()
        out: list[list[Number | str | None]] = []
        for pt in self.points:
            for r in pt.properties:
                row: list[Number | str | None] = [
                    *self.coords(pt), r.name, *(getattr(r, k) for k in VALUES), pt.states,
                    pt.transitions, pt.uniform_states, pt.uniform_transitions]
                if verdicts:
                    row.append(r.verdict.kind if r.verdict is not None else None)
                if references:
                    ref = reference(r) or {}
                    row += [ref.get(k) for k in VALUES]
                if reduced:
                    row.append(pt.symmetry)
                out.append(row)
        return out

    def _reduced(self) -> bool:
        """Whether a point has a line on the symmetry of alike agents (the CSV then has
        it as a column)."""
        return any(pt.symmetry is not None for pt in self.points)

    def _extras(self) -> tuple[bool, bool]:
        """Whether the CSV has a verdict column, and reference columns."""
        return (bool(sweep_verdicts.requirements(self)),
                any(reference(r) is not None for pt in self.points for r in pt.properties))

    def to_csv(self) -> str:
        buf = io.StringIO()
        w = csv.writer(buf, lineterminator="\n")
        w.writerow(self.columns())
        swept = len(self.swept)

        def cell(v: Number | str | None) -> str:
            return ("" if v is None else v if isinstance(v, str) else
                    str(v) if isinstance(v, int) else repr(float(v)))

        for row in self.rows():
            w.writerow([*(literal(v) for v in row[:swept]),
                        *(cell(v) for v in row[swept:])])
        return buf.getvalue()

    def to_json(self) -> dict[str, object]:
        if self.grid:
            return sweep_grid.to_json(self)
        first = self.points[0].properties if self.points else []
        reqs = sweep_verdicts.ranges_json(self)
        out: dict[str, object] = {
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
                **({} if pt.symmetry is None else {"symmetry": pt.symmetry}),
                # no check times: a sweep's output is the same however it was split
                # a property that is not a requirement: no threshold/verdict/error keys
                "properties": [{k: v for k, v in r.to_json().items()
                                if k != "seconds" and (k != "formula" or self.kind == "bound")
                                and (v is not None or k not in REQUIREMENT_KEYS)}
                               for r in pt.properties],
            } for pt in self.points],
        }
        if reqs:
            out["requirements"] = reqs
        return out

    def plot(self, path: str, *, protect: tuple[str, ...] = ()) -> None:
        """Min, max and uniform curves (or the value) per property, as PNG or SVG."""
        from matplotlib import rc_context

        ext = os.path.splitext(path)[1].lower()
        if ext not in (".png", ".svg"):
            raise CompileError([Diagnostic(codes.E003, Severity.ERROR,
                                           f"--plot {path}: the name must end in .png or .svg",
                                           None)])
        fig = self.figure()
        with rc_context(RC):
            buf = io.BytesIO()
            if ext == ".png":
                fig.savefig(buf, format="png", dpi=120, metadata={"Software": None})
            else:
                fig.savefig(buf, format="svg", metadata={"Date": None, "Creator": None})
        write_atomic(path, buf.getvalue(), protect=protect)

    def figure(self) -> Figure:
        """The plot as a matplotlib Figure: a panel per property (heat maps for a sweep
        over several constants)."""
        if self.grid:
            return sweep_grid.figure(self)
        from matplotlib import figure, rc_context
        from matplotlib.backends.backend_agg import FigureCanvasAgg
        from matplotlib.ticker import MaxNLocator

        n = max(1, len(self.names))
        with rc_context(RC):
            fig = figure.Figure(figsize=(6.4, 3.6 * n), layout="constrained")
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
                    un, label = self.curve(name, "uniform"), "uniform"
                    if all(v is None for v in un):  # the core's reference point's, if any
                        un, label = _reference_curve(self, name)
                    if any(v is not None for v in un):
                        ax.plot(xs, [_nan(v) for v in un], color="black", linestyle="--",
                                label=label, linewidth=1.2)
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
                    ax.set_xticks(xs, [literal(x) for x in self.xs])
                elif all(isinstance(x, int) for x in self.xs):  # no tick at ROUNDS = 1.5
                    ax.xaxis.set_major_locator(MaxNLocator(integer=True))
                sweep_verdicts.draw(ax, self, name, xs)
                ax.grid(True, alpha=0.3)
                ax.legend(loc="best")
        return fig


def reference(r: PropertyResult) -> dict[str, Any] | None:
    """The property's values at the core's reference point (with interval probabilities:
    their midpoint), as the core writes them in its JSON; None if it has none. Rendered as
    the core gives them, never judged."""
    ref = r.to_json().get("reference")
    return ref if isinstance(ref, dict) else None


def _reference_curve(res: SweepResult, name: str) -> tuple[list[float | None], str]:
    """The uniform resolution's curve at the core's reference point (with interval
    probabilities: their midpoint), or a DTMC's value there, and its label; no values if
    the core gives no reference point."""
    refs = [reference(pt.property(name)) or {} for pt in res.points]
    point = next((ref["point"] for ref in refs if "point" in ref), "")
    for key in ("uniform", "value"):
        curve = [ref.get(key) for ref in refs]
        if any(v is not None for v in curve):
            return curve, f"{key} at the {point}"
    return [None] * len(refs), ""


def _nan(v: float | None) -> float:
    return float("nan") if v is None or finite(v) is None else v
