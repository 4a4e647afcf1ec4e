"""`Sweep`: what :meth:`Mission.sweep` returns, the properties at each value of one open
constant (or of the step bound): ``to_pandas()`` (the rows of `afsmc sweep`'s CSV) and
``plot()`` (a matplotlib Figure, the picture of `afsmc sweep --plot`)."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, cast

from afsmc import verify as lib
from afsmc.api.errors import AfsmError
from afsmc.api.results import VERIFY_DEFAULTS, names
from afsmc.diagnostics import CompileError
from afsmc.lifetime import without_main
from afsmc.verify.reports.sweep_result import VALUES, SweepResult
from afsmc.verify.reports.sweep_values import Number, parse_values

if TYPE_CHECKING:
    import pandas as pd
    from matplotlib.figure import Figure

    from afsmc.answer.sweep import Sweep as OneSweep
    from afsmc.answer.sweep import SweepGrid
    from afsmc.api.mission import Mission


def sweep(mission: Mission, variable: str | Mapping[str, Sequence[Number] | str],
          values: Sequence[Number] | str = (), *,
          properties: Sequence[str] | str | None = None, **options: Any) -> Sweep:
    """:meth:`Mission.sweep`: :func:`afsmc.verify.reports.sweep`, the function `afsmc sweep` calls,
    with the command's defaults; `variable` "bound" sweeps the step bound, a mapping
    {name: values} the grid of several constants."""
    def parsed(vals: Sequence[Number] | str) -> Sequence[Number]:
        if not isinstance(vals, str):
            return vals
        try:
            return parse_values(vals)
        except ValueError as exc:
            raise ValueError(f"values {vals!r}: {exc}") from None
    if not isinstance(variable, str):
        grid = {name: list(parsed(vals)) for name, vals in variable.items()}
        return sweep_file(mission.path, grid, properties=properties, text=mission.text,
                          consts=dict(mission.consts), **options)
    if variable == "bound":
        options.setdefault("kind", "bound")
    return sweep_file(mission.path, variable, parsed(values), properties=properties,
                      text=mission.text, consts=dict(mission.consts), **options)


def sweep_file(path: str, variable: str | Mapping[str, Sequence[Number]],
               values: Sequence[Number] = (), *,
               properties: Sequence[str] | str | None = None, text: str | None = None,
               consts: Mapping[str, str] | None = None, **options: Any) -> Sweep:
    """The one way afsmc sweeps, for `afsmc sweep` and :meth:`Mission.sweep`:
    :func:`afsmc.verify.reports.sweep` with the command's defaults (every option passed on as
    given), its worker processes started without re-running a user's script. `variable`
    a mapping {name: values} sweeps the grid of several constants."""
    # the command's defaults, unless the options come whole (options=VerifyOptions(...))
    kwargs: dict[str, Any] = options if "options" in options else {**VERIFY_DEFAULTS,
                                                                     **options}
    try:
        with without_main():
            res = lib.sweep(path, variable, list(values), text=text, consts=dict(consts or {}),
                            properties=names(properties), **kwargs)
    except CompileError as exc:
        raise AfsmError.of(exc) from None
    return Sweep(res)


@dataclass(frozen=True)
class Sweep:
    """The points of a sweep; ``raw`` is the :class:`afsmc.verify.SweepResult`."""

    raw: SweepResult

    @property
    def variable(self) -> str:
        """The swept constant's name, or "bound"."""
        return self.raw.variable

    @property
    def xs(self) -> list[Number]:
        return self.raw.xs

    def to_pandas(self) -> pd.DataFrame:
        """One row per point and property, the rows and columns of `afsmc sweep`'s CSV: the
        swept value (a column named after the constant, or "bound"; a column per constant
        for a grid), ``property``, ``min``, ``max``, ``uniform``, ``value`` (NaN where not
        asked), ``states``, ``transitions``, ``uniform_states``, ``uniform_transitions``,
        and, if a swept property is a requirement, ``verdict``: the verdict the
        verification core judged at that point ("holds", "fails", "depends",
        "undecided"; None for a property that is no requirement or a value that failed),
        and, with interval probabilities, ``midpoint_min``, ``midpoint_max``,
        ``midpoint_uniform`` and ``midpoint_value`` (the values at their midpoint, the
        core's reference point).
        ``df.pivot(index=variable, columns="property", values="value")`` gives a curve
        per column."""
        import pandas as pd

        df = pd.DataFrame(self.raw.rows(), columns=self.raw.columns())
        for k in (*VALUES, *(f"midpoint_{v}" for v in VALUES)):
            if k in df.columns:
                df[k] = df[k].astype(float)
        return df

    def to_json(self) -> dict[str, object]:
        """The object `afsmc sweep --json` prints."""
        return self.raw.to_json()

    def answer(self) -> OneSweep | SweepGrid:
        """The same answer as a frozen, typed pydantic model of its published schema
        (`afsmc schema sweep`): a `Sweep` over one constant or the bound, a `SweepGrid`
        over several constants."""
        from afsmc.answer.schema import typed

        return cast("OneSweep | SweepGrid", typed("sweep", self.to_json()))

    def to_csv(self) -> str:
        """The CSV `afsmc sweep` writes."""
        return self.raw.to_csv()

    def plot(self) -> Figure:
        """The curves of `afsmc sweep --plot`, a panel per property (min, max and uniform
        for an MDP; the value for a DTMC), as a matplotlib Figure: shown inline in Jupyter,
        ``fig.savefig("sweep.png")`` to keep it."""
        return self.raw.figure()

    def _repr_html_(self) -> str:
        return self.to_pandas().to_html(index=False, na_rep="")
