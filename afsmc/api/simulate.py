"""`Estimates`: what :meth:`Mission.simulate` returns, the Monte Carlo estimate of every
declared property with its confidence interval (`afsmc simulate`); ``to_pandas()``,
``to_json()`` (the object `afsmc simulate --json` prints) and ``_repr_html_``.

`afsmc simulate` runs through :func:`prepare` and :func:`run` here, the two steps
:func:`simulate_file` (and so :meth:`Mission.simulate`) takes: one path.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any, cast

from afsmc.api.errors import AfsmError
from afsmc.diagnostics import CompileError, Diagnostic, Severity, codes
from afsmc.lifetime import without_main
from afsmc.model import ir
from afsmc.sim.compile import SimError
from afsmc.sim.policy import Table
from afsmc.sim.run import BATCH, STRATEGIES, Estimate, Job, Outcome, Strategy, job_for, program
from afsmc.sim.run import simulate as run_simulation
from afsmc.sim.scheduler import UNIFORM
from afsmc.verify.core.policy import Policy, extract

if TYPE_CHECKING:
    import pandas as pd

    from afsmc.answer.simulate import Simulation as SimulationAnswer
    from afsmc.api.mission import Mission

AT = ("draw", "mid", "min", "max")


def simulate(mission: Mission, runs: int = 100_000, *, seed: int = 0,
             resolve: Strategy = "uniform", confidence: float = 0.999,
             max_steps: int = 100_000, jobs: int = 1, batch_size: int = BATCH,
             dask: Any = None, traces: int = 0, at: str = "draw", strategy: str | None = None,
             progress: Callable[[str], None] | None = None) -> Estimates:
    """:meth:`Mission.simulate`, with `afsmc simulate`'s defaults: :func:`simulate_file` on
    the mission's text and constants."""
    return simulate_file(mission.path, mission.text, mission.consts, runs, seed=seed,
                         resolve=resolve, confidence=confidence, max_steps=max_steps,
                         jobs=jobs, batch_size=batch_size, dask=dask, traces=traces, at=at,
                         strategy=strategy, progress=progress)


def simulate_file(path: str, text: str, consts: Mapping[str, str], runs: int = 100_000, *,
                  seed: int = 0, resolve: Strategy = "uniform", confidence: float = 0.999,
                  max_steps: int = 100_000, jobs: int = 1, batch_size: int = BATCH,
                  dask: Any = None, traces: int = 0, at: str = "draw",
                  strategy: str | None = None,
                  progress: Callable[[str], None] | None = None) -> Estimates:
    """The one way afsmc simulates, for `afsmc simulate` and :meth:`Mission.simulate`:
    :func:`prepare` then :func:`run`. `at`: interval probabilities drawn once per run,
    uniformly from their intervals ("draw"), or at their midpoint ("mid"), lower ("min") or
    upper ("max") end; `strategy` ("min:NAME" or "max:NAME"):
    the runs follow Storm's min or max scheduler of property NAME instead of `resolve`;
    `progress` receives the strategy extraction's lines. Raises AfsmError, ValueError."""
    if runs < 1 or max_steps < 1 or jobs < 1 or batch_size < 1:
        raise ValueError("runs, max_steps, jobs and batch_size must be positive")
    if not 0.0 < confidence < 1.0:
        raise ValueError(f"confidence must be in (0, 1); got {confidence!r}")
    if traces < 0 or traces > runs:
        raise ValueError(f"traces must be in [0, runs]; got {traces!r}")
    sim = prepare(path, text, consts, resolve=resolve, max_steps=max_steps, at=at,
                  strategy=strategy, traces=traces, progress=progress)
    return run(sim, runs, seed=seed, confidence=confidence, jobs=jobs, batch_size=batch_size,
               dask=dask, traces=traces)


@dataclass(frozen=True)
class Simulation:
    """A simulation ready to run: the job the workers get, the checked model's warnings
    (W602, a mode the mission cannot end from, is why runs stay undecided), and the
    strategy the runs follow (None: `resolve`)."""

    job: Job
    policy: Policy | None = None

    @property
    def model(self) -> ir.Model:
        return program(self.job).model

    @property
    def warnings(self) -> list[Diagnostic]:
        return [d for d in program(self.job).diagnostics if d.severity is Severity.WARNING]

    @property
    def scheduler(self) -> str | None:
        """Who moves next in a composed mission whose agents interleave (or tie): the
        uniform scheduler, or the strategy; None where no such choice exists."""
        if program(self.job).movers is None:
            return None
        if self.policy is not None:
            return f"the {self.policy.direction}:{self.policy.property} strategy"
        return UNIFORM


def prepare(path: str, text: str, consts: Mapping[str, str], *,
            resolve: Strategy = "uniform", max_steps: int = 100_000, at: str = "draw",
            strategy: str | None = None, traces: int = 0,
            progress: Callable[[str], None] | None = None) -> Simulation:
    """Load and compile the machine for the simulator (and extract Storm's scheduler for
    `strategy`). Raises AfsmError: the file's errors, E407 for a file without properties
    when no sample runs are asked for (`traces`), E506 for a machine the simulator cannot
    run; ValueError for an unknown `resolve` or `at`."""
    if resolve not in STRATEGIES:
        raise ValueError(f"resolve must be one of {', '.join(STRATEGIES)}; got {resolve!r}")
    if at not in AT:
        raise ValueError(f"at must be draw, mid, min or max; got {at!r}")
    if strategy and resolve != "uniform":
        raise ValueError("strategy resolves the interval constants itself: give it or "
                         "resolve, not both")
    job = job_for(path, text, consts, resolve, max_steps, at)
    try:
        policy = None
        if strategy:
            policy = extract(program(job).model, strategy, progress=progress)
            job = dataclasses.replace(job, policy=Table(
                f"{policy.direction}:{policy.property}", policy.variables, policy.states,
                policy.commands))
        # Without properties there is nothing to estimate; sample runs (traces) are the
        # one use of such a file, as verify has none (E407 there too).
        if not traces and not program(job).monitors:
            raise CompileError([Diagnostic(
                codes.E407, Severity.ERROR, f"{path} declares no properties", None,
                hint="declare one ('property ok = P=? [ F \"done\" ];'), or watch sample "
                     "runs with --traces K")])
    except CompileError as exc:
        raise AfsmError.of(exc) from None
    except SimError as exc:
        raise _cannot(path, exc) from None
    return Simulation(job, policy)


def run(sim: Simulation, runs: int, *, seed: int = 0, confidence: float = 0.999,
        jobs: int = 1, batch_size: int = BATCH, dask: Any = None, traces: int = 0,
        progress: Callable[[int, int], None] | None = None) -> Estimates:
    """Run a prepared simulation (`progress(done, total)` after each batch). Raises
    AfsmError: E506 (the simulator failed), E507 (the Dask scheduler is unreachable). A
    Ctrl-C after some batches raises :class:`afsmc.interrupt.Stopped` with their
    :class:`afsmc.sim.run.Outcome` as ``partial``."""
    try:
        with without_main():
            out = run_simulation(sim.job, runs, seed, confidence=confidence, jobs=jobs,
                                 dask=dask, trace=traces, batch_size=batch_size,
                                 progress=progress)
    except CompileError as exc:
        raise AfsmError.of(exc) from None
    except SimError as exc:
        raise _cannot(sim.job.path, exc) from None
    except OSError as exc:  # e.g. the Dask scheduler is unreachable
        raise AfsmError([Diagnostic(
            codes.E507, Severity.ERROR, f"simulation failed: {exc}", None,
            hint=f"is a Dask scheduler running at {dask}?" if dask else None)]) from None
    return estimates(sim, out, seed=seed, confidence=confidence, traced=traces > 0)


def estimates(sim: Simulation, out: Outcome, *, seed: int, confidence: float,
              traced: bool) -> Estimates:
    """The Estimates of `sim`'s runs `out` (also those an interrupt kept)."""
    model = sim.model
    return Estimates(out, seed, confidence, sim.job.strategy, at=sim.job.at,
                     path=sim.job.path, machine=model.name,
                     constants={c.name: c.value for c in model.constants if c.is_param},
                     warnings=sim.warnings, policy=sim.policy, traced=traced,
                     scheduler=sim.scheduler)


def _cannot(path: str, exc: SimError) -> AfsmError:
    return AfsmError([Diagnostic(codes.E506, Severity.ERROR, f"cannot simulate {path}: {exc}",
                                 None)])


@dataclass(frozen=True)
class Estimates:
    """A simulation's estimates. ``raw`` is the :class:`afsmc.sim.run.Outcome` (``runs``,
    ``steps``, ``seconds``, ``traces``); ``estimates["finish"]`` gives one property;
    ``warnings`` are the model's (W602); ``policy`` the Storm strategy the runs followed."""

    raw: Outcome
    seed: int
    confidence: float
    resolve: str
    at: str = "draw"
    path: str = ""
    machine: str = ""
    constants: dict[str, object] = field(default_factory=dict)
    warnings: list[Diagnostic] = field(default_factory=list)
    policy: Policy | None = None
    traced: bool = False  # sample runs were asked for
    scheduler: str | None = None  # who moves next in a composed MDP (Simulation.scheduler)

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

    def answer(self) -> SimulationAnswer:
        """The same answer as a frozen, typed pydantic model of its published schema
        (`afsmc schema simulate`)."""
        from afsmc.answer.schema import typed

        return cast("SimulationAnswer", typed("simulate", self.to_json()))

    def to_json(self) -> dict[str, Any]:
        """The object `afsmc simulate --json` prints for the same file and options."""
        p = self.policy
        head: dict[str, Any] = {} if p is None else {"strategy": {
            "property": p.property, "direction": p.direction, "value": _num(p.value),
            "states": len(p.states)}}
        return head | {
            "file": self.path,  # which machine and instance, as verify --json says them
            "machine": self.machine,
            "constants": self.constants,
            "runs": self.raw.runs,
            "seed": self.seed,
            "resolve": self.resolve,
            "at": self.at,  # interval probabilities: draw, mid, min or max
            "confidence": self.confidence,
            **({"scheduler": self.scheduler} if self.scheduler else {}),
            "properties": [{"name": e.name, "estimate": _num(e.estimate), "low": _num(e.low),
                            "high": _num(e.high), "undecided": e.undecided,
                            "method": e.method, **({"reason": e.reason} if e.reason else {})}
                           for e in self.raw.estimates],
            **({"traces": self.raw.traces} if self.traced else {}),
            "warnings": [d.to_json() for d in self.warnings],
        }

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
        how = (f"{self.policy.direction} strategy of {self.policy.property}"
               if self.policy is not None else self.resolve)
        caption = (f"{self.raw.runs:,} runs, seed {self.seed}, {self.confidence:g} confidence, "
                   f"interval constants {how}"
                   + (f", who moves next: {self.scheduler}" if self.scheduler else ""))
        table: str = self.to_pandas().to_html(na_rep="n/a", float_format=_fmt)
        return f"<div><p>{caption}</p>{table}</div>"


def _num(v: float) -> Any:
    if math.isnan(v):
        return None  # an expected reward no run finished: no estimate
    return v if math.isfinite(v) else ("inf" if v > 0 else "-inf")


def _fmt(v: float) -> str:
    return "n/a" if math.isnan(v) else f"{v:.6g}"
