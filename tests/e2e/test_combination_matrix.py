"""The combination matrix (issue 44, point 6): every front-end, on every kind of mission,
with `--strategy`, `--witness 2`, a requirement, `--exact` and their pairs.

Each cell is one front-end (a row: `verify` as text, `--json` and `--junit`, `sweep` CSV
and JSON at one point (the mission's own value), `regions` over the mission's own box, the
Python API's `Results`, `to_pandas` and `_repr_html_` and `Sweep.to_pandas`, `diagram
--results/--strategy/--witness/--reach`, `simulate --strategy`) on one mission (a column:
tests/e2e/matrix/*.afsm, 41 to 152 states) with one set of options. Its id reads
`MISSION-ROW[-OPTION...]`, e.g. `interleaving-verify-json-strategy`. Each cell asserts:

- no internal error (exit code 3, a traceback: the cells run with AFSMC_TRACEBACK=1, so
  the exception itself fails the cell);
- no refusal the docs do not state: a refusal passes only if its code is in
  `DOCUMENTED_REFUSALS` for that row, mission and option, which names the doc section;
- the same bounds and verdict as `verify --json` for the same mission and options (the
  headline `min`/`max`, a DTMC's `value` as both, and `verdict`; see `Reference`): to
  1e-9 where the front-end gives full floats, to its digits where it rounds (a table's 6,
  a diagram's 4). `--strategy` and `--witness` only add to the output, so the reference
  leaves them out; a requirement and `--exact` change the values, so it has them. A
  front-end that shows a verdict-less view of a requirement fails; `regions` shows no
  bounds, only regions, whose verdict is read as `fe.regions_verdict` says;
- what `--strategy` and `--witness` add is there: a strategy table (or the turns), and
  paths or the reason there are none.

A cell that fails today is listed in `XFAIL` (strict), keyed by its id, with what breaks:
when a fix lands, the cell XPASSes and its entry goes.
"""

from __future__ import annotations

import json
import math
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import pytest

from tests.conftest import ROOT, run_cli
from tests.e2e.matrix import frontends as fe
from tests.e2e.matrix.frontends import HERE, Answer, Reference, Shown

pytestmark = pytest.mark.storm


# -- the columns: kinds of mission ---------------------------------------------------

@dataclass(frozen=True)
class Mission:
    """A small mission (tests/e2e/matrix/FILE, 41 to 152 states) and what the matrix asks
    of it. `requirement` is on `done` with a threshold that makes its verdict tell
    (`depends` where the bounds straddle it); `zero` is a requirement whose min is 0 (an
    until that cannot hold: the issue's `--witness` reproducers); `point` the one-point
    sweep at the mission's own value; `mode` the box whose `diagram --reach` is `done`;
    `box` the mission's interval probability for `regions`, if it has one."""

    file: str
    requirement: str
    zero: str
    point: str
    mode: str
    box: str | None = None

    @property
    def path(self) -> str:
        return str(HERE / self.file)


PATROL_ZERO = 'P>=0.5 [ "halted" U "done" ]'
PAIR_ZERO = 'P>=0.5 [ "lost" U "done" ]'
MISSIONS = {
    # min = max = 0.885759: holds
    "dtmc": Mission("dtmc.afsm", 'P>=0.8 [ F "done" ]', PATROL_ZERO, "CELLS=2:2", "Finished"),
    # MOVE_COST = [1, 2]: min 0.885759, max 0.913087, depends
    "intervals": Mission("intervals.afsm", 'P>=0.9 [ F "done" ]', PATROL_ZERO, "CELLS=2:2",
                         "Finished"),
    # P_FAULT = [0.005, 0.03]: 0.808 at the midpoint (holds there), 0.693 to 0.941 over
    # the box (depends): the wrong verdicts
    "iprob": Mission("iprob.afsm", 'P>=0.75 [ F "done" ]', PATROL_ZERO, "CELLS=2:2",
                     "Finished", "P_FAULT=0.005:0.03"),
    "both": Mission("both.afsm", 'P>=0.75 [ F "done" ]', PATROL_ZERO, "CELLS=2:2",
                    "Finished", "P_FAULT=0.005:0.03"),
    # who moves next is the only choice (no interval constant): min 0.961926, max 0.961985,
    # holds
    "interleaving": Mission("interleaving.afsm", 'P>=0.95 [ F "done" ]', PAIR_ZERO,
                            "JOBS=2:2", "Done"),
    # min 0.79546, max 0.961926: depends
    "timed-order": Mission("timed_order.afsm", 'P>=0.9 [ F "done" ]', PAIR_ZERO, "JOBS=2:2",
                           "Done"),
    "timed-nondet": Mission("timed_nondet.afsm", 'P>=0.9 [ F "done" ]', PAIR_ZERO,
                            "JOBS=2:2", "Done"),
    # MOVE_COST = [1, 2] from data "moves.csv": as `intervals`
    "data": Mission("data.afsm", 'P>=0.9 [ F "done" ]', PATROL_ZERO, "CELLS=2:2", "Finished"),
}


# -- the options ---------------------------------------------------------------------

# `req`: the mission's requirement (`-f`); `req0`: its requirement whose min is 0.
OPTION_SETS = ("", "strategy", "witness", "req", "exact", "strategy-witness", "strategy-req",
               "strategy-exact", "witness-req", "witness-exact", "req-exact", "req0",
               "witness-req0")
REQUIREMENT_SETS = tuple(o for o in OPTION_SETS if "req" in o)


def tokens(options: str) -> set[str]:
    return set(options.split("-")) - {""}


def selection(mission: Mission, options: str) -> list[str]:
    """The property asked: `done`, or the requirement as the one `--formula`."""
    opts = tokens(options)
    if "req" in opts:
        return ["-f", mission.requirement]
    if "req0" in opts:
        return ["-f", mission.zero]
    return ["-p", "done"]


def verify_argv(mission: Mission, options: str) -> list[str]:
    opts = tokens(options)
    return [mission.path, *selection(mission, options),
            *(["--strategy"] if "strategy" in opts else []),
            *(["--witness", "2"] if "witness" in opts else []),
            *(["--exact"] if "exact" in opts else [])]


def reference_options(options: str) -> str:
    """The options that change the values: a requirement, `--exact`."""
    return "-".join(o for o in options.split("-") if o in ("req", "req0", "exact"))


def api_options(mission: Mission, options: str) -> tuple[list[str], dict[str, Any]]:
    opts = tokens(options)
    argv = selection(mission, options)
    properties = [argv[1]] if argv[0] == "-p" else []
    kwargs: dict[str, Any] = {"formulas": [argv[1]]} if argv[0] == "-f" else {}
    kwargs |= {"strategy": True} if "strategy" in opts else {}
    kwargs |= {"witness": 2} if "witness" in opts else {}
    kwargs |= {"exact": True} if "exact" in opts else {}
    return properties, kwargs


# -- the rows: front-ends, and the options each takes ----------------------------------

ROWS: dict[str, tuple[str, ...]] = {
    "verify-text": OPTION_SETS,
    "verify-json": OPTION_SETS,
    "verify-junit": REQUIREMENT_SETS,
    "sweep-csv": ("", "req"),
    "sweep-json": ("", "req"),
    "api-sweep": ("", "req"),
    "regions": ("req",),  # missions with an interval probability: over its box
    "api": OPTION_SETS,
    "api-pandas": OPTION_SETS,
    "api-html": OPTION_SETS,
    "diagram-results": ("", "req"),
    "diagram-strategy": ("",),
    "diagram-witness": ("",),
    "diagram-reach": ("",),
    "simulate-strategy": ("",),
}
VERIFY_ROWS = ("verify-text", "verify-json", "verify-junit", "api", "api-pandas", "api-html")


def cell_id(mission: str, row: str, options: str) -> str:
    return "-".join(x for x in (mission, row, options) if x)


# -- refusals the docs state -----------------------------------------------------------

@dataclass(frozen=True)
class Refusal:
    """A refusal the docs state: in these rows and missions, with `option` (None: the row
    itself), the diagnostic `code`; `doc`'s section `section` says so in `quote`
    (checked by `test_the_documented_refusals_are_in_the_docs`)."""

    rows: tuple[str, ...]
    missions: tuple[str, ...]
    option: str | None
    code: str
    doc: str
    section: str
    quote: str


DOCUMENTED_REFUSALS = (
    # An interval probability is no interval constant: `iprob` is a DTMC too.
    Refusal(VERIFY_ROWS, ("dtmc", "iprob"), "strategy", "E415", "docs/verification.md",
            "Strategies and failure paths (--witness K)",
            "`--strategy` or `--witness-dir` on a "
            "model without choices (a machine without interval constants"),
    # docs/diagrams.md ("--strategy and --witness") sends `diagram --strategy` to `afsmc
    # verify --strategy`, whose refusal this is.
    Refusal(("diagram-strategy",), ("dtmc", "iprob"), None, "E415", "docs/verification.md",
            "Strategies and failure paths (--witness K)",
            "`--strategy` or `--witness-dir` on a "
            "model without choices (a machine without interval constants"),
    Refusal(("simulate-strategy",), ("dtmc", "iprob"), None, "E415", "docs/monte-carlo.md",
            "Following Storm's strategy",
            "A machine without interval constants (E415)"),
)


def documented(mission: str, row: str, options: str, code: str) -> bool:
    opts = tokens(options)
    return any(row in r.rows and mission in r.missions and r.code == code
               and (r.option is None or r.option in opts) for r in DOCUMENTED_REFUSALS)


# -- cells that fail today (issue 44) --------------------------------------------------

def known(reason: str, missions: tuple[str, ...], rows: tuple[str, ...],
          option_sets: tuple[str, ...]) -> dict[str, str]:
    """XFAIL entries: every cell of these missions, rows and option sets (a row that does
    not take an option set has no such cell) fails today for `reason`."""
    assert set(missions) <= set(MISSIONS) and set(rows) <= set(ROWS), (missions, rows)
    assert set(option_sets) <= set(OPTION_SETS), option_sets
    return {cell_id(m, r, o): reason for m in missions for r in rows for o in option_sets
            if o in ROWS[r] and (r != "regions" or MISSIONS[m].box is not None)}


SINGLE = ("dtmc", "intervals", "iprob", "both", "data")
COMPOSED = ("interleaving", "timed-order", "timed-nondet")
MDPS = ("intervals", "both", "data", "timed-order", "timed-nondet")  # interval constants
TABLES = ("verify-text", "verify-json", "api", "api-pandas", "api-html")
FLOATS = ("verify-json", "api", "api-pandas")  # full floats (the others round)
WITH_STRATEGY = tuple(o for o in OPTION_SETS if "strategy" in tokens(o))
WITH_WITNESS = tuple(o for o in OPTION_SETS if "witness" in tokens(o) and "strategy" not in tokens(o))

def table(*groups: dict[str, str]) -> dict[str, str]:
    """The groups of `known` as one table; a cell is in one group only."""
    out: dict[str, str] = {}
    for group in groups:
        assert not set(group) & set(out), sorted(set(group) & set(out))
        out |= group
    return out


XFAIL = table(
)


def cells() -> Iterator[Any]:
    for mission, m in MISSIONS.items():
        for row, option_sets in ROWS.items():
            if row == "regions" and m.box is None:
                continue
            for options in option_sets:
                cid = cell_id(mission, row, options)
                marks = ([pytest.mark.xfail(strict=True, reason=f"issue 44: {XFAIL[cid]}")]
                         if cid in XFAIL else [])
                yield pytest.param(mission, row, options, id=cid, marks=marks)


# -- the reference: verify --json, once per mission and options --------------------------

class References:
    """`verify --json` per (mission, value-changing options), computed once per module
    (and per xdist worker)."""

    def __init__(self) -> None:
        self.cache: dict[tuple[str, str], tuple[Answer, dict[str, Any] | None]] = {}

    def get(self, mission: str, options: str) -> tuple[Answer, dict[str, Any] | None]:
        key = (mission, reference_options(options))
        if key not in self.cache:
            self.cache[key] = fe.verify_json(verify_argv(MISSIONS[mission], key[1]))
        return self.cache[key]


@pytest.fixture(scope="module")
def references() -> References:
    return References()


@pytest.fixture(scope="module")
def api_cache() -> dict[tuple[str, str], Any]:
    return {}


@pytest.fixture(autouse=True)
def _tracebacks_in_the_output(monkeypatch: pytest.MonkeyPatch) -> None:
    # an internal error prints its traceback (instead of a file in /tmp), for the report
    monkeypatch.setenv("AFSMC_TRACEBACK", "1")


# -- comparing -------------------------------------------------------------------------

def close(shown: float | None, ref: float | None, digits: int | None) -> bool:
    if shown is None or ref is None:
        return shown is ref
    if math.isinf(ref) or math.isinf(shown):
        return shown == ref
    if digits is None:
        return abs(shown - ref) <= 1e-9
    # a value rounded to `digits` significant digits: within one unit of the last
    unit = 10 ** (math.floor(math.log10(abs(ref))) - digits + 1) if ref else 10.0 ** -digits
    return abs(shown - ref) <= unit


def settle(mission: str, row: str, options: str, answer: Answer, ref: Reference,
           names: list[str] | None = None) -> None:
    """The cell's verdict: a documented refusal, or the reference's bounds and verdicts."""
    if answer.code is not None:
        assert documented(mission, row, options, answer.code), (
            f"refused with {answer.code}, which the docs do not state here: {answer.message}")
        return
    assert not answer.notes, "; ".join(answer.notes)
    for name in names if names is not None else ref.names:
        assert name in answer.shown, f"{name} is not shown (shown: {sorted(answer.shown)})"
        got: Shown = answer.shown[name]
        lo, hi = ref.bounds(name)
        if got.lo is not None or got.hi is not None or row != "regions":
            assert close(got.lo, lo, got.digits), f"{name}: lower bound {got.lo}, verify --json {lo}"
            if got.hi is not None or row not in ("diagram-strategy", "simulate-strategy"):
                assert close(got.hi, hi, got.digits), (
                    f"{name}: upper bound {got.hi}, verify --json {hi}")
        verdict = ref.verdict(name)
        if verdict is not None:
            assert got.verdict == verdict, f"{name}: verdict {got.verdict}, verify --json {verdict}"


# -- the matrix ------------------------------------------------------------------------

@pytest.mark.parametrize(("mission", "row", "options"), list(cells()))
def test_cell(mission: str, row: str, options: str, references: References,
              api_cache: dict[tuple[str, str], Any], tmp_path: Path) -> None:
    m = MISSIONS[mission]
    refused, data = references.get(mission, options)
    if data is None:
        # verify --json itself refuses: the cell may refuse only as documented, and so
        # must the reference
        assert documented(mission, "verify-json", reference_options(options), refused.code or ""), (
            f"verify --json refused with {refused.code}: {refused.message}")
    ref = Reference(data or {"properties": []})
    argv = verify_argv(m, options)
    if row == "verify-text":
        answer = fe.verify_text(argv)
    elif row == "verify-json":
        answer, _ = fe.verify_json(argv)
    elif row == "verify-junit":
        answer = fe.verify_junit(argv, tmp_path)
    elif row in ("sweep-csv", "sweep-json"):
        sweep = [m.path, "--const", m.point, *selection(m, options)]
        answer = fe.sweep_csv(sweep) if row == "sweep-csv" else fe.sweep_json(sweep)
    elif row == "api-sweep":
        properties, kwargs = api_options(m, options)
        answer = fe.api_sweep(m.path, m.point, properties, kwargs)
    elif row == "regions":
        assert m.box is not None
        answer = fe.regions([m.path, "--param", m.box, "--require", m.requirement], "adhoc")
    elif row in ("api", "api-pandas", "api-html"):
        key = (mission, options)
        if key not in api_cache:
            properties, kwargs = api_options(m, options)
            api_cache[key] = fe.api(m.path, properties, kwargs)
        if row == "api":
            answer = fe.api_results(api_cache[key], api_options(m, options)[1])
        else:
            answer = (fe.api_pandas if row == "api-pandas" else fe.api_html)(api_cache[key])
    elif row == "diagram-results":
        results = tmp_path / "verify.json"
        results.write_text(json.dumps(data), encoding="utf-8")
        answer = fe.diagram_results([m.path], results, ref.names, tmp_path)
    elif row == "diagram-strategy":
        answer = fe.diagram_strategy([m.path], "done", tmp_path, midpoint=m.box is not None)
        if m.box is not None:
            # the strategy drawn is the midpoint model's (docs/verification.md, "What a
            # result means"): its value is verify's reference there, not the bound
            ref = fe.Reference(fe.at_midpoint(ref.data))
    elif row == "diagram-witness":
        answer, p = fe.diagram_witness([m.path], "done", tmp_path)
        top = ref.bounds("done")[1]
        if p is not None and top is not None:
            # one path into the target holds at most the max's probability
            assert 0 < p <= top + 1e-9, f"the path's probability {p}, the max {top}"
        settle(mission, row, options, answer, ref, names=[])
        return
    elif row == "diagram-reach":
        answer = fe.diagram_reach([m.path], m.mode, "done", tmp_path)
    elif row == "simulate-strategy":
        answer, (low, high) = fe.simulate_strategy([m.path], "done")
        if m.box is not None:
            # simulations follow the interval probabilities' midpoint (docs/verification.md,
            # "What a result means"): Storm's min there is verify's reference, not its bound
            ref = fe.Reference(fe.at_midpoint(ref.data))
        if answer.code is None:
            lo, hi = ref.bounds("done")
            assert low <= (hi or 0) + 1e-9 and high >= (lo or 0) - 1e-9, (
                f"the estimate's interval [{low}, {high}] misses [{lo}, {hi}]")
    else:
        raise AssertionError(row)
    settle(mission, row, options, answer, ref)


def test_the_documented_refusals_are_in_the_docs() -> None:
    """Each refusal the matrix accepts is stated in the docs, in the words quoted."""
    for r in DOCUMENTED_REFUSALS:
        text = " ".join((ROOT / r.doc).read_text(encoding="utf-8").split())
        assert r.quote in text, (r.doc, r.section, r.quote)


def test_every_xfail_names_a_cell() -> None:
    """An entry of XFAIL that names no cell (a typo, a cell renamed) would hide nothing."""
    ids = {p.id for p in cells()}
    assert set(XFAIL) <= ids, sorted(set(XFAIL) - ids)


def test_the_missions_are_small() -> None:
    """The matrix stays fast: every mission has at most a few hundred states."""
    for name, m in MISSIONS.items():
        r = run_cli("verify", m.path, "-p", "done", "--json", "--no-uniform")
        assert r.code == 0, (name, r.err)
        assert json.loads(r.out)["model"]["states"] <= 300, name
