"""A sweep of requirements: the sub-ranges of the swept value where each one holds, fails,
depends or is undecided, and its threshold drawn on the plot."""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

from afsmc.text import literal
from afsmc.verify.reports.sweep_values import Number

if TYPE_CHECKING:
    from afsmc.verify.reports.sweep_result import SweepResult

# The verdicts' colours on the plot (matplotlib's tableau palette)
COLOURS = {"holds": "tab:green", "fails": "tab:red", "depends": "tab:orange",
           "undecided": "tab:gray"}


def requirements(res: SweepResult) -> list[str]:
    """The swept properties that are requirements, in order."""
    first = res.points[0].properties if res.points else []
    return [r.name for r in first if r.threshold is not None]


def ranges(res: SweepResult, name: str) -> list[tuple[str, Number, Number]]:
    """(verdict, first x, last x) for each run of points with the same verdict, in the
    order swept; a point whose value is missing has the verdict "no value"."""
    out: list[tuple[str, Number, Number]] = []
    for pt in res.points:
        v = pt.property(name).verdict
        kind = v.kind if v is not None else "no value"
        if out and out[-1][0] == kind:
            out[-1] = (kind, out[-1][1], pt.x)
        else:
            out.append((kind, pt.x, pt.x))
    return out


def ranges_json(res: SweepResult) -> list[dict[str, object]]:
    """The sweep's JSON `requirements`: each one's sub-ranges."""
    return [{"name": name, "ranges": [{"verdict": k, "from": a, "to": b}
                                      for k, a, b in ranges(res, name)]}
            for name in requirements(res)]


def summary(res: SweepResult) -> list[str]:
    """One line per requirement: `need: holds for CELLS 1..3, depends for 4, fails for 5..6`
    (over several constants: how many points have each verdict)."""
    if res.grid:
        from afsmc.verify.reports.sweep_grid import summary as grid_summary

        return grid_summary(res)
    var = res.variable if res.kind == "const" else "step bound"
    lines = []
    for name in requirements(res):
        parts = [f"{k} for {literal(a)}" if a == b else f"{k} for {literal(a)}..{literal(b)}"
                 for k, a, b in ranges(res, name)]
        lines.append(f"{name} ({var}): " + ", ".join(parts))
    return lines


def draw(ax: Any, res: SweepResult, name: str, xs: list[float]) -> None:
    """The requirement's threshold as a dashed line, and each point's verdict as a coloured
    mark on it."""
    first = res.points[0].property(name) if res.points else None
    if first is None or first.threshold is None:
        return
    t = first.threshold
    ax.axhline(t.bound, color="tab:purple", linestyle=":", linewidth=1.2,
               label=f"requirement {t.op} {t.exact}")
    for kind, colour in COLOURS.items():
        at = [x for x, pt in zip(xs, res.points, strict=True)
              if (v := pt.property(name).verdict) is not None and v.kind == kind]
        if at:
            ax.scatter(at, [t.bound] * len(at), color=colour, s=18, zorder=3, label=kind)
