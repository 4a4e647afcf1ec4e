"""`Estimates`: what :meth:`Mission.simulate` returns, the Monte Carlo estimate of every
declared property with its confidence interval (`afsmc simulate`); ``to_pandas()``."""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

from afsmc.api.errors import AfsmError
from afsmc.diagnostics import CompileError, Diagnostic, Severity, codes
from afsmc.lifetime import without_main
from afsmc.sim.compile import SimError
from afsmc.sim.run import BATCH, Estimate, Outcome, Strategy, job_for
from afsmc.sim.run import simulate as run_simulation

if TYPE_CHECKING:
    import pandas as pd

    from afsmc.api.mission import Mission


def simulate(mission: Mission, runs: int = 100_000, *, seed: int = 0,
             resolve: Strategy = "uniform", confidence: float = 0.999,
             max_steps: int = 100_000, jobs: int = 1, batch_size: int = BATCH,
             dask: Any = None, traces: int = 0, at: str = "draw") -> Estimates:
    """:meth:`Mission.simulate`, with `afsmc simulate`'s defaults: the job `afsmc simulate`
    makes (:func:`afsmc.sim.run.job_for`) run by :func:`afsmc.sim.run.simulate`. `at`:
    interval probabilities at their midpoint ("mid"), lower ("min") or upper ("max") end."""
    if runs < 1 or max_steps < 1 or jobs < 1 or batch_size < 1:
        raise ValueError("runs, max_steps, jobs and batch_size must be positive")
    if not 0.0 < confidence < 1.0:
        raise ValueError(f"confidence must be in (0, 1); got {confidence!r}")
    if at not in ("draw", "mid", "min", "max"):
        raise ValueError(f"at must be draw, mid, min or max; got {at!r}")
    job = job_for(mission.path, mission.text, mission.consts, resolve, max_steps, at)
    try:
        with without_main():
            out = run_simulation(job, runs, seed, confidence=confidence, jobs=jobs,
                                 dask=dask, trace=traces, batch_size=batch_size)
    except CompileError as exc:
        raise AfsmError.of(exc) from None
    except SimError as exc:
        raise AfsmError([Diagnostic(codes.E506, Severity.ERROR,
                                    f"cannot simulate {mission.path}: {exc}", None)]) from None
    return Estimates(out, seed, confidence, resolve)


@dataclass(frozen=True)
class Estimates:
    """A simulation's estimates. ``raw`` is the :class:`afsmc.sim.run.Outcome` (``runs``,
    ``steps``, ``seconds``, ``traces``); ``estimates["finish"]`` gives one property."""

    raw: Outcome
    seed: int
    confidence: float
    resolve: str

    @property
    def runs(self) -> int:
        return self.raw.runs

    @property
    def traces(self) -> list[list[dict[str, Any]]]:
        """The sample runs asked for with ``traces=K``, in mission terms."""
        return self.raw.traces

    def __getitem__(self, name: str) -> Estimate:
        for e in self.raw.estimates:
            if e.name == name:
                return e
        raise KeyError(f"no property {name!r}; there are "
                       + ", ".join(repr(e.name) for e in self.raw.estimates))

    def to_pandas(self) -> pd.DataFrame:
        """One row per declared property, indexed by its name: ``kind`` ("P" or "R"),
        ``estimate``, ``low`` and ``high`` (the confidence interval; an expected reward
        with undecided runs has ``high`` = inf) and ``undecided`` (runs stopped at
        `max_steps`)."""
        import pandas as pd

        rows = [{"property": e.name, "kind": e.kind, "estimate": e.estimate, "low": e.low,
                 "high": e.high, "undecided": e.undecided} for e in self.raw.estimates]
        return pd.DataFrame(rows, columns=["property", "kind", "estimate", "low", "high",
                                           "undecided"]).set_index("property")

    def _repr_html_(self) -> str:
        caption = (f"{self.raw.runs:,} runs, seed {self.seed}, {self.confidence:g} confidence, "
                   f"interval constants {self.resolve}")
        table: str = self.to_pandas().to_html(na_rep="n/a", float_format=_fmt)
        return f"<div><p>{caption}</p>{table}</div>"


def _fmt(v: float) -> str:
    return "n/a" if math.isnan(v) else f"{v:.6g}"
