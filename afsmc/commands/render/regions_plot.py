"""The picture of `afsmc regions --plot`: the regions over two parameters (or one), green
where the requirement holds, red where it fails, grey where unknown (as PROPhESY draws
them).

With more parameters than the axes, the picture is a projection: a point of the axes
stands for a whole slice of the other parameters, in which some regions may hold and
others fail. Each cell of the regions' grid on the axes (afsmc.verify.reports.regions.projection)
then shows the verdict over its slice, in `afsmc verify`'s words: holds (for every value
of the other parameters), fails (for every one), depends (holds for some, fails for
others), and, where part of the slice is undecided, the verdict where it is decided, in a
lighter shade. So every decided part of the box shows, whatever lies over it. Over the
plotted parameters alone, the picture draws the regions: holds, fails or unknown. `fills`
gives the rectangles drawn and what each shows, so that the tests read the picture."""

from __future__ import annotations

import io
from dataclasses import dataclass

from afsmc.verify.reports.regions import Cell, RegionResult, projection

# what a cell shows, by the verdicts in its slice
COLOURS = {
    "holds": "#43a047",
    "holds, rest unknown": "#a5d6a7",
    "depends": "#fb8c00",
    "fails, rest unknown": "#ef9a9a",
    "fails": "#e53935",
    "unknown": "#bdbdbd",
}


@dataclass(frozen=True)
class Fill:
    """One cell of the picture, in the axes' units (one axis: y from 0 to 1), and what it
    shows (a key of COLOURS)."""

    x: tuple[float, float]
    y: tuple[float, float]
    shows: str


def shows(cell: Cell) -> str:
    """What a cell shows: the verdict over its slice of the other parameters (a share is
    positive exactly where a region of that verdict covers part of the slice)."""
    holds, fails, unknown = (cell.share[v] > 0.0 for v in ("holds", "fails", "unknown"))
    if holds and fails:
        return "depends"
    if holds or fails:
        verdict = "holds" if holds else "fails"
        return f"{verdict}, rest unknown" if unknown else verdict
    return "unknown"


def fills(res: RegionResult, axes: list[str]) -> list[Fill]:
    """The rectangles the plot fills, each with what it shows: over the plotted
    parameters alone, the regions themselves (the cells of one region show its verdict);
    with more, the projection's cells."""
    if all(n in axes for n in res.box):
        return [Fill(r.bounds[axes[0]],
                     r.bounds[axes[1]] if len(axes) > 1 else (0.0, 1.0), r.verdict)
                for r in res.regions]
    return [Fill(c.x, c.y if c.y is not None else (0.0, 1.0), shows(c))
            for c in projection(res, axes)]


def legend(others: list[str]) -> dict[str, str]:
    """The legend's words for what a cell shows (over two parameters: the regions')."""
    if not others:
        return {"holds": "holds", "fails": "fails", "unknown": "unknown"}
    every = "every " + ", ".join(others)
    return {
        "holds": f"holds for {every}",
        "holds, rest unknown": "holds where decided, the rest unknown",
        "depends": f"depends: holds for some {', '.join(others)}, fails for others",
        "fails, rest unknown": "fails where decided, the rest unknown",
        "fails": f"fails for {every}",
        "unknown": "unknown",
    }


def title(res: RegionResult, axes: list[str]) -> str:
    """The requirement, the shares of the whole volume, and what a cell stands for."""
    text = (f"{res.requirement}\nholds on {res.fraction('holds'):.1%} of the volume, fails "
            f"on {res.fraction('fails'):.1%}, unknown {res.fraction('unknown'):.1%}")
    others = [n for n in res.box if n not in axes]
    if others:
        text += ("\nprojected: a cell shows the verdict over every "
                 + ", ".join(f"{n} in [{res.box[n][0]:g}, {res.box[n][1]:g}]" for n in others))
    return text


def plot(res: RegionResult, axes: list[str], fmt: str) -> bytes:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.patches import Patch, Rectangle

    x = axes[0]
    y = axes[1] if len(axes) > 1 else None
    others = [n for n in res.box if n not in axes]
    fig, ax = plt.subplots(figsize=(6.4, 6.0 if others else 5.0), dpi=120)
    for f in fills(res, axes):
        ax.add_patch(Rectangle((f.x[0], f.y[0]), f.x[1] - f.x[0], f.y[1] - f.y[0],
                               facecolor=COLOURS[f.shows], edgecolor="white", linewidth=0.4))
    ax.set_xlim(*res.box[x])
    ax.set_ylim(*(res.box[y] if y is not None else (0.0, 1.0)))
    ax.set_xlabel(x)
    if y is not None:
        ax.set_ylabel(y)
    else:
        ax.set_yticks([])  # one axis: a cell spans the height, which measures nothing
    ax.set_title(title(res, axes), fontsize=8)
    words = legend(others)
    handles = [Patch(color=COLOURS[k], label=w) for k, w in words.items()]
    if others:  # six entries: below the axes, where they hide no cell
        fig.legend(handles=handles, loc="lower center", ncol=2, fontsize=7, frameon=False)
        fig.tight_layout(rect=(0.0, 0.12, 1.0, 1.0))
    else:
        ax.legend(handles=handles, loc="upper right", fontsize=8)
        fig.tight_layout()
    buf = io.BytesIO()
    meta = {"Software": None} if fmt == "png" else {"Date": None} if fmt in ("svg", "pdf") else {}
    fig.savefig(buf, format=fmt or "png", metadata=meta)
    plt.close(fig)
    return buf.getvalue()
