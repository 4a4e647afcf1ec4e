"""`Results`: what :meth:`Mission.verify` returns, a table of one row per property.

``to_pandas()`` is the table (columns ``formula``, ``kind``, ``min``, ``max``, ``uniform``,
``value``, and ``verdict`` when the results carry verdicts), ``_repr_html_`` shows it in
Jupyter, ``to_json()`` is the object `afsmc verify --json` prints. Every one renders the
answer of :func:`afsmc.verify.run` as it is: ``min`` and ``max`` are the bounds over
everything uncertain and the verdicts those the run gave (docs/verification.md, "What a
result means"); nothing here computes or judges again.
"""

from __future__ import annotations

import html
import json
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, cast

from afsmc import verify as lib
from afsmc.api.errors import AfsmError
from afsmc.compiler import Checked
from afsmc.diagnostics import CompileError, Diagnostic
from afsmc.lifetime import without_main
from afsmc.text import num
from afsmc.verify.core.uncertainty import described
from afsmc.verify.engines.parametric import Extreme
from afsmc.verify.outcome.results import PropertyResult, VerifyResult, symmetry_words

if TYPE_CHECKING:
    import pandas as pd

    from afsmc.answer.verify import Verification
    from afsmc.api.mission import Mission

# `afsmc verify`'s defaults where afsmc.verify.run's differ (tests/unit/api check them
# against the command's parser).
VERIFY_DEFAULTS: dict[str, Any] = {"engine": "auto"}
VALUES = ("min", "max", "uniform", "value")
EXTRA = ("verdict", "decided_by")  # fields of a property's JSON that become columns
# interval probabilities: the values at their midpoint (PropertyResult.reference), columns
# when there are any; reference points, never judged
MIDPOINT = ("midpoint_min", "midpoint_max", "midpoint_value", "midpoint_uniform")


def names(properties: Sequence[str] | str | None) -> list[str]:
    """A property name or a list of them (None: all)."""
    if properties is None:
        return []
    return [properties] if isinstance(properties, str) else list(properties)


def verify(mission: Mission, properties: Sequence[str] | str | None = None,
           **options: Any) -> Results:
    """:meth:`Mission.verify`: :func:`verify_file` on the mission as loaded (not loaded
    again). ``witness=K`` is `afsmc verify --witness K`: the paths of the one property
    checked."""
    k = options.get("witness")
    if isinstance(k, int) and not isinstance(k, bool):
        wanted = names(properties)
        options["witness"] = (wanted[0] if wanted and len(wanted) == 1 else None, k)
    return verify_file(mission.path, properties, text=mission.text,
                       consts=dict(mission.consts), checked=mission.checked, **options)


def verify_file(path: str, properties: Sequence[str] | str | None = None, *,
                text: str | None = None, consts: Mapping[str, str] | None = None,
                checked: Checked | None = None, **options: Any) -> Results:
    """The one way afsmc verifies, for `afsmc verify` and :meth:`Mission.verify`:
    :func:`afsmc.verify.run` with the command's defaults (every option passed on as
    given), its worker processes started without re-running a user's script. `checked`:
    the file loaded already with `consts`."""
    # the command's defaults, unless the options come whole (options=VerifyOptions(...))
    kwargs = options if "options" in options else {**VERIFY_DEFAULTS, **options}
    try:
        with without_main():
            res = lib.run(path, text=text, consts=dict(consts or {}),
                          properties=names(properties), checked=checked, **kwargs)
    except CompileError as exc:
        raise AfsmError.of(exc) from None
    box = res.probability
    return Results(res, None if box is None else Intervals(dict(box.box), list(box.extremes)))


@dataclass(frozen=True)
class Intervals:
    """Where the properties' bounds over the mission's interval probabilities (`const prob
    P = [lo, hi]`) lie: ``box`` (each one's interval) and one
    :class:`afsmc.verify.engines.parametric.Extreme` per property: ``min_attained`` and
    ``max_attained`` (the properties' ``min`` and ``max``), ``min`` and ``max`` (the outer
    ends: attained minus or plus the precision), ``min_at`` and ``max_at`` (where Storm
    found them)."""

    box: dict[str, tuple[float, float]]
    bounds: list[Extreme]

    def __getitem__(self, name: str) -> Extreme:
        for e in self.bounds:
            if e.name == name:
                return e
        raise KeyError(f"no property {name!r}")

    def to_json(self) -> dict[str, object]:
        """The ``probability_intervals`` object of `afsmc verify --json`."""
        from afsmc.verify.engines import parametric

        return parametric.to_json(self.box, self.bounds)


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
        return self.raw.to_json()

    def answer(self) -> Verification:
        """The same answer as a frozen, typed pydantic model of its published schema
        (`afsmc schema verify`): ``res.answer().properties[0].verdict.kind``."""
        from afsmc.answer.schema import typed

        return cast("Verification", typed("verify", self.to_json()))

    def rows(self) -> list[dict[str, object]]:
        """One dict per property: name, formula, kind, min, max, uniform, value (an infinite
        expected reward as inf), then the extra fields of the JSON (a verdict and the bound
        that decides it), then the values at the interval probabilities' midpoint."""
        entries = self.to_json()["properties"]
        assert isinstance(entries, list)
        extras = [k for k in EXTRA if any(k in e for e in entries)]
        out = []
        for p, entry in zip(self.raw.properties, entries, strict=True):
            row: dict[str, object] = {"property": p.name, "formula": p.formula, "kind": p.kind}
            row |= {k: getattr(p, k) for k in VALUES}
            row |= {k: entry.get(k) for k in extras}
            if self.intervals is not None:
                ref = p.reference
                row |= {f"midpoint_{k}": None if ref is None else getattr(ref, k)
                        for k in ("min", "max", "value", "uniform")}
            out.append(row)
        return out

    def to_pandas(self) -> pd.DataFrame:
        """One row per property, indexed by its name: ``formula``, ``kind`` ("P" or "R"),
        ``min``, ``max``, ``uniform``, ``value`` (NaN where not asked: a DTMC has only a
        value, an MDP min, max and uniform), and ``verdict`` and ``decided_by`` if the
        results have verdicts. ``min`` and ``max`` are the bounds over everything
        uncertain. A mission with interval probabilities (`const prob P = [lo, hi]`) has
        four more, ``midpoint_min``, ``midpoint_max``, ``midpoint_value`` and
        ``midpoint_uniform``: the values with each of them at the middle of its interval,
        a reference point that no verdict rests on."""
        import pandas as pd

        rows = self.rows()
        columns = ["property", "formula", "kind", *VALUES,
                   *[k for k in (*EXTRA, *MIDPOINT) if rows and k in rows[0]]]
        df = pd.DataFrame(rows, columns=columns).set_index("property")
        for k in (*VALUES, *[k for k in MIDPOINT if k in df.columns]):
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
        over = described(self.raw.uncertainty, self.raw.probability, self.raw.composition)
        what = (f"min and max bound each property over {html.escape(over)}" if over
                else "one value per property")
        caption = (f"{html.escape(self.raw.path)}: {what}; {m.states:,} states, "
                   f"{m.transitions:,} transitions, engine {html.escape(m.engine)}")
        if self.intervals is not None:
            caption += "; midpoint_*: at the interval probabilities' midpoint, never judged"
        sym = symmetry_words(self.raw.symmetry)
        if sym is not None:
            caption += f"; {html.escape(sym)}"
        return (f'<table class="afsmc-results"><caption>{caption}</caption>'
                f"<thead><tr>{head}</tr></thead><tbody>{body}</tbody></table>")


def _cell(v: object) -> str:
    if v is None:
        return ""
    if isinstance(v, float):
        return num(v)
    return str(v)
