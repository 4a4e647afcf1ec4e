"""The picture of `afsmc regions --plot`: the regions of two parameters as rectangles,
green where the requirement holds, red where it fails, grey where undecided (as PROPhESY
draws them). With more parameters, a region's rectangle is its projection; the title says
so."""

from __future__ import annotations

import io

from afsmc.verify.regions import RegionResult

COLOURS = {"holds": "#4caf50", "fails": "#e53935", "unknown": "#bdbdbd"}


def plot(res: RegionResult, axes: list[str], fmt: str) -> bytes:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.patches import Patch, Rectangle

    names = list(res.box)
    x = axes[0]
    y = axes[1] if len(axes) > 1 and len(names) > 1 else None
    fig, ax = plt.subplots(figsize=(6, 5), dpi=120)
    for r in res.regions:
        x0, x1 = r.bounds[x]
        y0, y1 = r.bounds[y] if y is not None else (0.0, 1.0)
        ax.add_patch(Rectangle((x0, y0), x1 - x0, y1 - y0, facecolor=COLOURS[r.verdict],
                               edgecolor="white", linewidth=0.4))
    ax.set_xlim(*res.box[x])
    ax.set_ylim(*(res.box[y] if y is not None else (0.0, 1.0)))
    ax.set_xlabel(x)
    ax.set_ylabel(y if y is not None else "")
    others = [n for n in names if n not in (x, y)]
    title = f"{res.requirement}\ncoverage {res.coverage:.1%}"
    if others:
        title += " (projected over " + ", ".join(others) + ")"
    ax.set_title(title, fontsize=9)
    ax.legend(handles=[Patch(color=c, label=v) for v, c in COLOURS.items()],
              loc="upper right", fontsize=8)
    fig.tight_layout()
    buf = io.BytesIO()
    meta = {"Software": None} if fmt == "png" else {"Date": None} if fmt in ("svg", "pdf") else {}
    fig.savefig(buf, format=fmt or "png", metadata=meta)
    plt.close(fig)
    return buf.getvalue()
