"""`afsmc simulate --json`: Monte Carlo estimates of the properties with confidence
intervals, sample runs, and the strategy the runs followed."""

from __future__ import annotations

from typing import ClassVar, Literal

from pydantic import ConfigDict, Field, RootModel

from afsmc.answer.common import Absent, Answer, ConstValue, Diagnostic

# JSON has no infinity: an infinite estimate or bound is a string ("inf", "-inf"), one no
# run decided is null (verify writes null and names the key in `infinite` instead).
Estimate = float | Literal["inf", "-inf"] | None


class Followed(Answer):
    """`--strategy min:NAME|max:NAME`: the Storm strategy the runs followed."""

    property: str = Field(description="the property whose strategy it is")
    direction: Literal["min", "max"] = Field(description="its min or max strategy")
    value: Estimate = Field(description="the property's min or max, as Storm computed it "
                                        "('inf' for an infinite expected reward)")
    states: int = Field(ge=0, description="states in which the strategy was recorded")


class PropertyEstimate(Answer):
    """One property's estimate."""

    name: str = Field(description="the property")
    estimate: Estimate = Field(description="the estimate (a probability, or a mean "
                                           "reward); null if no run decided it")
    low: Estimate = Field(description="the confidence interval's lower end")
    high: Estimate = Field(description="its upper end ('inf' for an expected reward that "
                                       "undecided runs may make infinite)")
    undecided: int = Field(ge=0, description="runs stopped at --max-steps before deciding it")
    method: Literal["clopper-pearson", "normal", "range", "one-sided"] = Field(
        description="how the interval was made: Clopper-Pearson (a probability), the normal "
                    "approximation (a reward), or, when every run earned the same, from the "
                    "chance that a run differs and the range of a run's total in the model "
                    "(range), one-sided where the model gives no upper end")
    reason: str | Absent = Field(None, description="why the interval is range or one-sided")


class TraceStep(Answer):
    """One state of a sample run."""

    step: int = Field(ge=0, description="the step number, from 0 (the initial state)")
    mode: str = Field(description="the mode (a composed mission: each agent's)")
    action: str | Absent = Field(None, description="the action that led here; absent at step 0")
    hazard: str | Absent = Field(None, description="the hazard that happened instead of the "
                                                   "action's own outcome")
    outcome: int | str | Absent = Field(
        None, description="which outcome led here: its index among the action's outcomes "
                          "(0 for the first written), or the hazard's name (H/j for "
                          "outcome j of a hazard of several); absent at step 0")
    duration: int | dict[str, int] | Absent = Field(
        None, description="the value the step took for the interval constant its updates "
                          "read ({NAME: value} for several); absent where it reads none")
    vars: dict[str, int | bool] = Field(description="every variable's value, by name")


class Simulation(Answer):
    """`afsmc simulate --json` when it succeeds (exit 0)."""

    strategy: Followed | Absent = Field(None, description="--strategy: the strategy followed")
    file: str = Field(description="the .afsm file, as given")
    machine: str = Field(description="the machine's name")
    constants: dict[str, ConstValue] = Field(description="the open constants' values used")
    runs: int = Field(ge=0, description="runs made (stopped: the runs that finished)")
    seed: int = Field(ge=0, description="the random seed")
    resolve: Literal["uniform", "floor", "ceil", "lo", "hi"] = Field(
        description="--resolve as given: the interval constants' floor or ceil drawn "
                    "uniformly, or always the floor (floor, lo) or the ceil (ceil, hi)")
    at: Literal["draw", "mid", "min", "max"] = Field(
        description="interval probabilities: drawn once per run (draw), or at the "
                    "midpoint, lower or upper end")
    confidence: float = Field(gt=0, lt=1, description="the confidence level of the intervals")
    scheduler: str | Absent = Field(
        None, description="a composed mission whose agents' turns are a choice: the rule "
                          "that picks who moves")
    properties: list[PropertyEstimate] = Field(description="one estimate per property")
    traces: list[list[TraceStep]] | Absent = Field(
        None, description="--traces K: K sample runs, as --traces-out writes them")
    warnings: list[Diagnostic] = Field(description="afsmc's warnings (W602: modes that "
                                                   "cannot end)")


class SimulateFailure(Answer):
    """`afsmc simulate --json` when it fails (exit 1; 3 for a bug in afsmc), or is stopped
    before a batch of runs finished (exit 130 or 143)."""

    interrupted: Literal[True] | Absent = Field(None, description="stopped by Ctrl-C or SIGTERM")
    diagnostics: list[Diagnostic] = Field(description="what went wrong")


class SimulatePartial(Simulation):
    """A simulation stopped by Ctrl-C or SIGTERM (exit 130 or 143): the estimates of the
    runs that finished."""

    FIRST: ClassVar[tuple[str, ...]] = ("interrupted", "diagnostics")

    interrupted: Literal[True] = Field(description="stopped by Ctrl-C or SIGTERM")
    diagnostics: list[Diagnostic] = Field(description="an N412 note with the estimates so far")


class SimulateOutput(RootModel[Simulation | SimulateFailure | SimulatePartial]):
    """Every object `afsmc simulate --json` prints."""

    model_config = ConfigDict(frozen=True)
