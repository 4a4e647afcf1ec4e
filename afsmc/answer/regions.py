"""`afsmc regions --json`: a box of parameter values split into regions where a requirement
holds for every value, fails for every value, or is not decided."""

from __future__ import annotations

from typing import Literal

from pydantic import ConfigDict, Field, RootModel

from afsmc.answer import common as c
from afsmc.answer.common import Absent, Answer, Diagnostic


class Region(Answer):
    """A sub-box and what parameter lifting (or exact corner values of a value proven
    monotone) proved for all of it."""

    bounds: dict[str, tuple[float, float]] = Field(
        description="each parameter's interval [lo, hi] in this region")
    verdict: Literal["holds", "fails", "unknown"] = Field(
        description="holds or fails for every value of the region, or not decided")


class Regions(Answer):
    """The regions of the box (exit 0)."""

    requirement: str = Field(description="the --require property, as written")
    box: dict[str, tuple[float, float]] = Field(
        description="each parameter's interval [lo, hi]: the --param ranges, and the "
                    "interval probabilities not named there")
    coverage: float = Field(ge=0, le=1, description="the decided fraction of the box's volume")
    target_coverage: float = Field(gt=0, le=1, description="the --coverage asked for")
    holds: float = Field(ge=0, le=1, description="the fraction of the volume where it holds")
    fails: float = Field(ge=0, le=1, description="the fraction where it fails")
    unknown: float = Field(ge=0, le=1, description="the fraction not decided")
    rounds: int = Field(ge=0, description="rounds of halving run")
    states: int = Field(ge=0, description="states of the parametric model")
    seconds: float = Field(ge=0, description="the run's time, s, rounded to 1e-3")
    verdict: Literal["holds", "fails", "depends", "undecided"] = Field(
        description="the verdict over the whole box, in verify's words (docs/verification.md, "
                    "\"What a result means\")")
    reason: str = Field(description="one sentence: why the box has that verdict")
    from_file: list[str] = Field(
        description="the dimensions no --param named: the file's interval probabilities")
    region_meaning: str | None = Field(
        description="what a region's verdict means where it is not verify's word for the "
                    "values in it (an MDP with a bare requirement: a region fails where "
                    "some floor/ceil choice misses it); null where it is")
    min: float | None = Field(
        description="the requirement's value's min over the whole box, as `afsmc verify` "
                    "bounds it (by `engine`); null if not computed")
    max: float | None = Field(description="its max over the whole box, likewise")
    error: float | None = Field(description="each bound's error: the true extreme lies "
                                            "within it")
    decided_by: c.DecidedBy | None = Field(description=c.DECIDED_BY)
    engine: Literal["lifting", "parametric"] = Field(
        description="what decided the regions and bounded the whole box: afsmc's explorer "
                    "(\"lifting\": lifted bounds, and exact corner values where the value "
                    "is proven monotone; docs/uncertainty.md) or Storm's parametric engine "
                    "and region checker (\"parametric\", for missions the explorer does not "
                    "take)")
    regions: list[Region] = Field(description="the regions, decided ones first")
    feasible: dict[str, float] | None = Field(
        None, description="--feasible: one valuation of the parameters that meets the "
                          "requirement; null if none was found; absent without --feasible")
    feasible_method: str | None = Field(
        None, description="--feasible: how it was found (Storm's feasibility check, or the "
                          "centre of the largest region where it holds); null as `feasible`")


class RegionsFailure(Answer):
    """`afsmc regions --json` when it fails (exit 1; 3 for a bug in afsmc) or is stopped
    (exit 130 or 143)."""

    interrupted: Literal[True] | Absent = Field(None, description="stopped by Ctrl-C or SIGTERM")
    diagnostics: list[Diagnostic] = Field(description="what went wrong")


class RegionsOutput(RootModel[Regions | RegionsFailure]):
    """Every object `afsmc regions --json` prints."""

    model_config = ConfigDict(frozen=True)
