"""`Results`: what :meth:`Mission.verify` returns, a table of one row per property.

``to_pandas()`` is the table (columns ``formula``, ``kind``, ``min``, ``max``, ``uniform``,
``value``, and ``verdict`` when the results carry verdicts), ``_repr_html_`` shows it in
Jupyter, ``to_json()`` is the object `afsmc verify --json` prints.
"""

from __future__ import annotations

import html
import json
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

from afsmc import verify as lib
from afsmc.api.errors import AfsmError
from afsmc.diagnostics import CompileError, Diagnostic
from afsmc.lifetime import without_main
from afsmc.text import num
from afsmc.verify import parametric
from afsmc.verify.parametric import Extreme
from afsmc.verify.results import PropertyResult, VerifyResult
from afsmc.verify.verdicts import judge_over

if TYPE_CHECKING:
    import pandas as pd

    from afsmc.api.mission import Mission

# `afsmc verify`'s defaults where afsmc.verify.run's differ (tests/unit/api check them
# against the command's parser).
VERIFY_DEFAULTS: dict[str, Any] = {"engine": "auto"}
VALUES = ("min", "max", "uniform", "value")
EXTRA = ("verdict",)  # fields of a property's JSON that become columns when present
SPAN = ("interval_min", "interval_max")  # over interval probabilities, when there are any


def names(properties: Sequence[str] | str | None) -> list[str]:
    """A property name or a list of them (None: all)."""
    if properties is None:
        return []
    return [properties] if isinstance(properties, str) else list(properties)


def verify(mission: Mission, properties: Sequence[str] | str | None = None,
           **options: Any) -> Results:
    """:meth:`Mission.verify`: :func:`verify_file` on the mission's text and constants.
    ``witness=K`` is `afsmc verify --witness K`: the paths of the one property checked."""
    k = options.get("witness")
    if isinstance(k, int) and not isinstance(k, bool):
        wanted = names(properties)
        options["witness"] = (wanted[0] if wanted and len(wanted) == 1 else None, k)
    return verify_file(mission.path, properties, text=mission.text,
                       consts=dict(mission.consts), **options)


def verify_file(path: str, properties: Sequence[str] | str | None = None, *,
                text: str | None = None, consts: Mapping[str, str] | None = None,
                **options: Any) -> Results:
    """The one way afsmc verifies, for `afsmc verify` and :meth:`Mission.verify`:
    :func:`afsmc.verify.run` with the command's defaults (every option passed on as
    given), its worker processes started without re-running a user's script."""
    kwargs = {**VERIFY_DEFAULTS, **options}
    try:
        with without_main():
            res = lib.run(path, text=text, consts=dict(consts or {}),
                          properties=names(properties), **kwargs)
            # interval probabilities (const prob P = [lo, hi]): min/max over every fixed
            # value, from Storm's parametric engine, as `afsmc verify` prints them
            box, bounds = parametric.for_file(
                path, consts, names(properties), kwargs.get("formulas", ()),
                via=kwargs.get("via", "prism"), reductions=kwargs.get("reductions"),
                text=text)
    except CompileError as exc:
        raise AfsmError.of(exc) from None
    if not bounds:
        return Results(res)
    # a requirement holds only if it holds at every fixed interval probability
    judge_over(res.properties, {e.name: (e.min_attained, e.max_attained) for e in bounds},
               parametric.DEFAULT_PRECISION + 1e-6,
               "over every fixed value of the interval probabilities")
    return Results(res, Intervals(box, bounds))


@dataclass(frozen=True)
class Intervals:
    """The properties' bounds over the mission's interval probabilities (`const prob P =
    [lo, hi]`): ``box`` (each one's interval) and one
    :class:`afsmc.verify.parametric.Extreme` per property: ``min`` and ``max`` (sound
    bounds over every fixed value in the box), ``min_at`` and ``max_at`` (where Storm
    found them). The main table's values are at the intervals' midpoints."""

    box: dict[str, tuple[float, float]]
    bounds: list[Extreme]

    def __getitem__(self, name: str) -> Extreme:
        for e in self.bounds:
            if e.name == name:
                return e
        raise KeyError(f"no property {name!r}")

    def to_json(self) -> dict[str, object]:
        """The ``probability_intervals`` object of `afsmc verify --json`."""
        return parametric.to_json(self.box, self.bounds)

    def __str__(self) -> str:
        return parametric.render(self.box, self.bounds)


@dataclass(frozen=True)
class Results:
    """The answer of :meth:`Mission.verify`. ``raw`` is the
    :class:`afsmc.verify.VerifyResult` (model sizes, times, ...); ``results["finish"]`` or
    ``results.value("finish")`` gives one property."""

    raw: VerifyResult
    intervals: Intervals | None = None  # bounds over interval probabilities, if any

    @property
    def kind(self) -> str:
        """"dtmc" (one value per property) or "mdp" (min, max and uniform)."""
        return self.raw.kind

    @property
    def properties(self) -> list[PropertyResult]:
        return self.raw.properties

    @property
    def warnings(self) -> list[Diagnostic]:
        return self.raw.warnings

    def __getitem__(self, name: str) -> PropertyResult:
        return self.raw.property(name)

    def __len__(self) -> int:
        return len(self.raw.properties)

    def value(self, name: str) -> float | None:
        """Property `name`'s value: a DTMC's value; for an MDP its uniform value if there
        is one (min and max are in ``results[name]``)."""
        p = self.raw.property(name)
        return p.value if p.value is not None else p.uniform

    def to_json(self) -> dict[str, object]:
        """The object `afsmc verify --json` prints for the same file, constants and options
        (with ``probability_intervals`` when the mission has interval probabilities)."""
        out = self.raw.to_json()
        if self.intervals is not None:
            out["probability_intervals"] = self.intervals.to_json()
        return out

    def rows(self) -> list[dict[str, object]]:
        """One dict per property: name, formula, kind, min, max, uniform, value (an infinite
        expected reward as inf), then the extra fields of the JSON (a verdict)."""
        entries = self.to_json()["properties"]
        assert isinstance(entries, list)
        extras = [k for k in EXTRA if any(k in e for e in entries)]
        out = []
        for p, entry in zip(self.raw.properties, entries, strict=True):
            row: dict[str, object] = {"property": p.name, "formula": p.formula, "kind": p.kind}
            row |= {k: getattr(p, k) for k in VALUES}
            row |= {k: entry.get(k) for k in extras}
            if self.intervals is not None:
                bound = self.intervals[p.name]
                row |= {"interval_min": bound.min, "interval_max": bound.max}
            out.append(row)
        return out

    def to_pandas(self) -> pd.DataFrame:
        """One row per property, indexed by its name: ``formula``, ``kind`` ("P" or "R"),
        ``min``, ``max``, ``uniform``, ``value`` (NaN where not asked: a DTMC has only a
        value, an MDP min, max and uniform), and ``verdict`` if the results have one. A
        mission with interval probabilities (`const prob P = [lo, hi]`) has two more,
        ``interval_min`` and ``interval_max``: the bounds over every fixed value of them
        (``intervals``), while the other values are at their midpoints."""
        import pandas as pd

        rows = self.rows()
        columns = ["property", "formula", "kind", *VALUES,
                   *[k for k in (*EXTRA, *SPAN) if rows and k in rows[0]]]
        df = pd.DataFrame(rows, columns=columns).set_index("property")
        for k in (*VALUES, *[k for k in SPAN if k in df.columns]):
            df[k] = df[k].astype(float)
        return df

    def __str__(self) -> str:
        return "\n".join(json.dumps(r, default=str) for r in self.rows())

    def _repr_html_(self) -> str:
        rows = self.rows()
        keys = [k for k in (rows[0] if rows else {}) if k not in ("kind",)]
        shown = [k for k in keys if k not in VALUES or any(r[k] is not None for r in rows)]
        head = "".join(f"<th>{html.escape(k)}</th>" for k in shown)
        body = "".join("<tr>" + "".join(f"<td>{html.escape(_cell(r[k]))}</td>" for k in shown)
                       + "</tr>" for r in rows)
        m = self.raw.model
        what = ("an MDP (min and max over the interval constants' floor/ceil choices)"
                if self.kind == "mdp" else "a DTMC")
        caption = (f"{html.escape(self.raw.path)}: {what}; {m.states:,} states, "
                   f"{m.transitions:,} transitions, engine {html.escape(m.engine)}")
        if self.intervals is not None:
            over = ", ".join(f"{html.escape(n)} in [{lo:g}, {hi:g}]"
                             for n, (lo, hi) in self.intervals.box.items())
            caption += (f"; interval_min and interval_max: over every fixed {over} (the "
                        "other values at the midpoints)")
        return (f'<table class="afsmc-results"><caption>{caption}</caption>'
                f"<thead><tr>{head}</tr></thead><tbody>{body}</tbody></table>")


def _cell(v: object) -> str:
    if v is None:
        return ""
    if isinstance(v, float):
        return num(v)
    return str(v)
