"""What `afsmc report` puts in an assurance case, gathered once: the mission as written,
ONE verification (`afsmc.verify.run`, with the strategies where something is chosen),
each reachability property split by cause, the figures' sources, and what it takes to
reproduce it. The renderers (afsmc.report.html, afsmc.report.markdown) only show this;
nothing here or there judges a verdict again.
"""

from __future__ import annotations

import dataclasses
import hashlib
import os
import platform
import re
import shlex
from collections.abc import Callable, Mapping, Sequence
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass, field

from afsmc import __version__
from afsmc.api.diagram import render, span_text
from afsmc.api.results import verify_file
from afsmc.api.sim_check import sim_check_file
from afsmc.backends.dot import Overlay
from afsmc.backends.dot import diagram as dot_diagram
from afsmc.check.sim_sources import INTERVAL, policy_of
from afsmc.compiler import load as load_checked
from afsmc.diagnostics import CompileError
from afsmc.lower.symmetry import decide
from afsmc.model import ir
from afsmc.report.baseline import Comparison, compare
from afsmc.report.causes import Split, split_all, splittable, why_not
from afsmc.report.sensitivity import Sensitivity, sensitivities
from afsmc.sim.evidence import Evidence
from afsmc.verify.core.api import load_with_formulas, select, sound_mode
from afsmc.verify.core.options import VerifyOptions
from afsmc.verify.engines.guard import IN_PROCESS_STATES, default_max_states, mem_available
from afsmc.verify.outcome.results import PropertyResult, VerifyResult
from afsmc.verify.outcome.strategy import StrategyEntry, has_choices

Say = Callable[[str], None]
PATHS = 3  # the most probable paths shown into each failure property's largest cause
# the shares of the free memory the verification and the causes, which run side by
# side, may take (verify alone takes 70%: afsmc.verify.engines.jobs)
VERIFY_SHARE, CAUSES_SHARE = 0.45, 0.3
# how far below guard.IN_PROCESS_STATES the verified model must be for the sensitivities'
# runs (the model with one figure moved, a little larger or smaller) to stay in process
SMALL_MARGIN = 4


@dataclass(frozen=True)
class Figure:
    """A constant whose value comes from a simulation or a data file: as declared, its
    source, the confidence its check uses, and a fresh check's evidence (None: not
    re-checked)."""

    name: str
    declared: str
    source: str
    confidence: str
    evidence: Evidence | None = None


@dataclass(frozen=True)
class Case:
    path: str
    machine: str
    description: str
    constants: dict[str, object]
    modes: list[ir.Mode]
    agents: list[str]
    result: VerifyResult
    svg: str  # the diagram with the results drawn in ("" and `svg_note` if it cannot be)
    svg_note: str
    causes: dict[str, list[Split]] | None  # None: not asked for
    figures: list[Figure]
    rechecked: int  # the runs of the fresh sim-check; 0: not re-checked
    reproduce: list[tuple[str, str]]
    command: str
    generated: str  # the one line that differs between two reports of the same input
    baseline: Comparison | None = None
    notes: list[str] = field(default_factory=list)
    sensitivity: list[Sensitivity] | None = None  # None: not asked for
    worst_case: bool = True  # the strategies were asked for
    # the min and max strategies of each property (verify --strategy), by name
    strategies: dict[str, dict[str, list[StrategyEntry]]] = field(default_factory=dict)

    def property(self, name: str) -> PropertyResult:
        return self.result.property(name)


def command(path: str, consts: Mapping[str, str], properties: Sequence[str] = (),
            formulas: Sequence[str] = (), engine: str = "auto") -> str:
    """The `afsmc report` command that makes the same numbers, argument files expanded."""
    words = ["afsmc", "report", path, *[f"--const={k}={v}" for k, v in consts.items()],
             *[f"--property={n}" for n in properties], *[f"--formula={f}" for f in formulas]]
    if engine != "auto":
        words.append(f"--engine={engine}")
    return shlex.join(words)


def description(text: str) -> str:
    """The comment above `machine NAME;`: the mission in its author's words."""
    lines = []
    for line in text.splitlines():
        s = line.strip()
        if s.startswith("machine ") or (s and not s.startswith("//")):
            break
        lines.append(s[2:].strip() if s.startswith("//") else "")
    return "\n".join(lines).strip()


def _digest(path: str) -> str:
    h = hashlib.sha256()
    with open(path, "rb") as f:
        for block in iter(lambda: f.read(1 << 20), b""):
            h.update(block)
    return h.hexdigest()


def data_files(model: ir.Model, path: str) -> list[str]:
    """The data files of `from data` constants, as paths from the current directory."""
    base = os.path.dirname(path)
    return sorted({os.path.join(base, c.source.ref) for c in model.constants
                   if c.source is not None and c.source.column is not None})


def _storm_version() -> str:
    try:
        import stormpy.info

        return f"Storm {stormpy.info.storm_version()} (stormpy {stormpy.__version__})"
    except ImportError:
        return "not installed"


def reproduce(path: str, model: ir.Model, res: VerifyResult) -> list[tuple[str, str]]:
    """afsmc's, Storm's and Python's versions, the files' hashes, the model's size and
    the engine: what another run needs to be the same."""
    m = res.model
    rows = [("afsmc", __version__), ("Storm", _storm_version()),
            ("Python", platform.python_version())]
    if os.path.isfile(path):
        rows.append((f"sha256 {path}", _digest(path)))
    for d in data_files(model, path):
        rows.append((f"sha256 {d}", _digest(d) if os.path.isfile(d) else "missing"))
    rows.append(("model", f"{m.type.upper()}, {m.states:,} states, {m.transitions:,} "
                 f"transitions, {m.choices:,} choices"))
    if res.uniform_model is not None:
        u = res.uniform_model
        rows.append(("uniform model", f"DTMC, {u.states:,} states, {u.transitions:,} "
                     "transitions"))
    rows.append(("engine", f"{m.engine} (--engine {res.engine}, via {res.via})"
                 + (f", solver {m.solver}" if m.solver else "")))
    if res.constants:
        rows.append(("constants", ", ".join(f"{k}={v}" for k, v in res.constants.items())))
    return rows


def figures(model: ir.Model, evidence: Sequence[Evidence] = ()) -> list[Figure]:
    by_name = {e.name: e for e in evidence}
    out = []
    for c in model.constants:
        if c.source is None:
            continue
        declared = (f"[{c.interval[0]}, {c.interval[1]}]" if c.interval is not None
                    and c.interval[0] != c.interval[1] else str(c.value))
        stated = dict(c.source.policy)
        policy = policy_of(c)
        conf = f"{policy.confidence:g}" + ("" if "confidence" in stated else " (the default)")
        if policy.shape == INTERVAL:
            conf += f"; coverage {policy.coverage:g}"
        out.append(Figure(c.name, declared, ("sim " if c.source.column is None else "")
                          + c.source.display, conf, by_name.get(c.name)))
    return out


def overlay(res: VerifyResult) -> Overlay:
    """The verification's numbers drawn in the diagram: one line per property."""
    notes = []
    for p in res.properties:
        text = span_text(p.min, p.max) if p.value is None else span_text(p.value, p.value)
        notes.append(f"{p.name}: {text}" + (f": {p.verdict.kind}" if p.verdict else ""))
    return Overlay(notes=notes)


def drawn(model: ir.Model, res: VerifyResult) -> tuple[str, str]:
    """The diagram as inline SVG (no XML prolog), or "" and why not."""
    try:
        data = render(dot_diagram(model, overlay(res)), "svg").decode("utf-8")
    except CompileError as exc:
        return "", exc.diagnostics[0].message
    start = data.find("<svg")
    svg = data[start:] if start >= 0 else data
    # Graphviz's comments name its version and the graph: nothing a reader needs
    return re.sub(r"<!--.*?-->\n?", "", svg, flags=re.S), ""


def causes_of(model: ir.Model, checked_names: set[str], say: Say,
              max_bytes: int | None = None, max_states: int | None = None
              ) -> tuple[dict[str, list[Split]], list[str]]:
    """The causes of every failure property among those verified (`checked_names`, for
    the report's "How it fails"), and why the other reachability properties are not
    there. `max_bytes`, `max_states`: the memory and states their model may take
    (afsmc.report.causes)."""
    notes = []
    wanted = []
    for prop in model.properties:
        if not splittable(prop) or prop.name not in checked_names:
            continue
        reason = why_not(model, prop)
        if reason is not None:
            notes.append(reason)
        else:
            wanted.append(prop)
    if not wanted:
        return {}, notes
    say("causes of " + ", ".join(p.name for p in wanted))
    try:
        splits = split_all(model, wanted, paths=PATHS, max_bytes=max_bytes,
                           max_states=max_states)
    except CompileError as exc:
        return {}, [*notes, exc.diagnostics[0].message]
    out: dict[str, list[Split]] = {}
    for prop in wanted:
        if failure(prop, splits[prop.name]):
            out[prop.name] = splits[prop.name]
        else:
            notes.append(f"{prop.name} is no failure property: no hazard leads into its "
                         "target, and it is no upper bound (P<=, P<)")
    return out, notes


def failure(prop: ir.Property, splits: Sequence[Split]) -> bool:
    """A failure property: a hazard leads into its target (with a positive probability),
    or it is a requirement that bounds the probability from above (`P<=`, `P<`)."""
    upper = prop.threshold is not None and prop.threshold.op in ("<=", "<")
    return upper or any(c.kind == "hazard" for s in splits for c in s.causes)


def build(path: str, consts: Mapping[str, str] | None = None, *,
          options: VerifyOptions | None = None, properties: Sequence[str] = (),
          recheck: int = 0, command: str = "", generated: str = "",
          baseline: Mapping[str, object] | None = None, baseline_name: str = "",
          tolerance: float = 0.0, formulas: Sequence[str] = (), text: str | None = None,
          sensitivity: bool = True, worst_case: bool = True, causes: bool = True,
          progress: Say | None = None) -> Case:
    """Gather the report of the .afsm file at `path`: one verification with `options`
    (strategies added where the mission has choices, unless not `worst_case`), the
    causes (unless not `causes`), the sensitivities (unless not `sensitivity`), the
    figures (re-checked with `recheck` runs each, 0: not), a comparison with `baseline`
    (an earlier `afsmc verify --json` object). Raises CompileError."""
    say = progress or (lambda line: None)
    consts = dict(consts or {})
    checked = load_checked(path, consts, text=text)
    model = checked.model
    opts = options or VerifyOptions(engine="auto")
    # the ad-hoc formulas among the properties, named as verify names them
    full = load_with_formulas(path, consts, formulas, checked=checked)
    plays = worst_case and has_choices(model) and not opts.bisimulation
    if plays:  # the strategies' table names the agents: the same model for the values
        opts = dataclasses.replace(opts, reductions=decide(
            opts.reductions, "the report's strategies name the agents, which the "
            "reduction's canonical order would turn into slots (--symmetry forces it)"))
    # verify's schedulers come beside the values in one run, except in sound mode (a
    # requirement), where verify's values are checked without them (afsmc.verify.core
    # .conditioning): there the strategies come from a run of their own
    sound = not opts.exact and sound_mode(select(full.model, properties, full.adhoc),
                                          opts.precision, opts.exact, opts.engine)[0] is not None
    # the causes come from a model of their own (afsmc.report.causes), so they are split
    # while the verification runs (in its own process, when the model may be large),
    # each with a share of the free memory
    names = {p.name for p in select(full.model, properties, full.adhoc)}
    pool = ThreadPoolExecutor(1) if causes else None
    free = mem_available()
    if pool is not None and free is not None and opts.memory_budget is None:
        opts = dataclasses.replace(opts, memory_budget=int(free * VERIFY_SHARE))
    # their states limited as verify's are (--max-states, else what the free memory
    # holds), so that a model verify refuses as too large is not explored here for long
    split_later = pool.submit(causes_of, full.model, names, say,
                              None if free is None else int(free * CAUSES_SHARE),
                              opts.max_states or default_max_states()) if pool else None
    say("verifying")
    try:
        res = verify_file(path, list(properties), text=text, consts=consts, checked=checked,
                          options=dataclasses.replace(opts, strategy=plays and not sound),
                          formulas=list(formulas), progress=progress).raw
    finally:
        if pool is not None:
            pool.shutdown(wait=True)
    plans = res
    if plays and sound:
        say("the strategies")
        plans = verify_file(path, list(properties), text=text, consts=consts,
                            checked=checked, options=dataclasses.replace(opts, strategy=True),
                            formulas=list(formulas)).raw
    strategies = {p.name: p.strategy for p in plans.properties if p.strategy is not None}
    svg, svg_note = drawn(model, res)
    split, notes = split_later.result() if split_later is not None else (None, [])
    evidence: list[Evidence] = []
    if recheck:
        say(f"sim-check, {recheck:,} runs per constant")
        evidence = sim_check_file(path, consts, text, runs=recheck).evidence
    comparison = None
    if baseline is not None:
        comparison = compare(baseline, res.to_json(), tolerance, baseline_name)
    slopes = None
    if sensitivity:
        # dozens of verifications of the model with one figure moved within its range:
        # where the model verified is far below the size that needs a watched child
        # (guard.IN_PROCESS_STATES), they run in this process, without a fresh
        # interpreter's start (about a second each) per run
        small = res.model.states * SMALL_MARGIN <= IN_PROCESS_STATES
        slopes = sensitivities(path, checked.model.source.text, model, consts,
                               [p for p in res.properties if p.threshold is not None],
                               dataclasses.replace(opts, isolate=False) if small else opts,
                               say)
    agents = [a.name for a in model.composition.agents] if model.composition else []
    return Case(path, model.name, description(checked.model.source.text),
                dict(res.constants), list(model.modes), agents, res, svg, svg_note, split,
                figures(model, evidence), recheck, reproduce(path, model, res), command,
                generated, comparison, notes, slopes, worst_case, strategies)
