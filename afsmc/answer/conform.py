"""`afsmc conform --json`: logged runs checked against the spec (the steps it does not
allow) and the constants estimated from them, judged by sim-check's rules."""

from __future__ import annotations

from typing import Literal

from pydantic import ConfigDict, Field, RootModel

from afsmc.answer.common import Answer, Count, Diagnostic

# the quantile intervals of a constant judged on too few samples reach infinity
Bound = float | Literal["inf", "-inf"]


class ConstantEvidence(Answer):
    """One constant estimated from the logs and judged (the rules of docs/monte-carlo.md)."""

    name: str = Field(description="the constant")
    ref: str = Field(description="where its evidence comes from: the logs")
    kind: Literal["duration", "probability"] = Field(
        description="what the logs measured: the values of an interval constant, or the "
                    "outcomes of the draws of a probability")
    shape: Literal["interval", "number", "probability", "probability interval"] = Field(
        description="the rule it is judged by")
    declared: str = Field(description="its value as the spec states it")
    runs: Count = Field(description="its samples: trials of a probability, measured values "
                                    "of an interval constant")
    seed: None = Field(description="always null: the logs are not a seeded simulation")
    mean: float = Field(description="the samples' mean (a probability's estimate)")
    mean_low: float = Field(description="the confidence interval of the mean, lower end "
                                        "(Clopper-Pearson for a probability)")
    mean_high: float = Field(description="its upper end")
    cdf_lo: float | None = Field(description="an interval constant: the samples' CDF at its "
                                             "floor; else null")
    cdf_hi: float | None = Field(description="the samples' CDF at its ceiling; else null")
    hull: list[int] | None = Field(description="an interval constant: the integer hull of "
                                               "the samples' central coverage; else null")
    accept: str = Field(description="what the rule accepts")
    verdict: Literal["consistent", "drifted", "inconclusive"] = Field(
        description="inconclusive: consistent, with too few samples to bound what the rule "
                    "accepts")
    suggestion: str | None = Field(description="the value --update writes; null if no "
                                               "value of its type fits the rule")
    confidence: float = Field(gt=0, lt=1, description="the confidence level of the test")
    coverage: float | None = Field(description="an interval constant's central coverage")
    method: str | None = Field(description="the confidence interval's method "
                                           "(Clopper-Pearson for a probability)")


class Conformance(Answer):
    """`afsmc conform --json` when the logs could be read (exit 0; 1 on a violation or a
    drift)."""

    file: str = Field(description="the .afsm file, as given")
    logs: list[str] = Field(description="the log files, as given")
    runs: Count = Field(description="runs in the logs")
    steps: Count = Field(description="steps checked")
    ambiguous: Count = Field(description="steps whose changes fit several outcomes (not "
                                         "counted as evidence of which)")
    violations: list[Diagnostic] = Field(description="E720: each step the spec does not "
                                                     "allow, at its log's line, with the state")
    constants: list[ConstantEvidence] = Field(description="each constant the logs exercise")
    unexercised: list[str] = Field(description="constants the logs could estimate but do "
                                               "not exercise")
    updated: list[str] = Field(description="--update: the constants rewritten in the file")
    diagnostics: list[Diagnostic] = Field(description="E721: drifted constants (E508: "
                                                      "with no value their rule accepts)")


class ConformFailure(Answer):
    """`afsmc conform --json` when the spec or the logs cannot be used (exit 1): the
    file's errors, E701, and every bad line of the logs (E710-E713)."""

    diagnostics: list[Diagnostic] = Field(description="what went wrong")


class ConformOutput(RootModel[Conformance | ConformFailure]):
    """Every object `afsmc conform --json` prints."""

    model_config = ConfigDict(frozen=True)
