"""What matters most: how each requirement's deciding bound moves with each figure.

The figures are the mission's `param double` constants and its probabilities (`const
prob P = 0.01`, and interval probabilities `const prob P = [lo, hi]`, taken at their
midpoint). A requirement's sensitivity to a figure is the derivative of the bound its
verdict rests on (`decided_by`: min, max or the value) at the nominal point, by the
central difference of two verifications with the figure set a step below and above its
value in the file's text, each requirement asked for its values (`=?`: verify's exact
backward pass where the model is acyclic, else its value iteration to a relative 1e-10)
so that the difference is exact to far more digits than shown (docs/report.md, "What
matters most"). Integer constants have no derivative and are left out.

The flip value of a probability: where in its range ([0, 1], or its interval) the
deciding bound crosses the threshold, searched from the figure's value towards the end
of the range the derivative points to (the bound taken to move one way along it): found
by regula falsi on further verifications, and stated with the bound's value there. A
`param double` declares no range, so it has none.
"""

from __future__ import annotations

import dataclasses
import math
import re
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass

from afsmc.api.errors import AfsmError
from afsmc.api.results import verify_file
from afsmc.diagnostics import CompileError
from afsmc.model import ir
from afsmc.sim.evidence import value_spans
from afsmc.verify.core.options import VerifyOptions
from afsmc.verify.outcome.results import PropertyResult

STEP = 1e-4  # the step, relative to the figure's value (its distance from 0 and 1 for a
# probability)
FLIP_RUNS = 10  # at most this many verifications to find a flip value, after its end's

Say = Callable[[str], None]


@dataclass(frozen=True)
class Figure:
    """A constant that a derivative can be taken by: its kind ("param", "probability",
    "interval probability"), nominal value and range (None: none declared)."""

    name: str
    kind: str
    value: float
    range: tuple[float, float] | None


@dataclass(frozen=True)
class Sensitivity:
    requirement: str
    bound: str  # the deciding bound: "min", "max" or "value"
    figure: Figure
    derivative: float | None  # None: not computed (`note` says why)
    step: float
    flip: float | None = None  # the figure's value where the verdict flips, in its range
    flip_bound: float | None = None  # the deciding bound there
    note: str = ""

    def to_json(self) -> dict[str, object]:
        return {"requirement": self.requirement, "bound": self.bound,
                "figure": self.figure.name, "kind": self.figure.kind,
                "value": self.figure.value, "derivative": self.derivative,
                "step": self.step, "flip": self.flip, "note": self.note}


def figures(model: ir.Model) -> list[Figure]:
    out = []
    for c in model.constants:
        if c.prob_interval is not None:
            lo, hi = c.prob_interval
            out.append(Figure(c.name, "interval probability", (lo + hi) / 2, (lo, hi)))
        elif c.declared_type == "prob" and not c.is_param:
            out.append(Figure(c.name, "probability", float(c.value), (0.0, 1.0)))
        elif c.is_param and c.type.value == "double":
            out.append(Figure(c.name, "param", float(c.value), None))
    return out


QUERY = re.compile(r'^(P|R\{"[^"]*"\})(min|max)?(<=|>=|<|>)\s*[^\s\[]+')


def as_query(formula: str) -> str:
    """A requirement's formula asked for its values: `P>=0.75 [ ... ]` -> `P=? [ ... ]`,
    so that verify takes its quickest exact route (a threshold makes it check sound, by
    iterating)."""
    return QUERY.sub(lambda m: f"{m.group(1)}{m.group(2) or ''}=?", formula, count=1)


class Runner:
    """Verifications of some requirements with one figure changed: a `param` through its
    --const, any other constant by its value in the file's text. Each requirement is
    asked as a formula of its own, `=?` for its threshold (`as_query`), and found again
    by its place among them."""

    def __init__(self, path: str, text: str, consts: Mapping[str, str],
                 requirements: Sequence[PropertyResult], options: VerifyOptions):
        self.path, self.text, self.consts = path, text, dict(consts)
        self.names = [p.name for p in requirements]
        self.formulas = [as_query(p.formula) for p in requirements]
        self.options = dataclasses.replace(options, precision=None, exact=False,
                                           strategy=False, witness=None, uniform=False)
        self.spans = value_spans(text, path)
        self.runs = 0

    def bounds(self, f: Figure, value: float) -> dict[str, PropertyResult]:
        text, consts = self.text, dict(self.consts)
        if f.kind == "param":
            consts[f.name] = repr(value)
        else:
            start, end = self.spans[f.name]
            text = text[:start] + repr(value) + text[end:]
        self.runs += 1
        res = verify_file(self.path, [], text=text, consts=consts, options=self.options,
                          formulas=self.formulas)
        return dict(zip(self.names, res.properties, strict=True))


def _bound(p: PropertyResult, which: str) -> float:
    v = getattr(p, which)
    return math.nan if v is None else float(v)


def _step(f: Figure) -> float:
    if f.range is not None:
        lo, hi = f.range
        room = min(f.value - lo, hi - f.value)
        if room <= 0:
            return 0.0
        return STEP * room
    return STEP * (abs(f.value) or 1.0)


def _missing(p: PropertyResult, which: str, value: float) -> float:
    """How far the bound is from meeting the threshold: > 0 where it misses it."""
    t = p.threshold
    assert t is not None
    return (t.bound - value) if t.op in (">=", ">") else (value - t.bound)


def _flip(run: Runner, f: Figure, p: PropertyResult, which: str, at: float, slope: float
          ) -> tuple[float | None, float | None, str]:
    """Where in its range the deciding bound crosses the threshold, and the bound there;
    None and why not. `at`: the bound at the figure's value, `slope`: its derivative. The
    search goes from the value towards the end of the range the derivative points to
    (towards the threshold), and finds the crossing by regula falsi (Illinois)."""
    if f.range is None:
        return None, None, "no range declared"
    t = p.threshold
    assert t is not None
    a, fa = f.value, _missing(p, which, at)
    towards = -slope if t.op in (">=", ">") else slope  # d(missing)/d(figure)
    if towards == 0 or fa == 0:
        return None, None, "the bound does not move towards the threshold"
    up = (towards > 0) == (fa < 0)
    b = f.range[1] if up else f.range[0]
    fb = _missing(p, which, _bound(run.bounds(f, b)[p.name], which))
    if math.isnan(fb) or (fa > 0) == (fb > 0):
        return None, None, (f"the verdict does not flip between {f.value:g} and {b:g}, the "
                            "end of its range the derivative points to")
    side = 0
    c, fc = a, fa
    for _ in range(FLIP_RUNS):
        c = (a * fb - b * fa) / (fb - fa)
        fc = _missing(p, which, _bound(run.bounds(f, c)[p.name], which))
        if abs(fc) <= 1e-9 or abs(b - a) <= 1e-9 * max(1.0, abs(c)):
            break
        if (fc > 0) == (fb > 0):
            b, fb = c, fc
            if side == -1:
                fa /= 2
            side = -1
        else:
            a, fa = c, fc
            if side == 1:
                fb /= 2
            side = 1
    bound = t.bound - fc if t.op in (">=", ">") else t.bound + fc
    return c, bound, ""


def sensitivities(path: str, text: str, model: ir.Model, consts: Mapping[str, str],
                  requirements: Sequence[PropertyResult], options: VerifyOptions,
                  say: Say | None = None) -> list[Sensitivity]:
    """Each requirement's sensitivity to each figure, most sensitive first per
    requirement (by the derivative's size)."""
    out: list[Sensitivity] = []
    reqs = [p for p in requirements if p.verdict is not None and p.verdict.decided_by]
    if not reqs:
        return out
    run = Runner(path, text, consts, reqs, options)
    for f in figures(model):
        h = _step(f)
        if say:
            say(f"sensitivity to {f.name}")
        try:
            if h == 0:
                raise ValueError("its value is at an end of its range")
            up, down = run.bounds(f, f.value + h), run.bounds(f, f.value - h)
        except (CompileError, AfsmError, ValueError) as exc:
            why = exc.diagnostics[0].message if isinstance(exc, CompileError) else str(exc)
            out += [Sensitivity(p.name, str(p.verdict.decided_by), f, None, h,  # type: ignore[union-attr]
                                note=f"not computed: {why}") for p in reqs]
            continue
        for p in reqs:
            which = str(p.verdict.decided_by)  # type: ignore[union-attr]
            hi, lo = _bound(up[p.name], which), _bound(down[p.name], which)
            d = (hi - lo) / (2 * h)
            try:
                flip, there, note = (None, None, "no derivative") if math.isnan(d) else \
                    _flip(run, f, p, which, (hi + lo) / 2, d)
            except (CompileError, AfsmError) as exc:
                flip, there, note = None, None, f"no flip searched: {exc.diagnostics[0].message}"
            out.append(Sensitivity(p.name, which, f, None if math.isnan(d) else d, h,
                                   flip, there, note))
    order = {p.name: i for i, p in enumerate(reqs)}
    return sorted(out, key=lambda s: (order[s.requirement], -abs(s.derivative or 0.0),
                                      s.figure.name))
