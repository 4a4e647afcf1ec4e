"""Storm's parametric engine (storm-pars) on a lowered model whose chosen constants are
left undefined: the interval probabilities (`const prob P = [lo, hi]`) and the constants
`afsmc regions` varies.

Meaning of an interval probability: one fixed, unknown p in [lo, hi], the same wherever
the constant appears (P and 1 - P stay coupled). The bounds of a property over it are
Storm's `compute_extremal_value` on the parametric model (parameter lifting, refined until
the requested absolute precision), jointly with the floor/ceil choices of the integer
intervals (a parametric MDP: the scheduler and the parameters optimise together).

Guarantee. Storm returns a valuation p* and the value f(p*), which is attained, and
refines until no region can hold a better value by more than `precision`. So the true
minimum lies in [f(p*) - precision, f(p*)]; `Extreme.bound` is the outer end,
f(p*) - precision for a minimum and f(p*) + precision for a maximum: a value no fixed p
in the box goes beyond. The solver itself is Storm's sound value iteration (relative
precision 1e-6), whose error adds to that.

Storm's exact default environment for parametric models solves the lifted games with
rational arithmetic, which never finished on the patrol example's 319 states; the sound
floating-point environment answers in a fraction of a second.
"""

from __future__ import annotations

import dataclasses
import math
import os
import re
import tempfile
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass
from fractions import Fraction
from typing import Any, Literal

from afsmc.backends import jani as jani_backend
from afsmc.backends.prism import PrismPrinter, emit, formula_text, property_variants
from afsmc.diagnostics import CompileError, Diagnostic, Severity, codes
from afsmc.lower.lowering import Lowered
from afsmc.model import expr as E
from afsmc.model import ir
from afsmc.model.semantics import bounded_globally, globally_dual
from afsmc.verify.plan.precision import PARAMETER_PRECISION

Box = Mapping[str, tuple[float, float]]


def _fail(code: Any, message: str, span: Any = None, hint: str | None = None) -> CompileError:
    return CompileError([Diagnostic(code, Severity.ERROR, message, span, hint=hint)])


def rational(x: float) -> str:
    """A float as the decimal fraction it is written as ("0.05" is 1/20, not the binary
    double nearest to it)."""
    f = Fraction(repr(float(x)))
    return f"{f.numerator}/{f.denominator}"


@dataclass(frozen=True)
class Query:
    """One Storm query for a bound of a property: its name in the generated files, its
    PRISM text, the direction over the parameters, and whether the value is 1 - answer
    (a step-bounded G asked as its dual)."""

    prop: str
    end: str  # "min" | "max": which bound of the property this gives
    name: str
    text: str
    direction: str  # "min" | "max", over the parameters
    complement: bool


def queries(low: Lowered, prop: ir.Property) -> list[Query]:
    """The min and the max query of `prop` on `low` (a DTMC's one query twice)."""
    printer = PrismPrinter({}, low)
    out = []
    variants = dict((opt or "", name) for name, opt in property_variants(low, prop))
    for end in ("min", "max"):
        opt = end if low.kind == "mdp" and not prop.opt else prop.opt
        name = variants.get(opt, prop.name)
        if isinstance(prop.path, ir.Path) and prop.path.kind == "G":
            # Storm's parametric engine has no G: P [G φ] = 1 - P [F !φ], min and max
            # swapped (bounded or not)
            flipped = {"min": "max", "max": "min"}.get(opt, "")
            dual = (globally_dual(prop, name) if bounded_globally(prop) else dataclasses.replace(
                prop, path=ir.Path("F", E.neg(prop.path.target))))
            out.append(Query(prop.name, end, jani_backend.dual_name(low, name),
                             formula_text(dual, flipped, printer),
                             "max" if end == "min" else "min", True))
        else:
            out.append(Query(prop.name, end, name, formula_text(prop, opt, printer), end, False))
    return out


def with_parameters(low: Lowered, names: Iterable[str]) -> Lowered:
    """`low` with the constants `names` left undefined by the backends."""
    return dataclasses.replace(low, parameters=tuple(sorted(set(names))))


@dataclass(frozen=True)
class Source:
    """What a process needs to build the parametric model: picklable text."""

    via: str  # "prism" | "jani"
    model_text: str
    params: tuple[str, ...]


def source(low: Lowered, via: str) -> Source:
    if via == "jani":
        import json

        text = json.dumps(jani_backend.emit(low))
    else:
        text = emit(low).model
    return Source(via, text, low.parameters)


class Parametric:
    """The parametric sparse model Storm built from a `Source`, in this process."""

    def __init__(self, src: Source, formulas: Sequence[str]):
        import stormpy
        import stormpy.environments
        from stormpy import developer

        developer.set_log_level(developer.LogLevel.OFF)  # warnings per state on stdout
        self.stormpy = stormpy
        self.src = src
        try:
            if src.via == "jani":
                program, props = stormpy.parse_jani_model_from_string(src.model_text)
                self.by_name = {p.get_name(): p for p in props}
                self.program = program
            else:
                with tempfile.TemporaryDirectory(prefix="afsmc-") as tmp:
                    path = os.path.join(tmp, "model.prism")
                    with open(path, "w", encoding="utf-8") as f:
                        f.write(src.model_text)
                    self.program = stormpy.parse_prism_program(path)
                self.by_name = {}
            self.formulas = {f: self.parse(f) for f in formulas}
            raws = [p.get_raw_formula() for p in self.formulas.values()] + [
                p.get_raw_formula() for p in self.by_name.values()]
            opts = stormpy.BuilderOptions(raws)
            self.model = stormpy.build_model[stormpy.RationalFunction](self.program, options=opts)
        except RuntimeError as exc:
            raise _fail(codes.E443, f"Storm's parametric engine: {_message(exc)}") from None
        self.vars = {v.name: v for v in self.model.collect_all_parameters()}
        self._checkers: dict[str, Any] = {}
        self.env = stormpy.environments.sound()

    def parse(self, text: str) -> Any:
        return self.stormpy.parse_properties(text, self.program)[0]

    def prop(self, q: Query) -> Any:
        """The JANI file's own property where it has one, else the PRISM-syntax text
        (Storm reads it against either model)."""
        if self.src.via == "jani" and not q.complement and q.name in self.by_name:
            return self.by_name[q.name]
        return self.formulas[q.text]

    def region(self, box: Box) -> Any:
        import stormpy.pars as sp

        Q = sp.RationalFunctionCoefficient
        bounds = {}
        for name, var in self.vars.items():
            lo, hi = box[name]
            bounds[var] = (Q(rational(lo)), Q(rational(hi)))
        return sp.create_region(bounds)

    def well_defined(self, box: Box) -> str | None:
        """Why `box` is no graph-preserving region, or None: a transition's probability
        that is 0 (or not in (0, 1]) at a corner of the box."""
        import itertools

        import stormpy.pars as sp

        Q = sp.RationalFunctionCoefficient
        names = sorted(self.vars)
        corners = [dict(zip(names, c, strict=True))
                   for c in itertools.product(*(box[n] for n in names))]
        seen: set[str] = set()
        for state in self.model.states:
            for action in state.actions:
                for t in action.transitions:
                    f = t.value
                    if f.is_constant():
                        continue
                    key = str(f)
                    if key in seen:
                        continue
                    seen.add(key)
                    for c in corners:
                        v = float(f.evaluate({self.vars[n]: Q(rational(x))
                                              for n, x in c.items()}))
                        if not 0.0 < v <= 1.0:
                            at = ", ".join(f"{n}={x:g}" for n, x in c.items())
                            shown = key[:-4] if key.endswith("/(1)") else key
                            return f"at {at} a transition's probability {shown} is {v:g}"
        return None

    # Storm's own graph-preservation test refuses boxes of two or more parameters that it
    # cannot prove well-defined; `well_defined` has checked every transition at every
    # corner of the whole box (afsmc's probabilities are multilinear in the parameters:
    # products of P and 1 - P), so the checkers below are told the precondition holds.
    def _task(self, prop: Any) -> Any:
        from stormpy import developer

        return developer.CheckTask[self.stormpy.RationalFunction](prop.get_raw_formula(), True)

    def extremal(self, q: Query, box: Box, precision: float) -> tuple[float, dict[str, float]]:
        import stormpy.pars as sp
        import stormpy.pars.developer as pd

        d = sp.OptimizationDirection
        try:
            checker = pd.initialize_region_refinement_checker(
                self.env, self.model, self._task(self.prop(q)), preconditions_validated=True)
            value, at = checker.compute_extremal_value(
                self.env, self.region(box), d.MINIMIZE if q.direction == "min" else d.MAXIMIZE,
                self.stormpy.RationalFunction(sp.Polynomial(sp.RationalFunctionCoefficient(
                    rational(precision)))), True)
        except RuntimeError as exc:
            raise _fail(codes.E443, f"Storm's parametric engine on {q.prop}: "
                        f"{_message(exc)}") from None
        return float(value), {v.name: float(x) for v, x in at.items()}

    def analyze(self, formula: str, box: Box) -> str:
        """"holds" if every valuation in `box` satisfies `formula` (parameter lifting),
        "fails" if none does, else "unknown"."""
        import stormpy.pars.developer as pd

        try:
            checker = self._checkers.get(formula)
            if checker is None:
                checker = pd.initialize_region_model_checker(
                    self.env, self.model, self._task(self.formulas[formula]),
                    preconditions_validated=True)
                self._checkers[formula] = checker
            res = checker.analyze_region(self.env, self.region(box),
                                         pd.RegionResultHypothesis.UNKNOWN, False)
        except RuntimeError as exc:
            raise _fail(codes.E443, f"Storm's parametric engine: {_message(exc)}") from None
        return {pd.RegionResult.ALL_SAT: "holds",
                pd.RegionResult.ALL_VIOLATED: "fails"}.get(res, "unknown")

    def feasible(self, formula: str, box: Box) -> dict[str, float] | None:
        import stormpy.pars as sp

        try:
            res = sp.check_feasibility(self.model, self.formulas[formula],
                                       region=self.region(box), environment=self.env)
        except RuntimeError as exc:
            raise _fail(codes.E443, f"Storm's parametric engine: {_message(exc)}") from None
        witness = res.witness
        if witness is None:
            return None
        return {v.name: float(x) for v, x in witness.valuation.items()}


def _message(exc: BaseException) -> str:
    text = str(exc).strip().splitlines()
    return re.sub(r"^.*?ERROR \(.*?\): ", "", text[-1] if text else type(exc).__name__)


@dataclass(frozen=True)
class Extreme:
    """A property's bounds over the interval probabilities: `min`/`max` are the outer
    (sound) ends; `attained` the value found at `min_at`/`max_at`; `engine` what found
    them: "parametric" (Storm's parametric engine) or "lifting" (parameter lifting on
    afsmc's explorer, afsmc.verify.lifting)."""

    name: str
    min: float
    max: float
    min_attained: float
    max_attained: float
    min_at: dict[str, float]
    max_at: dict[str, float]
    engine: Literal["lifting", "parametric"] = "parametric"

    def to_json(self) -> dict[str, object]:
        """JSON has no infinity: an infinite bound (an expected reward) is null, named in
        `infinite`, as in a property's own object."""
        values = {"outer_min": self.min, "outer_max": self.max,
                  "min_attained": self.min_attained, "max_attained": self.max_attained}
        out: dict[str, object] = {"name": self.name}
        out |= {k: v if math.isfinite(v) else None for k, v in values.items()}
        out |= {"min_at": self.min_at, "max_at": self.max_at, "engine": self.engine}
        infinite = [k for k, v in values.items() if not math.isfinite(v)]
        if infinite:
            out["infinite"] = infinite
        return out


def interval_box(model: ir.Model) -> dict[str, tuple[float, float]]:
    return {c.name: c.prob_interval for c in model.prob_intervals if c.prob_interval}


def _corners(box: Box) -> list[dict[str, float]]:
    import itertools

    names = sorted(box)
    return [dict(zip(names, c, strict=True)) for c in itertools.product(*(box[n] for n in names))]


def well_defined_ir(low: Lowered, box: Box) -> tuple[bool, str | None]:
    """Whether every branch probability of `low` that reads a parameter stays in (0, 1] at
    every corner of `box`: (True, None) if so, (True, why) if not, and (False, None) when
    a probability also reads the state (then Storm's transitions are checked instead)."""
    from afsmc.model.evaluate import EvalError, scalar
    from afsmc.model.pretty import show
    from afsmc.model.semantics import inline

    model = low.model
    consts: dict[str, Any] = dict(model.const_values)
    consts |= {gen: value for gen, (_, value) in low.bounds.items()}
    seen: set[E.Expr] = set()
    corners = _corners(box)
    for cmd in low.commands:
        for b in cmd.branches:
            e = inline(b.prob, model)
            if e in seen or not E.consts_read(e) & set(box):
                continue
            seen.add(e)
            if E.vars_read(e) or E.reads_mode(e):
                return False, None
            for c in corners:
                try:
                    v = float(scalar(e, consts | c))
                except (EvalError, ZeroDivisionError, OverflowError):
                    return False, None
                if not 0.0 < v <= 1.0:
                    at = ", ".join(f"{n}={x:g}" for n, x in c.items())
                    return True, (f"at {at} the probability {show(e)} of a branch of "
                                  f"{cmd.action} is {v:g}")
    return True, None


def check_box(low: Lowered, built: Parametric, box: Box) -> None:
    """E440 unless `box` is a graph-preserving region of the parametric model."""
    decided, why = well_defined_ir(low, box)
    if not decided:
        why = built.well_defined(box)
    if why is not None:
        raise ill_defined(low.model, box, why)


def ill_defined(model: ir.Model, box: Box, why: str) -> CompileError:
    """E440: the box reaches a valuation where a transition disappears."""
    edge = [n for n, (lo, hi) in box.items() if lo == 0.0 or hi == 1.0]
    hint = ("Storm's parameter lifting needs every transition to keep a positive "
            "probability in the whole box: use an open bound, e.g. "
            + ", ".join(_open_bound(model, n, lo, hi) for n, (lo, hi) in box.items()
                        if n in edge)
            if edge else "narrow the box so that every probability stays positive")
    span = next((c.span for c in model.constants if c.name in edge), None)
    return _fail(codes.E440, f"the parameter box makes the model ill-defined: {why}", span,
                 hint=hint)


def _open_bound(model: ir.Model, name: str, lo: float, hi: float) -> str:
    """The box's side `name` with open ends: as the file's declaration when the side is
    the file's interval, else as a --param flag."""
    a, b = _open(lo, "lo"), _open(hi, "hi")
    if any(c.name == name and c.prob_interval == (lo, hi) for c in model.constants):
        return f"const prob {name} = [{a}, {b}];"
    return f"{name} in [{a}, {b}] (--param {name}={a}:{b})"


def _open(x: float, end: str) -> str:
    if end == "lo" and x == 0.0:
        return "1e-6"
    if end == "hi" and x == 1.0:
        return "0.999999"
    return f"{x:g}"


def extremes(low: Lowered, props: Sequence[ir.Property], *, via: str = "prism",
             precision: float = PARAMETER_PRECISION, box: Box | None = None
             ) -> list[Extreme]:
    """Each property's min and max over every p in `box` (default: the interval
    probabilities' box), jointly with the floor/ceil choices of `low` (the nondet
    lowering)."""
    box = interval_box(low.model) if box is None else box
    plow = with_parameters(low, box)
    qs = extreme_queries(plow, props)
    built = Parametric(source(plow, via), sorted({q.text for v in qs.values() for q in v}))
    check_box(low, built, box)
    return extremes_on(built, qs, props, box, precision)


def extreme_queries(plow: Lowered, props: Sequence[ir.Property]) -> dict[str, list[Query]]:
    """The min and max queries of each property (by name) on the parametric model `plow`:
    their texts are what a `Parametric` must be built with to answer them."""
    return {p.name: queries(plow, p) for p in props}


def extremes_on(built: Parametric, qs: Mapping[str, list[Query]],
                props: Sequence[ir.Property], box: Box, precision: float) -> list[Extreme]:
    """`extremes` on a parametric model already built with the texts of `qs`
    (`extreme_queries`), whose box is known to be well defined."""
    out = []
    for p in props:
        got: dict[str, tuple[float, float, dict[str, float]]] = {}
        for q in qs[p.name]:
            v, at = built.extremal(q, box, precision)
            if q.complement:
                v = 1.0 - v
            outer = v - precision if q.end == "min" else v + precision
            if p.kind == "P":
                outer = min(1.0, max(0.0, outer))
            got[q.end] = (outer, v, at)
        out.append(Extreme(p.name, got["min"][0], got["max"][0], got["min"][1], got["max"][1],
                           got["min"][2], got["max"][2]))
    return out


def to_json(box: Mapping[str, tuple[float, float]], found: Sequence[Extreme],
            precision: float = PARAMETER_PRECISION) -> dict[str, object]:
    return {"box": {n: list(b) for n, b in box.items()}, "precision": precision,
            "meaning": "one fixed value in each interval; min_attained/max_attained are the "
                       "properties' min and max (the true extremes lie within their error, "
                       "beyond them); outer_min/outer_max lie the refinement precision "
                       "further out",
            "properties": [e.to_json() for e in found]}
