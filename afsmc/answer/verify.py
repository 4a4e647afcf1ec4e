"""`afsmc verify --json`: the models Storm built, one object per property (its bounds,
verdict, strategies and most probable paths), the times, and on failure the diagnostics
with what was answered before it."""

from __future__ import annotations

from typing import Literal

from pydantic import ConfigDict, Field, RootModel

from afsmc.answer import common as c
from afsmc.answer.common import Absent, Answer, ConstValue, Count, Diagnostic, Seconds


class ModelStats(Answer):
    """A model Storm built and checked: the MDP whose choices are what is uncertain, the
    uniform DTMC beside it, or a mission's only DTMC."""

    states: int = Field(ge=0, description="reachable states")
    transitions: int = Field(ge=0, description="transitions (an MDP's: of every choice)")
    choices: int = Field(ge=0, description="choices (an MDP's state-action pairs; a DTMC "
                                           "has one per state; 0 on the symbolic engines)")
    type: Literal["mdp", "dtmc"] = Field(description="mdp: something is chosen "
                                                     "(min/max); dtmc: nothing is")
    resolution: Literal["nondet", "uniform"] = Field(
        description="how the interval constants were lowered: nondet (a choice of floor or "
                    "ceil), uniform (drawn at random)")
    engine: str = Field(description="the engine that checked it: sparse, hybrid, dd, or "
                                    "explicit (afsmc's own exploration)")
    processes: int = Field(ge=0, description="Storm processes that built it (--split: one "
                                             "per query); 0 for a uniform DTMC answered by "
                                             "the MDP's exploration")
    solver: str | Absent = Field(
        None, description="how the equations were solved: acyclic, topological, "
                          "value-iteration, sound-value-iteration, exact; absent on the dd "
                          "engine")
    engine_reason: str | Absent = Field(None, description="why --engine auto chose it")
    quotient_states: Count | Absent = Field(None, description="--bisim: states of the "
                                                              "quotient checked")
    quotient_transitions: Count | Absent = Field(None, description="--bisim: its transitions")


class StrategyEntry(Answer):
    """One interval constant at one end, in one action and mode, as a strategy takes it."""

    constant: str = Field(description="the interval constant")
    end: Literal["floor", "ceil"] = Field(description="the end the strategy takes")
    value: int = Field(description="that end's value")
    action: str = Field(description="the action whose constant it is")
    mode: str = Field(description="the mode (a composed mission: each agent's, "
                                  "'uav1: Ready; uav2: Ready')")
    states: int = Field(ge=0, description="reached states where the strategy takes this end")
    when: str | None = Field(description="a condition on one variable that holds in exactly "
                                         "those states (against the other end), or null")
    indifferent: int = Field(ge=0, description="further reached states of this action and mode "
                                               "where both ends give the same value")


class TurnEntry(Answer):
    """A composed mission whose agents' turns are a choice: which agent a strategy moves,
    where that matters."""

    action: str = Field(description="the action moved: 'uav1: Look', or a synchronised "
                                    "'Launch (uav1, uav2)'")
    mode: str = Field(description="the agents' modes there")
    states: int = Field(ge=0, description="reached states where the strategy moves it")


class WitnessStep(Answer):
    """One step of a most probable path."""

    mode: str = Field(description="the mode the step starts in (a composed mission: each "
                                  "agent's)")
    action: str = Field(description="the action that fired: '(final)' for a final mode's "
                                    "self-loop, '(no enabled action)' for a deadlock")
    probability: float = Field(ge=0, description="the step's probability")
    changes: dict[str, int | bool | str] = Field(
        description="the variables it changed, by name ('mode' and an agent's 'uav1.mode': "
                    "the new mode's name)")
    choice: dict[str, Literal["floor", "ceil"]] = Field(
        description="the interval constants it fixed and the end taken ('T_TAKEOFF[uav1]': "
                    "by the partner of a synchronised action)")
    hazard: str | Absent = Field(None, description="the hazard that happened instead of the "
                                                   "action's own outcome")


class Witness(Answer):
    """A most probable path into the property's target (`--witness K`)."""

    probability: float = Field(ge=0, description="the path's probability")
    end_mode: str = Field(description="the mode it ends in")
    confirmed: bool = Field(description="every step replayed through the lowered model "
                                        "with Storm's probability")
    steps: list[WitnessStep] = Field(description="its steps, in order")


class CauseKey(Answer):
    """What led into a property's target: the step that first entered it."""

    kind: Literal["hazard", "action", "initial"] = Field(
        description="hazard: a hazard happened in that step; action: the action fired and "
                    "no hazard happened; initial: the first state is in the target already")
    event: str = Field(description="the hazard's or the action's name (initial: the "
                                   "machine's)")
    during: str | Absent = Field(None, description="a hazard's: the action it struck")
    mode: str = Field(description="the mode the step entered")


class CauseShare(Answer):
    """One cause and its probability; a property's causes add up to its value (or, in an
    MDP, to its min and to its max, each under the scheduler that attains it)."""

    cause: CauseKey = Field(description="the cause")
    probability: float = Field(ge=0, description="the probability of reaching the target "
                                                 "by this cause")
    under: Literal["min", "max", "value"] = Field(
        description="the scheduler: that of the min or the max (an MDP), or value (a DTMC)")


class PropertyResult(Answer):
    """One property's answer."""

    name: str = Field(description="the property's name ('adhoc' for --formula)")
    formula: str = Field(description="the formula in afsm syntax, as written")
    min: float | None = Field(description=c.MIN)
    max: float | None = Field(description=c.MAX)
    uniform: float | None = Field(description=c.UNIFORM)
    value: float | None = Field(description=c.VALUE)
    infinite: list[Literal["min", "max", "uniform", "value"]] | Absent = Field(
        None, description=c.INFINITE)
    seconds: dict[Literal["min", "max", "uniform", "value"], float] = Field(
        description="Storm's time to check each value given, s (of the query asked instead: "
                    "a Pmax as 1 - Pmin, a bounded G as its dual); with interval "
                    "probabilities, the reference point's queries (the bounds' time is "
                    "timings.bounds)")
    threshold: c.Threshold | None = Field(description=c.THRESHOLD)
    verdict: c.Verdict | None = Field(description=c.VERDICT)
    error: float | None = Field(description=c.ERROR)
    reason: str | Absent = Field(None, description=c.REASON)
    broken_by: c.Bound | Absent = Field(None, description=c.BROKEN_BY)
    decided_by: c.DecidedBy | Absent = Field(None, description=c.DECIDED_BY)
    exact: dict[Literal["min", "max", "uniform", "value"], str] | Absent = Field(
        None, description="--exact: each value as the fraction 'num/den'")
    reference: c.Reference | Absent = Field(None, description=c.REFERENCE)
    attained_at: c.AttainedAt | Absent = Field(None, description=c.ATTAINED_AT)
    strategy: dict[c.Bound, list[StrategyEntry]] | Absent = Field(
        None, description="--strategy: the min and max strategies in mission terms")
    turns: dict[c.Bound, list[TurnEntry]] | Absent = Field(
        None, description="--strategy on a mission whose agents' turns are a choice: which "
                          "agent each strategy moves")
    witnesses: list[Witness] | Absent = Field(
        None, description="--witness K: the most probable paths into the target")
    witness_strategy: Literal["min", "max", "value"] | Absent = Field(
        None, description="with witnesses: the strategy they follow (value: a DTMC's)")
    witness_violates: bool | Absent = Field(
        None, description="with witnesses: they go where the property can no longer hold "
                          "(a P>= requirement's violations)")
    witness_note: str | Absent = Field(
        None, description="with witnesses: why there are fewer than asked")
    causes: list[CauseShare] | Absent = Field(
        None, description="--causes: the probability split by what led into the target, "
                          "most probable first (docs/report.md, \"How it fails\")")


class Timings(Answer):
    """Where the time went, s."""

    load: float = Field(ge=0, description="parse, resolve and check the .afsm file")
    parse: float = Field(ge=0, description="Storm parsing the model")
    build: float = Field(ge=0, description="Storm building the (first) model")
    check: float = Field(ge=0, description="Storm checking it")
    uniform_build: Seconds | Absent = Field(None, description="building the uniform DTMC")
    uniform_check: Seconds | Absent = Field(None, description="checking it")
    bounds: Seconds | Absent = Field(
        None, description="with interval probabilities: Storm's parametric engine bounding "
                          "the properties over them (build and refinement)")
    total: float = Field(ge=0, description="the whole run")


class StateSpace(Answer):
    """The state space's size before it was built, and the limit."""

    upper_bound: int = Field(ge=0, description="modes x the product of the variables' ranges")
    max_states: int = Field(ge=0, description="the --max-states in effect")


class IntervalBound(Answer):
    """A property's bounds over the interval probabilities."""

    name: str = Field(description="the property")
    outer_min: float | None = Field(description="min_attained minus the refinement "
                                                "precision (null: infinite)")
    outer_max: float | None = Field(description="max_attained plus the refinement precision "
                                                "(null: infinite)")
    min_attained: float | None = Field(description="the least value Storm found, at `min_at`: "
                                                   "the property's `min` (null: infinite)")
    max_attained: float | None = Field(description="the greatest value Storm found, at "
                                                   "`max_at`: the property's `max` (null: "
                                                   "infinite)")
    min_at: dict[str, float] = Field(description="where: each interval probability's value")
    max_at: dict[str, float] = Field(description="where: each interval probability's value")
    engine: Literal["lifting", "parametric"] = Field(
        description="what computed the bounds: parameter lifting on afsmc's explorer "
                    "(\"lifting\", docs/uncertainty.md) or Storm's parametric engine "
                    "(\"parametric\", the fallback for missions the explorer does not take)")
    infinite: list[Literal["outer_min", "outer_max", "min_attained",
                           "max_attained"]] | Absent = Field(
        None, description="which of the four are an infinite expected reward (JSON has no "
                          "infinity: they are null); absent when none is")


class ProbabilityIntervals(Answer):
    """The bounds over the interval probabilities (`const prob P = [lo, hi]`), from Storm's
    parametric engine."""

    box: dict[str, tuple[float, float]] = Field(
        description="each interval probability's interval [lo, hi]")
    precision: float = Field(ge=0, description="the bounds' precision (the region refinement's)")
    meaning: str = Field(description="what the bounds are, in words")
    properties: list[IntervalBound] = Field(description="one entry per property")


class BaselineChange(Answer):
    """One property against the baseline (`--baseline old.json`)."""

    name: str = Field(description="the property")
    old: dict[Literal["min", "max", "value"], float | None] = Field(
        description="its bounds in the baseline (null: not there, or infinite)")
    new: dict[Literal["min", "max", "value"], float | None] = Field(
        description="its bounds now (null: not there, or infinite)")
    old_verdict: c.Verdict | None = Field(description="the baseline's verdict")
    new_verdict: c.Verdict | None = Field(description="the verdict now")
    moved: float | None = Field(description="the largest change of a bound given in both "
                                            "(null: one became infinite)")
    flipped: bool = Field(description="the verdict changed")
    worse: bool = Field(description="it changed away from holds (exit 1)")
    flagged: bool = Field(description="flipped, moved by more than the tolerance, or in "
                                      "one run only")
    only_in: Literal["old", "new"] | Absent = Field(
        None, description="the property is in that run only")


class Baseline(Answer):
    """`--baseline`: this run against an earlier `afsmc verify --json`."""

    baseline: str = Field(description="the baseline file")
    tolerance: float = Field(ge=0, description="--tolerance: a bound that moved by more is "
                                               "flagged")
    changes: list[BaselineChange] = Field(description="one entry per property, this run's "
                                                      "order, then those only in the "
                                                      "baseline")


class Symmetry(Answer):
    """The symmetry reduction of a mission with alike agents (docs/language.md,
    "Symmetry"): applied, or why not. Exact either way: the values are the same."""

    groups: list[list[str]] = Field(description="the agents of each group kept in a "
                                                "canonical order; empty when not applied")
    reason: str | None = Field(description="why it was not applied (a property, label or "
                                           "reward that tells the agents apart, or an "
                                           "output that names them); null when applied")


class Verification(Answer):
    """`afsmc verify --json` when it succeeds (exit 0, or 1 when a requirement does not
    hold)."""

    file: str = Field(description="the .afsm file, as given")
    machine: str = Field(description="the machine's name")
    model: ModelStats = Field(description="the model checked first: the MDP, or the only DTMC")
    uniform_model: ModelStats | None = Field(description="an MDP's uniform DTMC, else null")
    properties: list[PropertyResult] = Field(description="one answer per property, in order")
    timings: Timings = Field(description="seconds, rounded to 1e-6")
    via: Literal["prism", "jani"] = Field(description="Storm's input language")
    engine: Literal["auto", "sparse", "dd", "hybrid"] = Field(description="--engine as given")
    constants: dict[str, ConstValue] = Field(description="the open constants' values used")
    state_space: StateSpace = Field(description="size before building, and the limit")
    warnings: list[Diagnostic] = Field(description="afsmc's warnings, as in `afsmc check --json`")
    uncertainty: list[Literal["interval constants", "agent order",
                              "interval probabilities"]] = Field(
        description="what min and max range over (docs/verification.md, \"What a result "
                    "means\"); empty: nothing is uncertain, a DTMC's one value per property")
    probability_intervals: ProbabilityIntervals | Absent = Field(
        None, description="bounds over the interval probabilities; absent without them")
    baseline: Baseline | Absent = Field(None, description="--baseline: what changed")
    symmetry: Symmetry | Absent = Field(
        None, description="the symmetry reduction, applied or why not; absent where no "
                          "agents are alike (or --no-symmetry)")


class VerifyFailure(Answer):
    """`afsmc verify --json` when it fails (exit 1; 3 for a bug in afsmc) or is stopped
    (exit 130 after a Ctrl-C, 143 after a SIGTERM): the diagnostics, and what was answered
    before, with null for each value not answered."""

    interrupted: Literal[True] | Absent = Field(None, description="stopped by Ctrl-C or SIGTERM")
    diagnostics: list[Diagnostic] = Field(description="what went wrong; an N412 note lists "
                                                      "what was answered")
    model: ModelStats | None = Field(None, description="absent when nothing was built; null "
                                                       "if none of its processes finished")
    uniform_model: ModelStats | None = Field(None, description="as `model`, for the uniform DTMC")
    properties: list[PropertyResult] | Absent = Field(
        None, description="the answers so far, null where not answered")


class VerifyOutput(RootModel[Verification | VerifyFailure]):
    """Every object `afsmc verify --json` prints: the answer, or a failure."""

    model_config = ConfigDict(frozen=True)
