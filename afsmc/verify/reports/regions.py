"""Parameter regions (`afsmc regions`): a box of parameter values split into sub-boxes
where a requirement holds for every value, fails for every value, or is not decided.

Each sub-box is analysed by parameter lifting (sound: it over-approximates the box): on
afsmc's explored model where the explorer takes the mission (`refine_lifted`: one lifted
backward pass a round, for all its boxes and both sides; afsmc.verify.lifting), else by
Storm's region checker,
which proves the requirement for every value of the box (holds), proves its negation for
every value (fails), or neither. Each proof keeps a margin (`margin`): the requirement is
proved with its threshold moved by the margin against it (`P>=b` as `P>=b+m`) and its
negation with the threshold moved the other way, so that a box whose values lie within the
engine's numerical error of the threshold (a value that does not depend on the parameters
and lies right at it) is left unknown rather than labelled by rounding. Neither: the box is halved along its widest side
(relative to the whole box) and its halves are checked in the next round, until the
decided volume reaches the coverage asked for (default 95%) or `max_rounds` rounds have
run. The boxes of one round are independent and
run on local processes or on a Dask cluster.

A requirement is `P>=0.6 [ F "success" ]` (also `>`, `<=`, `<`, `Pmin`, `Pmax`, `R{"r"}`).
On an MDP (integer intervals as floor/ceil choices) a bare `P>=b` must hold under every
choice: it holds where Pmin >= b and fails where Pmin < b (Pmax for `<=` and `<`).

The verdict over the whole box is `afsmc verify`'s, judged once by afsmc.verify.outcome.verdicts on
the requirement's bounds over the box (Storm's parametric engine, as verify bounds a
property over interval probabilities: docs/verification.md, "What a result means"); the
regions are the map of where it holds and fails.

With more than two parameters a plot shows a projection: `projection` gives, for each
cell of the two axes, the share of the volume over the other parameters that holds,
fails or is unknown.
"""

from __future__ import annotations

import bisect
import dataclasses
import itertools
import math
import multiprocessing
import os
import re
from collections.abc import Callable, Mapping, Sequence
from concurrent.futures import ProcessPoolExecutor
from dataclasses import dataclass, field
from typing import Any, Literal

from afsmc.diagnostics import CompileError, Diagnostic, Severity, codes
from afsmc.lifetime import die_with_parent
from afsmc.lower.lowering import Lowered
from afsmc.verify.core.uncertainty import LIFTING, PARAMETRIC
from afsmc.verify.engines.parametric import Parametric, Source, check_box, source, with_parameters
from afsmc.verify.lifting.model import Lifted, Query
from afsmc.verify.lifting.regions import Decider
from afsmc.verify.outcome.verdicts import Verdict
from afsmc.verify.plan.precision import PARAMETER_SOLVER_ERROR

Bounds = dict[str, tuple[float, float]]
_NEGATE = {">=": "<", ">": "<=", "<=": ">", "<": ">="}
_REQ = re.compile(r"\s*(P|R\{\"[^\"]*\"\}|R)(min|max)?\s*(<=|>=|<|>)\s*([0-9.eE+-]+)\s*(\[.*\])\s*$",
                  re.S)


@dataclass(frozen=True)
class Requirement:
    """A bounded property: its operator (P or R{...}), optimisation, comparison, bound
    and path, all as written."""

    op: str
    opt: str
    cmp: str
    bound: float
    path: str
    text: str

    def query(self) -> str:
        """The `=?` form, to be resolved as an ad-hoc afsm property."""
        return f"{self.op}{self.opt}=? {self.path}"


def parse_requirement(text: str) -> Requirement:
    m = _REQ.fullmatch(text)
    bound = None
    if m is not None:
        try:
            bound = float(m.group(4))
        except ValueError:
            bound = None
    if m is None or bound is None:
        raise CompileError([Diagnostic(
            codes.E442, Severity.ERROR, f"--require {text!r}: not a bounded property", None,
            hint="write e.g. 'P>=0.6 [ F \"success\" ]' or 'R{\"time\"}<=500 [ F \"done\" ]'")])
    return Requirement(m.group(1), m.group(2) or "", m.group(3), bound, m.group(5), text.strip())


def storm_formulas(req: Requirement, prism_query: str, mdp: bool) -> tuple[str, str]:
    """Storm's formulas of the requirement and of its negation, from the PRISM text of the
    requirement's `=?` query on the generated model. The region checker proves or refutes
    the first; the second says what "fails" means (for the tests and the docs)."""
    opt = req.opt or ("" if not mdp else "min" if req.cmp in (">=", ">") else "max")
    head = re.match(r"(P|R\{\"[^\"]*\"\})(min|max)?=\?", prism_query)
    assert head is not None
    rest = prism_query[head.end():]
    op = head.group(1)
    return (f"{op}{opt}{req.cmp}{req.bound!r}{rest}",
            f"{op}{opt}{_NEGATE[req.cmp]}{req.bound!r}{rest}")


@dataclass(frozen=True)
class Region:
    bounds: Bounds
    verdict: str  # "holds" | "fails" | "unknown"

    def volume(self, whole: Bounds) -> float:
        """Its share of the volume of `whole`."""
        return math.prod(_relative(side, whole[n]) for n, side in self.bounds.items())

    def to_json(self) -> dict[str, object]:
        return {"bounds": {n: [lo, hi] for n, (lo, hi) in self.bounds.items()},
                "verdict": self.verdict}


@dataclass
class RegionResult:
    requirement: str
    box: Bounds
    regions: list[Region]
    coverage: float  # the decided fraction of the box's volume
    target: float
    rounds: int
    seconds: float = 0.0
    states: int = 0
    feasible: dict[str, float] | None = None
    feasible_how: str = ""
    notes: list[str] = field(default_factory=list)
    # the dimensions not named with --param: the file's interval probabilities, each over
    # its own interval
    from_file: list[str] = field(default_factory=list)
    # the requirement's min and max over the whole box and their error, and the verdict
    # judged on them (afsmc.verify.outcome.verdicts.judge, as verify judges); None before they are
    # computed
    bounds: tuple[float, float, float] | None = None
    judged: Verdict | None = None
    # what a region's verdict means where it is not verify's word for its values (an MDP
    # with a bare requirement: the regions decide the worst choice only); "" where it is
    meaning: str = ""
    # what decided the regions and bounded the whole box, in words (LIFTING or PARAMETRIC)
    engine: str = PARAMETRIC

    def fraction(self, verdict: str) -> float:
        return sum(r.volume(self.box) for r in self.regions if r.verdict == verdict)

    def verdict(self) -> tuple[str, str]:
        """The verdict over the whole box, as `afsmc verify` judges it, and why; before the
        bounds are known, what the regions alone decide (holds or depends, else
        undecided)."""
        if self.judged is not None:
            return self.judged.kind, self.judged.reason
        has = {r.verdict for r in self.regions}
        if has == {"holds"}:
            return "holds", "it holds for every value of the box"
        if "holds" in has and "fails" in has:
            return "depends", "some values meet it, others do not"
        return "undecided", "the regions alone do not decide it"

    def to_json(self) -> dict[str, object]:
        verdict, reason = self.verdict()
        out: dict[str, object] = {
            "requirement": self.requirement,
            "box": {n: [lo, hi] for n, (lo, hi) in self.box.items()},
            "coverage": self.coverage, "target_coverage": self.target,
            "holds": self.fraction("holds"), "fails": self.fraction("fails"),
            "unknown": self.fraction("unknown"), "rounds": self.rounds,
            "states": self.states, "seconds": round(self.seconds, 3),
            "verdict": verdict, "reason": reason, "from_file": list(self.from_file),
            "region_meaning": self.meaning or None,
            "min": None if self.bounds is None else self.bounds[0],
            "max": None if self.bounds is None else self.bounds[1],
            "error": None if self.bounds is None else self.bounds[2],
            "decided_by": None if self.judged is None else self.judged.decided_by,
            "engine": "lifting" if self.engine == LIFTING else "parametric",
            "regions": [r.to_json() for r in self.regions]}
        if self.feasible is not None:
            out["feasible"] = self.feasible or None
            out["feasible_method"] = self.feasible_how or None
        return out


def split(b: Bounds, whole: Bounds) -> list[Bounds]:
    """Halve `b` along its widest side, measured relative to the whole box."""
    def rel(n: str) -> float:
        lo, hi = b[n]
        wlo, whi = whole[n]
        return (hi - lo) / (whi - wlo) if whi > wlo else 0.0

    n = max(sorted(b), key=rel)
    lo, hi = b[n]
    mid = (lo + hi) / 2
    return [dict(b) | {n: (lo, mid)}, dict(b) | {n: (mid, hi)}]


# ---- the work of one process: the model built once, boxes checked against it ----------

_WORKER: dict[str, Any] = {}


def _init(src: Source, formulas: tuple[str, str], parent: int | None = None) -> None:
    if parent is not None:
        die_with_parent(parent)
    _WORKER["built"] = Parametric(src, list(formulas))
    _WORKER["formulas"] = formulas


def _check(b: Bounds) -> str:
    """A box's label: holds if all of it meets the requirement with the margin against it,
    fails if none of it meets it with the margin for it (with_margin), else unknown."""
    built: Parametric = _WORKER["built"]
    tight, loose = _WORKER["formulas"]
    if built.analyze(tight, b) == "holds":
        return "holds"
    return "fails" if built.analyze(loose, b) == "fails" else "unknown"


def _check_on_dask(src: Source, formulas: tuple[str, str], boxes: list[Bounds]) -> list[str]:
    _init(src, formulas)
    return [_check(b) for b in boxes]


def margin(req: Requirement) -> float:
    """How far a region's values must lie from the threshold for the region to be labelled:
    the parametric engine's numerical error (its solver's precision), relative to the
    threshold for a reward beyond 1."""
    return PARAMETER_SOLVER_ERROR * max(1.0, abs(req.bound))


def with_margin(req: Requirement, prism_query: str, mdp: bool) -> tuple[str, str]:
    """The formulas a region is labelled by: the requirement with its threshold moved by
    `margin` against it (all of the box satisfies it: holds), and with its threshold moved
    by `margin` for it (none of the box satisfies it: fails)."""
    m = margin(req) if req.cmp in (">=", ">") else -margin(req)

    def at(bound: float) -> Requirement:  # a probability's threshold stays in [0, 1]
        return dataclasses.replace(req, bound=min(1.0, max(0.0, bound)) if req.op == "P"
                                   else bound)
    tight, loose = at(req.bound + m), at(req.bound - m)
    return (storm_formulas(tight, prism_query, mdp)[0], storm_formulas(loose, prism_query, mdp)[0])


def prepare(low: Lowered, params: Sequence[str], req: Requirement, prism_query: str,
            via: str, also: Sequence[str] = ()) -> tuple[Source, tuple[str, str], Parametric]:
    """The parametric model of `low` over `params`, built for the requirement with its
    margins (`with_margin`: the formulas returned) and the further formulas `also` (the
    bounds' queries, answered on the same build)."""
    plow = with_parameters(low, params)
    src = source(plow, via)
    formulas = with_margin(req, prism_query, low.kind == "mdp")
    return src, formulas, Parametric(src, [*formulas, *also])


def refine(low: Lowered, src: Source, formulas: tuple[str, str], built: Parametric,
           box: Bounds, *, coverage: float = 0.95, jobs: int = 1, dask: Any = None,
           max_rounds: int = 12, progress: Any = None) -> tuple[list[Region], int]:
    """The regions of `box`, refined round by round (see the module docstring)."""
    check_box(low, built, box)
    pool = None
    client = None
    if dask is not None:
        import distributed

        dd: Any = distributed  # untyped
        client = dask if isinstance(dask, dd.Client) else dd.Client(dask)
    elif jobs > 1:
        ctx = multiprocessing.get_context("spawn")  # safe even if the caller has threads
        pool = ProcessPoolExecutor(jobs, mp_context=ctx, initializer=_init,
                                   initargs=(src, formulas, os.getpid()))
    say = None if progress is None else (
        lambda rounds, todo, decided: progress(f"round {rounds}: {len(todo)} boxes checked, "
                                               f"{decided:.1%} of the volume decided"))
    try:
        return _rounds(box, lambda todo: _round(todo, src, formulas, built, pool, client, jobs),
                       coverage, max_rounds, say)
    finally:
        if pool is not None:
            pool.shutdown(cancel_futures=True)
        if client is not None and client is not dask:
            client.close()


Said = Callable[[int, list[Bounds], float], None]  # a round's progress line


def _rounds(box: Bounds, decide: Callable[[list[Bounds]], list[str]], coverage: float,
            max_rounds: int, say: Said | None) -> tuple[list[Region], int]:
    """The rounds of both routes: each decides the boxes left, the decided ones are kept,
    and the undecided ones are split in two for the next round, until `coverage` of the
    volume is decided, nothing is left, or `max_rounds`; the regions and the rounds."""
    done: list[Region] = []
    todo: list[Bounds] = [dict(box)]
    rounds = 0
    while todo and rounds < max_rounds:
        rounds += 1
        verdicts = decide(todo)
        unknown = [b for b, v in zip(todo, verdicts, strict=True) if v == "unknown"]
        done += [Region(b, v) for b, v in zip(todo, verdicts, strict=True) if v != "unknown"]
        decided = sum(r.volume(box) for r in done)
        if say is not None:
            say(rounds, todo, decided)
        if decided >= coverage or not unknown:
            return done + [Region(b, "unknown") for b in unknown], rounds
        todo = [h for b in unknown for h in split(b, box)]
    return done + [Region(b, "unknown") for b in todo], rounds


def _round(todo: list[Bounds], src: Source, formulas: tuple[str, str], built: Parametric,
           pool: ProcessPoolExecutor | None, client: Any, jobs: int) -> list[str]:
    if client is not None:
        n = max(1, len(todo) // max(1, 4 * jobs))
        chunks = [todo[i:i + n] for i in range(0, len(todo), n)]
        futures = client.map(_check_on_dask, [src] * len(chunks), [formulas] * len(chunks),
                             chunks, pure=False)
        return [v for part in client.gather(futures) for v in part]
    if pool is not None and len(todo) > 1:
        return list(pool.map(_check, todo))
    _WORKER["built"], _WORKER["formulas"] = built, formulas
    return [_check(b) for b in todo]


# ---- the same rounds by parameter lifting on afsmc's explorer ---------------------------


def lifted_query(req: Requirement, q: Query, mdp: bool) -> Query:
    """The query a region is decided by: the requirement's side ("min" for >= and >),
    under the scheduler it names (on an MDP, a bare requirement under every choice: the
    min for >= and >, the max for <= and <)."""
    lower = req.cmp in (">=", ">")
    sched: Literal["min", "max", ""] = (
        "" if not mdp else "min" if req.opt == "min" or (not req.opt and lower) else "max")
    return dataclasses.replace(q, end="min" if lower else "max", sched=sched)


def refine_lifted(lifted: Lifted, q: Query, req: Requirement, box: Bounds, *,
                  coverage: float = 0.95, max_rounds: int = 12, progress: Any = None
                  ) -> tuple[list[Region], int]:
    """The regions of `box` as `refine` makes them, each sub-box decided on afsmc's
    explored model (afsmc.verify.lifting.regions.Decider: exact values at two corners
    where the value is proven monotone over the box or one containing it, else the
    box's lifted bounds, with the same margin)."""
    decider = Decider(lifted, q, req.cmp, req.bound, margin(req))
    say = None if progress is None else (
        lambda rounds, todo, decided: progress(
            f"round {rounds}: {len(todo)} box{'es' if len(todo) > 1 else ''} checked "
            f"({decider.summary()}), {decided:.1%} of the volume decided"))
    return _rounds(box, decider.decide, coverage, max_rounds, say)


def point_bounds(values: Mapping[str, float]) -> Bounds:
    return {n: (v, v) for n, v in values.items()}


# ---- the projection a plot draws ------------------------------------------------------


@dataclass(frozen=True)
class Cell:
    """One cell of the grid of two axes (or one: `y` is None) that the regions' edges
    draw: the share of its volume over the other parameters where the requirement holds,
    fails or is unknown (the three add up to 1)."""

    x: tuple[float, float]
    y: tuple[float, float] | None
    share: dict[str, float]


def _relative(side: tuple[float, float], whole: tuple[float, float]) -> float:
    """A side's length relative to the whole box's side (1 where the box has no width)."""
    (lo, hi), (wlo, whi) = side, whole
    return (hi - lo) / (whi - wlo) if whi > wlo else 1.0


def _cells(edges: set[float]) -> list[tuple[float, float]]:
    """The intervals between consecutive edges; one point if the axis has no width."""
    e = sorted(edges)
    return [(e[0], e[0])] if len(e) == 1 else list(itertools.pairwise(e))


def _covered(cells: list[tuple[float, float]], lo: float, hi: float) -> range:
    """The indices of the cells inside [lo, hi] (each region's edges are cell edges)."""
    if len(cells) == 1:
        return range(1)
    starts = [c[0] for c in cells]
    return range(bisect.bisect_left(starts, lo), bisect.bisect_left(starts, hi))


def projection(res: RegionResult, axes: Sequence[str]) -> list[Cell]:
    """The regions projected onto `axes`: the grid of the regions' edges along the axes,
    each cell with the share of the volume over the other parameters that holds, fails
    or is unknown. Over two parameters (or one) every share is 0 or 1: the regions
    themselves."""
    x, y = axes[0], (axes[1] if len(axes) > 1 else None)
    others = [n for n in res.box if n not in axes]
    xs = _cells({e for r in res.regions for e in r.bounds[x]})
    ys = _cells({e for r in res.regions for e in r.bounds[y]}) if y is not None else [(0.0, 0.0)]
    shares = [[dict.fromkeys(("holds", "fails", "unknown"), 0.0) for _ in ys] for _ in xs]
    for r in res.regions:
        rest = math.prod(_relative(r.bounds[n], res.box[n]) for n in others)
        for i in _covered(xs, *r.bounds[x]):
            for j in (_covered(ys, *r.bounds[y]) if y is not None else range(1)):
                shares[i][j][r.verdict] += rest
    return [Cell(xs[i], ys[j] if y is not None else None, shares[i][j])
            for i in range(len(xs)) for j in range(len(ys))]
