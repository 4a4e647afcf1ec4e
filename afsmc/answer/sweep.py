"""`afsmc sweep --json` (and `-o FILE.json`): a property's values over a range of one
constant or of the step bound, or over a grid of several constants (long format), with the
sub-ranges where each requirement holds; on failure the diagnostics with the points that
were evaluated."""

from __future__ import annotations

from typing import ClassVar, Literal

from pydantic import ConfigDict, Field, RootModel

from afsmc.answer import common as c
from afsmc.answer.common import Absent, Answer, ConstValue, Diagnostic

# A point's verdict: a requirement's, or "no value" where its query failed.
PointVerdict = Literal["holds", "fails", "depends", "undecided", "no value"]

FILE = "the .afsm file, as given"
KIND = "what is swept: const (open constants) or bound (the properties' step bound)"
TYPE = "the models' type: mdp (min and max) or dtmc (one value)"
STATES = "reachable states of the point's model (the MDP or the DTMC); null if it failed"
TRANSITIONS = "its transitions; null if it failed"
UNIFORM_STATES = "states of the point's uniform DTMC; null for a DTMC, with --no-uniform, or " \
                 "if it failed"
UNIFORM_TRANSITIONS = "its transitions; null as for uniform_states"


class SweepProperty(Answer):
    """A swept property."""

    name: str = Field(description="its name ('adhoc' for --formula)")
    formula: str | Absent = Field(None, description="in afsm syntax (a const sweep; a bound "
                                                    "sweep gives it at each point)")


class _Values(Answer):
    """A property's answer at one point (the fields of PointValue and GridRow; pydantic
    puts a base's fields after those of the bases listed before it)."""

    min: float | None = Field(description=c.MIN)
    max: float | None = Field(description=c.MAX)
    uniform: float | None = Field(description=c.UNIFORM)
    value: float | None = Field(description=c.VALUE)
    infinite: list[Literal["min", "max", "uniform", "value"]] | Absent = Field(
        None, description=c.INFINITE)
    threshold: c.Threshold | Absent = Field(None, description="a requirement's comparison; "
                                                             "absent for a query")
    verdict: c.Verdict | Absent = Field(None, description=c.VERDICT.replace("null", "absent"))
    error: float | Absent = Field(None, description=c.ERROR.replace("null", "absent"))
    reason: str | Absent = Field(None, description=c.REASON)
    broken_by: c.Bound | Absent = Field(None, description=c.BROKEN_BY)
    decided_by: c.DecidedBy | Absent = Field(None, description=c.DECIDED_BY)
    reference: c.Reference | Absent = Field(None, description=c.REFERENCE)
    attained_at: c.AttainedAt | Absent = Field(None, description=c.ATTAINED_AT)


class _Sizes(Answer):
    """A point's model sizes."""

    states: int | None = Field(description=STATES)
    transitions: int | None = Field(description=TRANSITIONS)
    uniform_states: int | None = Field(description=UNIFORM_STATES)
    uniform_transitions: int | None = Field(description=UNIFORM_TRANSITIONS)
    symmetry: str | Absent = Field(
        None, description="the symmetry reduction of alike agents at this point, in "
                          "verify's words: applied, or why not; absent where the mission "
                          "has no alike agents")


class _PointHead(Answer):
    name: str = Field(description="the property")
    formula: str | Absent = Field(None, description="a bound sweep: the formula with this "
                                                    "point's bound")


class PointValue(_Values, _PointHead):
    """One property's answer at one point of a sweep over one constant or the bound."""


class _SweepPointHead(Answer):
    x: ConstValue = Field(description="the swept constant's value (or the step bound) here")


class _SweepPointTail(Answer):
    properties: list[PointValue] = Field(description="each property's answer here")


class SweepPoint(_SweepPointTail, _Sizes, _SweepPointHead):
    """One point of a sweep over one constant or the bound."""


class VerdictRange(Answer):
    """A run of consecutive points with the same verdict."""

    model_config = ConfigDict(frozen=True, extra="forbid", allow_inf_nan=False,
                              populate_by_name=True)

    verdict: PointVerdict = Field(description="their verdict")
    from_: ConstValue = Field(alias="from", description="the first point's x")
    to: ConstValue = Field(description="the last point's x (the same for one point)")


class SweepRequirement(Answer):
    """A swept requirement: the sub-ranges of x where it holds, fails, ..."""

    name: str = Field(description="the requirement")
    ranges: list[VerdictRange] = Field(description="the runs of points, in the order swept")


class Sweep(Answer):
    """A sweep over one constant or the step bound (exit 0)."""

    file: str = Field(description=FILE)
    variable: str = Field(description="the swept constant's name, or 'bound'")
    kind: Literal["const", "bound"] = Field(description=KIND)
    type: Literal["mdp", "dtmc"] = Field(description=TYPE)
    properties: list[SweepProperty] = Field(description="the swept properties, in order")
    points: list[SweepPoint] = Field(description="the points, in the order swept")
    requirements: list[SweepRequirement] | Absent = Field(
        None, description="each requirement's sub-ranges; absent without requirements")


class _GridHead(Answer):
    point: dict[str, ConstValue] = Field(description="each swept constant's value here")
    property: str = Field(description="the property")


class GridRow(_Sizes, _Values, _GridHead):
    """One property at one point of a sweep over several constants."""


class GridRequirement(Answer):
    """A requirement over a grid: how many points have each verdict."""

    name: str = Field(description="the requirement")
    points: dict[PointVerdict, int] = Field(description="points per verdict (only those that "
                                                        "occur)")


class SweepGrid(Answer):
    """A sweep over several constants, in long format (exit 0)."""

    file: str = Field(description=FILE)
    variables: list[str] = Field(description="the swept constants, the first varying slowest")
    kind: Literal["const"] = Field(description=KIND)
    type: Literal["mdp", "dtmc"] = Field(description=TYPE)
    properties: list[SweepProperty] = Field(description="the swept properties, in order")
    rows: list[GridRow] = Field(description="one row per point and property")
    requirements: list[GridRequirement] | Absent = Field(
        None, description="each requirement's verdict counts; absent without requirements")


class SweepFailure(Answer):
    """A sweep that failed before any point was evaluated (exit 1), or was stopped before
    (exit 130 or 143)."""

    interrupted: Literal[True] | Absent = Field(None, description="stopped by Ctrl-C or SIGTERM")
    diagnostics: list[Diagnostic] = Field(description="what went wrong")


class SweepPartial(Sweep):
    """A sweep over one constant or the bound of which some points or queries failed, or
    that was stopped: the points evaluated (a failed query's values null), and the
    diagnostics."""

    FIRST: ClassVar[tuple[str, ...]] = ("interrupted", "diagnostics")

    interrupted: Literal[True] | Absent = Field(None, description="stopped by Ctrl-C or SIGTERM")
    diagnostics: list[Diagnostic] = Field(description="what went wrong; an N412 note lists "
                                                      "the points evaluated")


class SweepGridPartial(SweepGrid):
    """A sweep over several constants of which some points or queries failed, or that was
    stopped: the rows evaluated, and the diagnostics."""

    FIRST: ClassVar[tuple[str, ...]] = ("interrupted", "diagnostics")

    interrupted: Literal[True] | Absent = Field(None, description="stopped by Ctrl-C or SIGTERM")
    diagnostics: list[Diagnostic] = Field(description="what went wrong; an N412 note lists "
                                                      "the points evaluated")


class SweepOutput(RootModel[Sweep | SweepGrid | SweepFailure | SweepPartial | SweepGridPartial]):
    """Every object `afsmc sweep --json` prints."""

    model_config = ConfigDict(frozen=True)
