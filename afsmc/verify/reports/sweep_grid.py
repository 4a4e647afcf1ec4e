"""A sweep over several constants (`afsmc sweep --const A=1:3 --const B=0:1:0.5`): its JSON
in long format, its requirements' summary, and its picture (heat maps; small multiples
for three constants or more).

The CSV is :meth:`SweepResult.to_csv`, one column per swept constant.
"""

from __future__ import annotations

import itertools
import math
from typing import TYPE_CHECKING, Any

from afsmc.text import literal
from afsmc.verify.engines.storm import finite
from afsmc.verify.reports.sweep_values import Number

if TYPE_CHECKING:
    from matplotlib.figure import Figure

    from afsmc.verify.reports.sweep_result import SweepPoint, SweepResult

VERDICTS = ("holds", "fails", "depends", "undecided", "no value")
MAX_PANELS = 64  # small multiples drawn at most (a larger grid: the first ones, and said so)
ANNOTATE = 12  # cells along each axis up to which each cell is written on its heat map


def to_json(res: SweepResult) -> dict[str, object]:
    """Long format: a row per point and property, the point as `{"A": 1, "B": 0.5}`."""
    from afsmc.verify.reports.sweep_result import REQUIREMENT_KEYS

    first = res.points[0].properties if res.points else []
    rows = []
    for pt in res.points:
        point = dict(zip(res.grid, res.coords(pt), strict=True))
        for r in pt.properties:
            row: dict[str, object] = {"point": point, "property": r.name}
            row.update({k: v for k, v in r.to_json().items()
                        if k not in ("name", "formula", "seconds")
                        and (v is not None or k not in REQUIREMENT_KEYS)})
            row.update(states=pt.states, transitions=pt.transitions,
                       uniform_states=pt.uniform_states,
                       uniform_transitions=pt.uniform_transitions)
            if pt.symmetry is not None:
                row["symmetry"] = pt.symmetry
            rows.append(row)
    out: dict[str, object] = {
        "file": res.path, "variables": list(res.grid), "kind": res.kind, "type": res.type,
        "properties": [{"name": r.name, "formula": r.formula} for r in first],
        "rows": rows,
    }
    reqs = requirements_json(res)
    if reqs:
        out["requirements"] = reqs
    return out


def verdict_counts(res: SweepResult, name: str) -> dict[str, int]:
    """How many points of the grid have each verdict of requirement `name`."""
    counts = dict.fromkeys(VERDICTS, 0)
    for pt in res.points:
        v = pt.property(name).verdict
        counts[v.kind if v is not None else "no value"] += 1
    return {k: n for k, n in counts.items() if n}


def requirements_json(res: SweepResult) -> list[dict[str, object]]:
    from afsmc.verify.reports import sweep_verdicts

    return [{"name": name, "points": verdict_counts(res, name)}
            for name in sweep_verdicts.requirements(res)]


def summary(res: SweepResult) -> list[str]:
    """`need (A x B): holds at 5 of 9 points, fails at 4`."""
    from afsmc.verify.reports import sweep_verdicts

    lines = []
    for name in sweep_verdicts.requirements(res):
        counts = verdict_counts(res, name)
        parts = [f"{k} at {n}" + (f" of {len(res.points)} points" if i == 0 else "")
                 for i, (k, n) in enumerate(counts.items())]
        lines.append(f"{name} ({' x '.join(res.grid)}): " + ", ".join(parts))
    return lines


# ---- the picture ----------------------------------------------------------------------

def _axis(res: SweepResult, i: int) -> list[Number]:
    """The values of the i-th swept constant, in the order swept."""
    seen: dict[Number, None] = {}
    for pt in res.points:
        seen.setdefault(res.coords(pt)[i], None)
    return list(seen)


def _keys(res: SweepResult) -> list[str]:
    return ["min", "max"] if res.type == "mdp" else ["value"]


def figure(res: SweepResult) -> Figure:
    """Heat maps of each property over the first two swept constants (x, y): min and max
    for an MDP, the value for a DTMC. With more constants, one small heat map per
    combination of the others' values (small multiples), in rows."""
    from matplotlib import figure as mfigure
    from matplotlib import rc_context
    from matplotlib.backends.backend_agg import FigureCanvasAgg

    from afsmc.verify.reports.sweep_result import RC

    xs, ys = _axis(res, 0), _axis(res, 1)
    rest = [_axis(res, i) for i in range(2, len(res.grid))]
    combos = list(itertools.product(*rest))[:MAX_PANELS]
    keys = _keys(res)
    cols = min(len(combos), 4) * len(keys)
    rows_per = math.ceil(len(combos) / 4)
    nrows = max(1, len(res.names)) * rows_per
    by_coords = {tuple(res.coords(pt)): pt for pt in res.points}
    cell = 2.6 if len(combos) > 1 else 4.2
    with rc_context(RC):
        fig = mfigure.Figure(figsize=(cell * cols + 1.0, cell * 0.85 * nrows + 0.6),
                             layout="constrained")
        FigureCanvasAgg(fig)
        for p, name in enumerate(res.names):
            first = res.points[0].property(name) if res.points else None
            prob = first is None or first.kind == "P"
            values = [v for pt in res.points for k in keys
                      if (v := _finite(getattr(pt.property(name), k))) is not None]
            lo, hi = (0.0, 1.0) if prob else (min(values, default=0.0), max(values, default=1.0))
            for c, combo in enumerate(combos):
                for j, key in enumerate(keys):
                    row = p * rows_per + c // 4
                    col = (c % 4) * len(keys) + j
                    ax = fig.add_subplot(nrows, cols, row * cols + col + 1)
                    grid = [[_value(by_coords.get((x, y, *combo)), name, key) for x in xs]
                            for y in ys]
                    mesh = _heat(ax, grid, xs, ys, lo, hi, len(combos) == 1)
                    where = ", ".join(f"{n}={literal(v)}"
                                      for n, v in zip(res.grid[2:], combo, strict=True))
                    ax.set_title(f"{name} {key}" + (f"\n{where}" if where else ""))
                    ax.set_xlabel(res.grid[0])
                    ax.set_ylabel(res.grid[1])
                    if c == len(combos) - 1 and j == len(keys) - 1:
                        fig.colorbar(mesh, ax=ax, label="probability" if prob
                                     else "expected reward")
        if len(combos) < math.prod(len(r) for r in rest):
            fig.suptitle(f"the first {len(combos)} of {math.prod(len(r) for r in rest)} "
                         "combinations of " + ", ".join(res.grid[2:]))
    return fig


def _finite(v: float | None) -> float | None:
    return None if v is None else finite(v)


def _value(pt: SweepPoint | None, name: str, key: str) -> float:
    if pt is None:
        return math.nan
    v = _finite(getattr(pt.property(name), key))
    return math.nan if v is None else v


def _heat(ax: Any, grid: list[list[float]], xs: list[Number], ys: list[Number], lo: float,
          hi: float, annotate: bool) -> Any:
    """One heat map: a cell per point (the values need not be evenly spaced), its value
    written in it when the grid is small."""
    mesh = ax.pcolormesh(range(len(xs) + 1), range(len(ys) + 1), grid, cmap="viridis",
                         vmin=lo, vmax=hi, shading="flat")
    step_x = max(1, math.ceil(len(xs) / 10))
    step_y = max(1, math.ceil(len(ys) / 10))
    ax.set_xticks([i + 0.5 for i in range(0, len(xs), step_x)],
                  [literal(x) for x in xs[::step_x]])
    ax.set_yticks([i + 0.5 for i in range(0, len(ys), step_y)],
                  [literal(y) for y in ys[::step_y]])
    if annotate and len(xs) <= ANNOTATE and len(ys) <= ANNOTATE:
        mid = (lo + hi) / 2
        for j, line in enumerate(grid):
            for i, v in enumerate(line):
                if not math.isnan(v):
                    ax.text(i + 0.5, j + 0.5, f"{v:.3g}", ha="center", va="center",
                            fontsize=7, color="black" if v > mid else "white")
    return mesh
