"""Check rule for `from sim ...` and `from data ...` constants: the reference names a
registered simulator output of a fitting kind (a data column backs an `int`, `double` or
`prob`), and the policy keys are known and in range. A data file is read by `sim-check`
only (afsmc.simlib.datafile), never here.

A reference is only ever looked up in the simulator registry (`afsmc.simlib.registry`),
which is filled from the `afsmc.simulators` entry-point group: nothing the spec names is
imported, evaluated or used for attribute access.
"""

from __future__ import annotations

import difflib
from dataclasses import dataclass

from afsmc.diagnostics import Reporter, codes
from afsmc.model import ir
from afsmc.simlib import registry
from afsmc.text import article

# What a constant backed by a simulation is checked as (see docs/monte-carlo.md).
INTERVAL = "interval"  # const int X = [lo, hi] from sim <duration|battery>
NUMBER = "number"  # const int|double X = v from sim <duration|battery>
PROBABILITY = "probability"  # const prob|double X = p from sim <probability>
PROB_INTERVAL = "probability interval"  # const prob X = [lo, hi] from sim <probability>

# policy key -> (the shapes it applies to, default, (low, high) open/closed range text)
POLICY_KEYS: dict[str, tuple[frozenset[str], str]] = {
    "coverage": (frozenset({INTERVAL}), "the central fraction of samples [lo, hi] must hull (0 < c < 1)"),
    "confidence": (frozenset({INTERVAL, NUMBER, PROBABILITY, PROB_INTERVAL}),
                   "confidence level of the statistical test (0 < c < 1)"),
    "tolerance": (frozenset({NUMBER}), "allowed distance between value and mean (>= 0)"),
}
DATA = "data"  # the kind of a data column of measurements (`from data ... column ...`)
DEFAULT_COVERAGE = 0.95
DEFAULT_CONFIDENCE = 0.999


@dataclass(frozen=True)
class Policy:
    shape: str
    coverage: float
    confidence: float
    tolerance: float | None  # None: the default for the constant's type


def shape_of(const: ir.Constant) -> str:
    if const.prob_interval is not None:
        return PROB_INTERVAL
    if const.interval is not None:
        return INTERVAL
    if const.declared_type == "prob":
        return PROBABILITY
    return NUMBER


def policy_of(const: ir.Constant, confidence: float | None = None) -> Policy:
    """The constant's policy with defaults filled in (assumes the rule below passed);
    `confidence` replaces the default confidence (a constant that states one keeps it)."""
    assert const.source is not None
    given = dict(const.source.policy)
    shape = shape_of(const)
    if shape == NUMBER and const.source.column is None and \
            _kind(const.source.ref) == "probability":
        shape = PROBABILITY  # a `double` fed by a probability output
    return Policy(shape, float(given.get("coverage", DEFAULT_COVERAGE)),
                  float(given.get("confidence", DEFAULT_CONFIDENCE if confidence is None
                                  else confidence)),
                  float(given["tolerance"]) if "tolerance" in given else None)


def data_kind(const: ir.Constant) -> str:
    """What a data column backing `const` holds: outcomes (0/1, true/false) for a `prob`,
    measured figures for an `int` or a `double`; "" for a type no column can back."""
    return {"prob": "probability", "int": DATA, "double": DATA}.get(const.declared_type, "")


def _kind(ref: str) -> str | None:
    try:
        return registry.kind(ref)
    except registry.UnknownSimulator:
        return None


def check_sim_sources(model: ir.Model, rep: Reporter) -> None:
    refs: list[str] | None = None
    for c in model.constants:
        src = c.source
        if src is None:
            continue
        kind = data_kind(c) if src.column is not None else _kind(src.ref)
        if kind is None:
            refs = registry.available() if refs is None else refs
            close = difflib.get_close_matches(src.ref, refs, n=3, cutoff=0.6)
            hint = ("did you mean " + ", ".join(f"'{r}'" for r in close) + "?") if close else (
                "simulators are named, never imported: see `afsmc sim-check --list` for the "
                "registered outputs (built-in ones and those of the 'afsmc.simulators' entry points)")
            rep.error(codes.E501, f"unknown simulator output '{src.ref}' for constant '{c.name}'",
                      src.span, hint=hint)
        shape = shape_of(c)
        if kind is not None:
            _check_kind(c, kind, shape, rep)
            if kind == "probability" and shape == NUMBER:
                shape = PROBABILITY
        seen: set[str] = set()
        for i, (key, value) in enumerate(src.policy):
            at = src.keys[i] if i < len(src.keys) else src.span
            if key in seen:
                rep.error(codes.E504, f"policy key '{key}' is given twice", at)
                continue
            seen.add(key)
            if key not in POLICY_KEYS:
                close = difflib.get_close_matches(key, list(POLICY_KEYS), n=1, cutoff=0.5)
                rep.error(codes.E504, f"unknown policy key '{key}' for constant '{c.name}'", at,
                          hint=(f"did you mean '{close[0]}'? " if close else "")
                          + "known keys: " + ", ".join(sorted(POLICY_KEYS)))
                continue
            shapes, meaning = POLICY_KEYS[key]
            if shape not in shapes:
                rep.error(codes.E504, f"policy key '{key}' does not apply to {_shape_text(shape)} "
                          f"'{c.name}'", at, hint=f"'{key}': {meaning}; it applies to "
                          + " and ".join(_shape_text(s) for s in sorted(shapes)))
            elif key in ("coverage", "confidence") and not 0.0 < value < 1.0:
                rep.error(codes.E504, f"policy '{key} = {value}' is not in (0, 1)", at)
            elif key == "tolerance" and value < 0:
                rep.error(codes.E504, f"policy 'tolerance = {value}' is negative", at)


def _shape_text(shape: str) -> str:
    return {INTERVAL: "the interval constant", NUMBER: "the number",
            PROBABILITY: "the probability", PROB_INTERVAL: "the interval probability"}[shape]


def _check_kind(c: ir.Constant, kind: str, shape: str, rep: Reporter) -> None:
    assert c.source is not None
    if c.source.column is not None:
        if not kind:
            rep.error(codes.E503, f"a data column cannot back {_a(c.declared_type)} constant "
                      f"'{c.name}'", c.source.span,
                      hint="a column of outcomes (0/1) backs a 'prob' (a value or an interval "
                           "[lo, hi]); a column of measurements backs an 'int' (a value or an "
                           "interval [floor, ceil]) or a 'double'")
        return
    if kind == "probability":
        if shape == INTERVAL or c.declared_type not in ("prob", "double"):
            what = "an interval" if shape == INTERVAL else f"{_a(c.declared_type)} constant"
            rep.error(codes.E503, f"'{c.source.ref}' is a probability, but '{c.name}' is {what}",
                      c.source.span, hint=f"declare it as 'const prob {c.name} = p from sim "
                      f"{c.source.ref};'")
    elif c.declared_type not in ("int", "double"):
        rep.error(codes.E503, f"'{c.source.ref}' is a {kind} figure, but '{c.name}' is "
                  f"{_a(c.declared_type)} constant", c.source.span,
                  hint="a duration or battery figure is an int (optionally an interval "
                  "[floor, ceil]) or a double")


def _a(type_name: str) -> str:
    """"an 'int'", "a 'bool'"."""
    return f"{article(type_name)} '{type_name}'"
