"""`sim-check`: re-run the simulation behind each `from sim ...` constant and judge
whether the number in the spec still agrees with it (rules in docs/monte-carlo.md).

Also rewrites drifted constants in the source text, touching only the value and the
`// sim-check: ...` provenance comment at the end of the constant's line.
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass
from typing import Any

import numpy as np
import numpy.typing as npt

from afsmc.check.sim_sources import INTERVAL, NUMBER, PROB_INTERVAL, PROBABILITY, policy_of
from afsmc.model import ir
from afsmc.sim import stats
from afsmc.simlib import registry
from afsmc.syntax import ast
from afsmc.syntax.parser import parse
from afsmc.text import short


@dataclass(frozen=True)
class Evidence:
    name: str
    ref: str
    kind: str  # the simulator output's kind
    shape: str  # interval | number | probability
    declared: str  # as the spec states it, e.g. "[12, 13]"
    runs: int  # simulator runs, or a data file's values
    seed: int | None  # None: a data file's values
    mean: float
    mean_low: float  # confidence interval of the mean (Clopper-Pearson for probabilities)
    mean_high: float
    cdf_lo: float | None  # empirical CDF at the declared floor / ceiling (intervals)
    cdf_hi: float | None
    hull: tuple[int, int] | None  # integer hull of the central `coverage` of the samples
    accept: str  # what the rule accepts, e.g. "lo in [11, 12], hi in [13, 13]"
    consistent: bool
    suggestion: str  # the value --update writes
    confidence: float
    coverage: float | None
    fits: bool = True  # the rule accepts `suggestion` (an int rule's range may hold no integer)
    # Consistent, but with too few runs to bound what the rule accepts (a quantile's
    # interval reaches infinity): nothing could have been rejected there, so not called so.
    inconclusive: bool = False
    # the confidence interval's method, for the probabilities (Clopper-Pearson)
    method: str | None = None

    @property
    def verdict(self) -> str:
        return "inconclusive" if self.inconclusive else \
            "consistent" if self.consistent else "drifted"

    def to_json(self) -> dict[str, object]:
        return {
            "name": self.name, "ref": self.ref, "kind": self.kind, "shape": self.shape,
            "declared": self.declared, "runs": self.runs, "seed": self.seed,
            "mean": self.mean, "mean_low": self.mean_low, "mean_high": self.mean_high,
            "cdf_lo": self.cdf_lo, "cdf_hi": self.cdf_hi,
            "hull": list(self.hull) if self.hull else None, "accept": self.accept,
            "verdict": self.verdict,
            "suggestion": self.suggestion if self.fits else None,
            "confidence": self.confidence, "coverage": self.coverage,
            "method": self.method,
        }


def judge(const: ir.Constant, runs: int, seed: int,
          samples: npt.NDArray[Any] | None = None, confidence: float | None = None,
          kind: str | None = None) -> Evidence:
    """Apply the rule for the constant's shape to `samples` of its simulator output (by
    default sampled here: `registry.sample(ref, runs, seed)`). `confidence` replaces the
    default confidence of a constant that states none; `kind` is the output's kind (by
    default the registry's)."""
    assert const.source is not None
    ref = const.source.ref
    pol = policy_of(const, confidence)
    kind = registry.kind(ref) if kind is None else kind
    x = np.asarray(registry.sample(ref, runs, seed) if samples is None else samples,
                   dtype=np.float64)
    n = len(x)
    mean = float(np.mean(x))
    conf = pol.confidence
    if pol.shape == PROB_INTERVAL:
        return _prob_interval(const, ref, kind, x, runs, seed, conf)
    if pol.shape == PROBABILITY:
        k = int(np.count_nonzero(x))
        low, high = stats.clopper_pearson(k, n, conf)
        p = float(const.value)
        return Evidence(const.name, ref, kind, pol.shape, short(p, 6), runs, seed, mean, low, high,
                        None, None, None,
                        f"p in [{short(low, 6)}, {short(high, 6)}] (Clopper-Pearson)",
                        low <= p <= high, stats.shortest_decimal(mean, low, high), conf, None,
                        method=stats.CLOPPER_PEARSON)
    low, high = stats.mean_interval(x, conf)
    if pol.shape == NUMBER:
        is_int = const.type.value == "int"
        tol = pol.tolerance if pol.tolerance is not None else (0.5 if is_int else 0.01 * abs(mean))
        v = float(const.value)
        ok = low - tol <= v <= high + tol
        fits = True
        if is_int:
            # the accepted integer nearest the mean; a small tolerance may admit none
            first, last = math.ceil(low - tol), math.floor(high + tol)
            fits = first <= last
            sugg = str(min(max(round(mean), first), last) if fits else round(mean))
        else:
            sugg = stats.shortest_decimal(mean, low, high)
        return Evidence(const.name, ref, kind, pol.shape, short(v, 6), runs, seed, mean, low, high,
                        None, None, None,
                        f"value in [{short(low - tol, 6)}, {short(high + tol, 6)}] "
                        f"(mean interval +- tolerance {short(tol, 6)})", ok, sugg, conf, None, fits)
    assert pol.shape == INTERVAL and const.interval is not None
    lo, hi = const.interval
    c = pol.coverage
    xs = np.sort(x)
    q_lo, q_hi = (1 - c) / 2, (1 + c) / 2
    a_lo, b_lo = stats.quantile_interval(xs, q_lo, conf)
    a_hi, b_hi = stats.quantile_interval(xs, q_hi, conf)
    hull = (math.floor(float(np.quantile(xs, q_lo))), math.ceil(float(np.quantile(xs, q_hi))))
    # (an unbounded end stays unbounded: too few runs to bound that quantile)
    lo_ok = tuple(math.floor(v) if math.isfinite(v) else v for v in (a_lo, b_lo))
    hi_ok = tuple(math.ceil(v) if math.isfinite(v) else v for v in (a_hi, b_hi))
    def accepted(a: float, b: float) -> bool:
        return lo_ok[0] <= a <= lo_ok[1] and hi_ok[0] <= b <= hi_ok[1]
    ok = accepted(lo, hi)
    accept = (f"floor in [{lo_ok[0]}, {lo_ok[1]}], ceil in [{hi_ok[0]}, {hi_ok[1]}] "
              f"(hull of the central {short(c * 100, 6)}% at confidence {short(conf, 6)})")
    cdf_lo = float(np.searchsorted(xs, lo, side="right")) / n
    cdf_hi = float(np.searchsorted(xs, hi, side="right")) / n
    return Evidence(const.name, ref, kind, pol.shape, f"[{lo}, {hi}]", runs, seed, mean, low,
                    high, cdf_lo, cdf_hi, hull, accept, ok, f"[{hull[0]}, {hull[1]}]", conf, c,
                    accepted(*hull),
                    inconclusive=ok and not all(math.isfinite(v) for v in (*lo_ok, *hi_ok)))


def _prob_interval(const: ir.Constant, ref: str, kind: str, x: npt.NDArray[np.float64],
                   runs: int, seed: int, conf: float) -> Evidence:
    """An interval probability [lo, hi] is consistent when it covers the simulation's
    Clopper-Pearson interval at `conf`: every p the runs leave plausible is in the box that
    verify bounds over. --update writes that interval, rounded outwards."""
    assert const.prob_interval is not None
    lo, hi = (float(v) for v in const.prob_interval)
    n = len(x)
    k = int(np.count_nonzero(x))
    low, high = stats.clopper_pearson(k, n, conf)
    a, b = stats.outward_decimals(low, high)
    return Evidence(const.name, ref, kind, PROB_INTERVAL, f"[{short(lo, 6)}, {short(hi, 6)}]",
                    runs, seed, k / n if n else math.nan, low, high, None, None, None,
                    f"[lo, hi] covering [{short(low, 6)}, {short(high, 6)}] "
                    f"({k} of {n}: Clopper-Pearson at {short(conf, 6)})",
                    lo <= low and high <= hi, f"[{a}, {b}]", conf, None,
                    method=stats.CLOPPER_PEARSON)


# ---- rewriting the file ------------------------------------------------------------

_PROVENANCE = re.compile(r"[ \t]*// sim-check:[^\r\n]*$")


def value_spans(text: str, path: str) -> dict[str, tuple[int, int]]:
    """Constant name -> (start, end) offsets of its value as written (re-parsed)."""
    module = parse(text, path)
    out: dict[str, tuple[int, int]] = {}
    for d in module.decls:
        if isinstance(d, ast.ConstDecl):
            out[d.name.text] = (d.value.span.start, d.value.span.end)
            out[d.name.text + "\0decl"] = (d.span.start, d.span.end)
    return out


def rewrite(text: str, path: str, changes: dict[str, tuple[str, str]]) -> str:
    """Replace the values of `changes` (name -> (new value text, provenance)) in `text`.

    Every other byte stays as it was; the provenance becomes (or replaces) a
    `// sim-check: ...` comment at the end of the line on which the declaration ends."""
    spans = value_spans(text, path)
    edits: list[tuple[int, int, str]] = []
    # One comment per line: declarations that share a line share it (an edit per declaration
    # of the same old comment would overlap, and cut into the next line).
    lines: dict[int, tuple[int, list[str]]] = {}  # end of line -> (last decl end, notes)
    for name, (value, note) in changes.items():
        start, end = spans[name]
        edits.append((start, end, value))
        decl_end = spans[name + "\0decl"][1]
        eol = len(text)
        for stop in ("\n", "\r"):
            i = text.find(stop, decl_end)
            if i != -1:
                eol = min(eol, i)
        last, notes = lines.get(eol, (decl_end, []))
        lines[eol] = (max(last, decl_end), [*notes, note])
    for eol, (last, notes) in lines.items():
        m = _PROVENANCE.search(text[last:eol])
        comment = f" // sim-check: {'; '.join(notes)}"
        edits.append((last + m.start(), eol, comment) if m else (eol, eol, comment))
    out = text
    for start, end, new in sorted(edits, reverse=True):
        out = out[:start] + new + out[end:]
    return out
