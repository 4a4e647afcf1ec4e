"""What every answer shares: the frozen base model, the diagnostics, a requirement's
threshold and verdict, and the reference values and attaining points of a bound.

A field typed ``X | Absent = None`` is a key that is absent when it does not apply and is
never ``null``; ``X | None`` without a default is a key that is always there and may be
``null``; ``X | None = None`` may be absent or ``null``.
"""

from __future__ import annotations

import functools
import typing
from typing import Annotated, Any, ClassVar, Literal

from pydantic import (
    AfterValidator,
    BaseModel,
    ConfigDict,
    Field,
    SerializerFunctionWrapHandler,
    ValidationInfo,
    model_serializer,
)
from pydantic.json_schema import SkipJsonSchema

# One version for the five schemas, in each one's "$id" (urn:afsmc:schema:<name>:<version>).
# Raise it whenever any schema changes: a key added, removed, renamed or retyped.
SCHEMA_VERSION = 3


def _never_null_in_json(value: None, info: ValidationInfo) -> None:
    """An `Absent` key's null is refused in JSON (as the schema refuses it); in Python,
    None stands for the key left out."""
    if info.mode == "json":
        raise ValueError("this key is absent or has a value, never null")
    return value


# The type of a key that is left out rather than written as null (see the docstring).
Absent = Annotated[None, SkipJsonSchema(), AfterValidator(_never_null_in_json)]

# An open constant's value (`--const NAME=VALUE`, a `param`): a bool, an integer or a double.
ConstValue = bool | int | float

# Constrained numbers, as types so that a constraint holds inside `X | Absent` too.
Count = Annotated[int, Field(ge=0)]
Position = Annotated[int, Field(ge=1)]  # a line or column, from 1
Seconds = Annotated[float, Field(ge=0)]

Verdict = Literal["holds", "fails", "depends", "undecided"]
Bound = Literal["min", "max"]


class Answer(BaseModel):
    """An object of afsmc's JSON: immutable, no key but those declared, no infinite number.

    Validating JSON refuses a null where the key is `Absent`, as the schema does. Dumping
    (`model_dump(mode="json", by_alias=True)`, `model_dump_json(by_alias=True)`) leaves out
    an `Absent` key that is None, and an optional nullable key (`X | None = None`) that was
    not given: the object afsmc prints, with its keys in the order of the fields."""

    # JSON has no infinity or NaN: a value that is one is refused, not written as null
    model_config = ConfigDict(frozen=True, extra="forbid", allow_inf_nan=False)
    # keys dumped before the others (a partial result's diagnostics come before the answer
    # it extends, as afsmc prints them)
    FIRST: ClassVar[tuple[str, ...]] = ()

    @model_serializer(mode="wrap")
    def _leave_out_absent(self, handler: SerializerFunctionWrapHandler) -> Any:
        out = handler(self)
        if not isinstance(out, dict):
            return out
        absent = absent_keys(type(self))
        for name, field in type(self).model_fields.items():
            if getattr(self, name) is None and (name in absent
                                                or name not in self.model_fields_set):
                out.pop(field.alias or name, None)
                out.pop(name, None)
        return {k: out[k] for k in self.FIRST if k in out} | out


@functools.cache
def absent_keys(cls: type[BaseModel]) -> frozenset[str]:
    """The fields of `cls` typed `X | Absent`: a key that is left out, never null."""
    def absent(annotation: Any) -> bool:
        return any(typing.get_origin(a) is Annotated
                   and any(isinstance(m, AfterValidator) and m.func is _never_null_in_json
                           for m in a.__metadata__)
                   for a in typing.get_args(annotation))

    return frozenset(n for n, f in cls.model_fields.items() if absent(f.annotation))


class RelatedPlace(Answer):
    """Another place in the source that a diagnostic refers to (where a name was declared
    first, the other writer of a variable, ...)."""

    message: str = Field(description="what this place is to the diagnostic")
    file: str = Field(description="the file, as it was given")
    line: Position = Field(description="line, from 1")
    column: Position = Field(description="column, from 1")


class Diagnostic(Answer):
    """An error, warning or note, as `afsmc check --json` prints it. Without a place in a
    file (an option's error, a failure of Storm, a note) the file and position keys are
    absent."""

    code: str = Field(pattern=r"^[EWN][0-9]{3}$",
                      description="the code (E: error, W: warning, N: note); "
                                  "`afsmc explain CODE` explains it")
    severity: Literal["error", "warning", "note"] = Field(
        description="error: the command failed; warning: a likely mistake; note: "
                    "information (what was kept when a run stopped)")
    message: str = Field(description="what is wrong, in one sentence (a note may have "
                                     "several lines)")
    file: str | Absent = Field(None, description="the file the span is in (`--formula` "
                                                 "for an ad-hoc property)")
    line: Position | Absent = Field(None, description="the span's first line, from 1")
    column: Position | Absent = Field(None, description="the span's first column, from 1")
    end_line: Position | Absent = Field(None, description="the line the span ends on")
    end_column: Position | Absent = Field(None, description="the column just after the "
                                                            "span's end")
    hint: str | Absent = Field(None, description="how to fix it, when afsmc knows")
    related: list[RelatedPlace] | Absent = Field(
        None, description="other places in the source the diagnostic refers to")


class Threshold(Answer):
    """A requirement's comparison, as written: `P>=0.65 [ ... ]` is `{"op": ">=", "bound":
    0.65}`."""

    op: Literal[">=", ">", "<=", "<"] = Field(description="the comparison")
    bound: float = Field(description="the number the value is compared with")


class Reference(Answer):
    """The property's values at a reference point of the interval probabilities
    (`const prob P = [lo, hi]`): shown for orientation, never judged."""

    point: Literal["midpoint"] = Field(
        description="where the interval probabilities are fixed: each at its midpoint")
    min: float | None = Field(description="the min there (null: not asked, or infinite)")
    max: float | None = Field(description="the max there (null: not asked, or infinite)")
    value: float | None = Field(description="a DTMC's one value there (null for an MDP)")
    uniform: float | None = Field(
        description="the value there with the interval constants' floor or ceil drawn "
                    "uniformly at random (null: not asked)")
    exact: dict[Literal["min", "max", "uniform", "value"], str] | Absent = Field(
        None, description="--exact: the values there as fractions `num/den`")


class AttainedAt(Answer):
    """Where the bounds are attained: a value of each interval probability, by name."""

    min: dict[str, float] = Field(description="the point where the min is attained")
    max: dict[str, float] = Field(description="the point where the max is attained")


# Descriptions shared by the property objects of verify and sweep.
MIN = ("the least value of the property over everything uncertain in the mission (interval "
       "constants, interval probabilities, who moves next), a sound bound within `error`; "
       "null for a DTMC, where not asked, where its query failed, or when infinite (then "
       "named in `infinite`)")
MAX = ("the greatest value over everything uncertain, a sound bound within `error`; null as "
       "for `min`")
UNIFORM = ("for an MDP of interval constants, the value when each one's floor or ceil is "
           "drawn uniformly at random at each step: a reference, never judged; null for a "
           "DTMC, with --no-uniform, or where no uniform model exists (agents that choose "
           "who moves next)")
VALUE = ("a DTMC's one value (a mission with nothing uncertain); null for an MDP, or as for "
         "`min`")
INFINITE = ("which of min, max, uniform and value are an infinite expected reward (JSON has "
            "no infinity: they are null); absent when none is")
THRESHOLD = "a requirement's comparison; null for a query (`=?`)"
VERDICT = ("a requirement's verdict: holds (the bound that counts meets the threshold for "
           "sure), fails (the other bound misses it for sure), depends (one bound meets it, "
           "the other does not), undecided (the threshold is within the error of a bound that "
           "decides); null for a query, or when a value it needs is missing")
ERROR = ("every value is within this of the true one (0: exact, with --exact); null: no "
         "guarantee (Storm's default precision, for a query)")
REASON = "the verdict in one sentence for people: the bound that decides it against the threshold"
BROKEN_BY = "for `depends`: the bound that misses the threshold"
DECIDED_BY = ("the bound the verdict rests on: for holds the worst bound (min for >= and >, "
              "max for <= and <), for fails the best one, for depends the one that misses, "
              "for undecided the one too near the threshold; value for a DTMC's one value; "
              "absent for a query (=?)")
DecidedBy = Literal["min", "max", "value"]
REFERENCE = ("the values at the interval probabilities' midpoint, never judged; absent "
             "without interval probabilities")
ATTAINED_AT = ("where min and max are attained over the interval probabilities; absent "
               "without them")
