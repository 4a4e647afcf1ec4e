"""What verification returns: the models Storm built and one result per property.

`VerifyResult` is `run`'s answer, `Checks` that of `check`; `Partial` is what a failed
check had answered (`CompileError.partial`). Each has the JSON form `afsmc verify --json`
prints.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

from afsmc.backends.prism import formula_text
from afsmc.diagnostics import Diagnostic
from afsmc.lower.lowering import SymmetryNote
from afsmc.model import ir
from afsmc.model.pretty import show
from afsmc.verify.engines.storm import JobResult, finite
from afsmc.verify.outcome.verdicts import Verdict, requirement_json

if TYPE_CHECKING:
    from afsmc.verify.core.uncertainty import ProbabilityBox, Reference
    from afsmc.verify.outcome.strategy import StrategyEntry, TurnEntry
    from afsmc.verify.outcome.witness import Witness


@dataclass
class ModelStats:
    """One model Storm built: the min/max MDP, the uniform DTMC, or the only DTMC."""

    type: str  # "dtmc" | "mdp"
    resolution: str  # "nondet" | "uniform" (how interval constants were lowered)
    states: int
    transitions: int
    choices: int
    parse_time: float
    build_time: float
    check_time: float
    engine: str = ""  # the engine that checked (what "auto" chose)
    engine_reason: str = ""
    quotient_states: int | None = None  # after --bisim
    quotient_transitions: int | None = None
    bisimulation_time: float = 0.0
    processes: int = 1  # Storm runs that built this model (--split: one per query)
    solver: str = ""  # "topological", "value-iteration" (storm_solvers.solver_for), "acyclic"

    def to_json(self) -> dict[str, object]:
        out: dict[str, object] = {
            "states": self.states, "transitions": self.transitions, "choices": self.choices,
            "type": self.type, "resolution": self.resolution, "engine": self.engine,
            "processes": self.processes}
        if self.solver:  # not for the dd engine
            out["solver"] = self.solver
        if self.engine_reason:
            out["engine_reason"] = self.engine_reason
        if self.quotient_states is not None:
            out["quotient_states"] = self.quotient_states
            out["quotient_transitions"] = self.quotient_transitions
        return out


@dataclass(frozen=True)
class PropertyResult:
    """min/max: the bounds over everything the mission leaves uncertain (the interval
    constants' floor/ceil, the agents' order, every fixed value of the interval
    probabilities: afsmc.verify.core.uncertainty), or value (nothing uncertain: a DTMC);
    uniform: the interval constants' floor or ceil at random, a reference point. None
    where not asked."""

    name: str
    formula: str  # in .afsm syntax
    kind: str  # "P" | "R"
    min: float | None = None
    max: float | None = None
    uniform: float | None = None
    value: float | None = None
    # Storm's time for each of the above, s: its check, or that of the query asked instead
    # (a Pmax as 1 - Pmin, a bounded G as its dual). Builds are in the model's build time.
    seconds: dict[str, float] = field(default_factory=dict)
    threshold: ir.Threshold | None = None  # a requirement's; None: `=?`
    verdict: Verdict | None = None  # a requirement's (afsmc.verify.outcome.verdicts)
    # Each value is within this of the true one (sound mode; 0: exact); None: no guarantee.
    error: float | None = None
    exact: dict[str, str] = field(default_factory=dict)  # --exact: the values as `num/den`
    # --strategy: the min and max schedulers in mission terms (afsmc.verify.outcome.strategy)
    strategy: dict[str, list[StrategyEntry]] | None = None
    # a composed mission whose agents' turns are a choice: which agent the min and max
    # schedulers move, where that matters (afsmc.verify.outcome.strategy.turns)
    turns: dict[str, list[TurnEntry]] | None = None
    # --witness: the most probable paths into the target ("min"/"max": following that
    # scheduler; "value": a DTMC's), and why fewer than asked, if so
    witnesses: list[Witness] | None = None
    witness_of: str = ""
    # the paths go where the property can no longer hold (a `P>=` requirement's violations)
    witness_avoids: bool = False
    witness_note: str = ""
    # interval probabilities: the answer at their midpoint, which the strategies and
    # witnesses follow, and where in their box each bound was attained
    reference: Reference | None = None
    attained_at: dict[str, dict[str, float]] | None = None

    def followed(self, end: str) -> tuple[float | None, str]:
        """The value of the model the strategies and witnesses follow, by end ("min",
        "max", "value"), and where: with interval probabilities that model has them at
        their midpoint (the reference), not the bounds over their box."""
        at = self.reference if self.reference is not None else self
        value = {"min": at.min, "max": at.max, "value": at.value}.get(end)
        return value, (" at the midpoint" if self.reference is not None else "")

    def to_json(self) -> dict[str, object]:
        out: dict[str, object] = {"name": self.name, "formula": self.formula}
        infinite = []
        for key in ("min", "max", "uniform", "value"):
            v = getattr(self, key)
            out[key] = finite(v)
            if v is not None and finite(v) is None:
                infinite.append(key)
        if infinite:
            out["infinite"] = infinite  # JSON has no infinity: these are null above
        out["seconds"] = {k: round(v, 3) for k, v in self.seconds.items()}
        out.update(requirement_json(self.threshold, self.verdict, self.error, self.exact))
        if self.reference is not None:
            out["reference"] = self.reference.to_json()
        if self.attained_at is not None:
            out["attained_at"] = self.attained_at
        if self.strategy is not None:
            out["strategy"] = {k: [e.to_json() for e in v] for k, v in self.strategy.items()}
        if self.turns is not None:
            out["turns"] = {k: [e.to_json() for e in v] for k, v in self.turns.items()}
        if self.witnesses is not None:
            out["witnesses"] = [w.to_json() for w in self.witnesses]
            out["witness_strategy"] = self.witness_of
            out["witness_violates"] = self.witness_avoids
            if self.witness_note:
                out["witness_note"] = self.witness_note
        return out


def find_property(results: Sequence[PropertyResult], name: str) -> PropertyResult:
    """The result of property `name`; a KeyError names the properties there are."""
    for p in results:
        if p.name == name:
            return p
    raise KeyError(f"no property {name!r}; there are " + ", ".join(repr(p.name) for p in results))


@dataclass(frozen=True)
class Checks:
    """What :func:`check` returns: the models built and one result per property."""

    model: ModelStats
    uniform_model: ModelStats | None
    properties: list[PropertyResult]
    # what min and max range over (afsmc.verify.core.uncertainty.sources), and the interval
    # probabilities' box with where the bounds were attained, if the mission has any
    uncertainty: tuple[str, ...] = ()
    probability: ProbabilityBox | None = None
    symmetry: SymmetryNote | None = None  # the symmetry reduction's outcome, if any to tell


@dataclass
class Partial:
    """What :func:`check` had answered when it failed (`CompileError.partial`): a min, max,
    uniform or value is None where its query failed or was not asked, and a model's stats
    are None if none of its processes finished."""

    model: ModelStats | None
    uniform_model: ModelStats | None
    properties: list[PropertyResult]

    def to_json(self) -> dict[str, object]:
        u = self.uniform_model
        return {"model": self.model.to_json() if self.model is not None else None,
                "uniform_model": u.to_json() if u is not None else None,
                "properties": [p.to_json() for p in self.properties]}


@dataclass
class VerifyResult:
    """What :func:`afsmc.verify.run` returns: the file, its constants, the models built,
    one result per property, the times and the loader's warnings."""

    path: str
    machine: str
    constants: dict[str, object]  # the open constants' values used
    via: str
    engine: str
    upper_bound: int  # modes × product of variable ranges
    max_states: int
    model: ModelStats
    uniform_model: ModelStats | None
    properties: list[PropertyResult]
    load_time: float
    total_time: float
    warnings: list[Diagnostic] = field(default_factory=list)
    composition: str | None = None  # agents: "interleaving", "timed, ties order|nondet"
    uncertainty: tuple[str, ...] = ()  # what min and max range over (Checks.uncertainty)
    probability: ProbabilityBox | None = None  # interval probabilities (Checks.probability)
    symmetry: SymmetryNote | None = None  # alike agents reduced, or why not (Checks.symmetry)

    @property
    def kind(self) -> str:
        return self.model.type

    def property(self, name: str) -> PropertyResult:
        return find_property(self.properties, name)

    def to_json(self) -> dict[str, object]:
        u = self.uniform_model
        timings: dict[str, float] = {
            "load": self.load_time, "parse": self.model.parse_time,
            "build": self.model.build_time, "check": self.model.check_time}
        if u is not None:
            timings |= {"uniform_build": u.build_time, "uniform_check": u.check_time}
        if self.probability is not None:
            timings["bounds"] = self.probability.seconds
        timings["total"] = self.total_time
        out: dict[str, object] = {
            "file": self.path,
            "machine": self.machine,
            "model": self.model.to_json(),
            "uniform_model": u.to_json() if u is not None else None,
            "properties": [p.to_json() for p in self.properties],
            "timings": {k: round(v, 6) for k, v in timings.items()},
            "via": self.via,
            "engine": self.engine,
            "constants": self.constants,
            "state_space": {"upper_bound": self.upper_bound, "max_states": self.max_states},
            "warnings": [d.to_json() for d in self.warnings],
            "uncertainty": list(self.uncertainty),
        }
        if self.probability is not None:
            out["probability_intervals"] = self.probability.to_json()
        if self.symmetry is not None:
            out["symmetry"] = {"groups": [list(g) for g in self.symmetry.groups],
                               "reason": self.symmetry.reason}
        return out


def symmetry_words(note: SymmetryNote | None) -> str | None:
    """The front-ends' one line on the symmetry reduction (afsmc.lower.symmetry): which
    agents it kept in a canonical order, or why the mission was checked whole."""
    if note is None:
        return None
    if note.reason is not None:
        return f"no symmetry reduction (the alike agents checked as they are): {note.reason}"
    groups = "; ".join(", ".join(g) for g in note.groups)
    return (f"symmetry: {groups} checked in a canonical order, one state per set of their "
            "local states (exact: the values are those of the mission whole)")


def shown(p: ir.Property) -> str:
    """A property's formula for people, in afsm syntax: as written where it was written."""
    return p.text or formula_text(p, p.opt, show)




def stats_of(res: JobResult, resolution: str) -> ModelStats:
    """The stats of the model one Storm process built and checked."""
    return ModelStats(res.kind, resolution, res.states, res.transitions, res.choices,
                      res.parse_time, res.build_time, res.check_time, res.engine,
                      res.engine_reason, res.quotient_states, res.quotient_transitions,
                      res.bisimulation_time, solver=res.solver)



def add_runs(a: ModelStats, b: ModelStats) -> ModelStats:
    """Two Storm runs of one model (--split): times add up, sizes are the same."""
    return dataclasses.replace(
        a, parse_time=a.parse_time + b.parse_time, build_time=a.build_time + b.build_time,
        check_time=a.check_time + b.check_time,
        bisimulation_time=a.bisimulation_time + b.bisimulation_time,
        processes=a.processes + b.processes)
