"""`Diagram`: the mission diagram (`afsmc diagram`) as an object that shows inline in
Jupyter (``_repr_svg_``) and saves as SVG, PNG, PDF or DOT (``save``).

Also the pieces `afsmc diagram` draws with: Storm's probability of reaching each mode
(``mode_reachability``, ``reach_overlay``) and Graphviz's rendering (``render``).
"""

from __future__ import annotations

import os
import time
from dataclasses import dataclass
from typing import TYPE_CHECKING

import graphviz

from afsmc.api.errors import AfsmError
from afsmc.backends.dot import Overlay
from afsmc.backends.dot import diagram as dot_diagram
from afsmc.check.modegraph import analyse
from afsmc.compiler import lowered
from afsmc.diagnostics import CompileError, Diagnostic, Severity, codes
from afsmc.files import write_atomic
from afsmc.lifetime import without_main
from afsmc.lower.lowering import Resolution
from afsmc.model import expr as E
from afsmc.model import ir
from afsmc.text import short
from afsmc.verify import default_max_states, upper_bound
from afsmc.verify.core.api import ask
from afsmc.verify.core.uncertainty import reach_bounds
from afsmc.verify.engines.guard import Progress
from afsmc.verify.engines.stopping import large_variables
from afsmc.verify.engines.storm import StormFailure
from afsmc.verify.outcome.strategy import turns_chosen
from afsmc.verify.plan.deep import refuse_deep_build

if TYPE_CHECKING:
    from afsmc.api.mission import Mission

FORMATS = ("svg", "png", "pdf")


def _error(code: str, message: str, hint: str | None = None) -> CompileError:
    return CompileError([Diagnostic(code, Severity.ERROR, message, None, hint=hint)])


def span_text(lo: object, hi: object) -> str:
    """`lo – hi`, or one number when they agree (to the digits shown)."""
    a, b = short(lo), short(hi)
    return a if a == b else f"{a} – {b}"


@dataclass(frozen=True)
class Diagram:
    """A drawn mission: ``source`` is the Graphviz DOT text, ``graph`` the
    :class:`graphviz.Digraph`. Rendering needs Graphviz's `dot` program (E610 if absent)."""

    graph: graphviz.Digraph
    name: str

    @property
    def source(self) -> str:
        """The DOT text (`afsmc compile -t dot` with the overlay drawn)."""
        text: str = self.graph.source
        return text

    def render(self, fmt: str = "svg") -> bytes:
        """The picture as "svg", "png" or "pdf" bytes. Raises AfsmError (E610, E613)."""
        if fmt not in FORMATS:
            raise ValueError(f"format must be one of {', '.join(FORMATS)}; got {fmt!r}")
        try:
            return render(self.graph, fmt)
        except CompileError as exc:
            raise AfsmError.of(exc) from None

    def _repr_svg_(self) -> str:
        return self.render("svg").decode("utf-8")

    def save(self, path: str | os.PathLike[str]) -> str:
        """Write the picture; its format follows the name: .svg, .png, .pdf, or .gv/.dot
        for the DOT text. Written atomically; returns the path."""
        path = os.fspath(path)
        ext = os.path.splitext(path)[1].lower().lstrip(".")
        try:
            if ext in ("gv", "dot"):
                write_atomic(path, self.source)
            elif ext in FORMATS:
                write_atomic(path, self.render(ext))
            else:
                raise ValueError(f"{path}: the name must end in .svg, .png, .pdf, .gv or .dot")
        except CompileError as exc:
            raise AfsmError.of(exc) from None
        return path


def diagram(mission: Mission, *, reach: bool = False, resolve: Resolution = "nondet",
            max_states: int | None = None, progress: Progress | None = None) -> Diagram:
    """:meth:`Mission.diagram`: `reach` writes Storm's probability of reaching each mode
    into its box (as `afsmc diagram --reach`, with `resolve` and `max_states`)."""
    overlay = Overlay()
    if reach:
        try:
            with without_main():
                overlay = reach_modes(mission.model, resolve, max_states=max_states,
                                      progress=progress)
        except CompileError as exc:
            raise AfsmError.of(exc) from None
    return Diagram(dot_diagram(mission.model, overlay), mission.name)


def reach_modes(model: ir.Model, resolution: Resolution, *, max_states: int | None = None,
                progress: Progress | None = None) -> Overlay:
    """The overlay of `--reach`: each mode's probability of ever being reached; in a
    composed mission, each agent's modes, in the agent's cluster."""
    if model.composition is None:
        return reach_overlay(*mode_reachability(model, resolution, max_states=max_states,
                                                progress=progress))
    reach, mdp = _reachability(model, resolution, max_states, progress)
    agents = {name: Overlay(modes={n: f"P(reach) {span_text(lo, hi)}"
                                   for n, (lo, hi) in sorted(modes.items())})
              for name, modes in reach.items()}
    over = [w for w, on in (("interval choices", model.is_nondeterministic),
                            ("the agents' turns", turns_chosen(model))) if on]
    caption = ("P(reach): probability of ever reaching the agent's mode" +
               (", min – max over " + " and ".join(over) if mdp and over else ""))
    return Overlay(caption=caption, agents=agents)


def mode_reachability(model: ir.Model, resolution: Resolution, *,
                      max_states: int | None = None, progress: Progress | None = None
                      ) -> tuple[dict[int, tuple[float, float]], bool]:
    """Storm: (min, max) probability of ever reaching each mode of a machine (equal for
    a DTMC), and whether the model is an MDP. Built once for all modes, with verify's
    guard: a model that may be large is built in a watched process and stopped at
    `max_states` (default: what the free memory holds) or when the memory runs short,
    with E405/E406. (A composed mission's agents' modes: `reach_modes`.)"""
    reach, mdp = _reachability(model, resolution, max_states, progress)
    return reach[""], mdp


def _reachability(model: ir.Model, resolution: Resolution, max_states: int | None,
                  progress: Progress | None
                  ) -> tuple[dict[str, dict[int, tuple[float, float]]], bool]:
    """(min, max) of reaching each mode, per agent ("": a machine's own modes)."""
    low = lowered(model, resolution)  # the reductions keep every mode's reachability
    if max_states is None:  # verify's up-front guard: a counter too deep for an unlimited build
        refuse_deep_build(low, "Storm's build for --reach", default_max_states(),
                          hint="--max-states N stops the build at N states (E405 if there "
                               "are more); or draw a smaller instance with --const")
    mdp = low.kind == "mdp"
    comp = model.composition
    unreachable: set[int] = set() if comp is not None else set(analyse(model).unreachable)
    # (agent, its mode variable in the generated model, mode number)
    targets = [("", "mode", m.number) for m in sorted(model.modes, key=lambda m: m.number)
               if m.number not in unreachable] if comp is None else [
        (a.name, a.mode_var, m.number) for a in comp.agents
        for m in sorted(a.model.modes, key=lambda m: m.number)]
    ops = ("min", "max") if mdp else ("",)

    def query(i: int, op: str) -> str:
        return f"reach_{i}_{op}" if op else f"reach_{i}"
    queries = {query(i, op): f"P{op}=? [ F {var}={n} ]"
               for i, (_, var, n) in enumerate(targets) for op in ops}
    say = progress or (lambda text: None)

    def relay(text: str) -> None:
        # One line per finished query would be one per mode; the guard's periodic lines
        # ("checking ...: 15 s") still show a slow one.
        if not text.startswith("checked "):
            say("reach: " + text)
    say(f"reach: building the {low.kind.upper()} with Storm and checking {len(targets)} "
        f"modes ...")
    t0 = time.monotonic()
    # With interval probabilities the values come from the bounds below (parameter lifting
    # on afsmc's explorer, else Storm's parametric engine); the build at the midpoint
    # stays, with one query, as the guard (state limit, memory) that they do not have.
    asked = dict(list(queries.items())[:1]) if model.prob_intervals else queries
    got = ask(low, asked, bound=upper_bound(model), what=f"{low.kind.upper()} (--reach)",
              max_states=max_states, progress=relay)
    if got.failure is not None:
        raise _reach_error(got.failure, model)
    say(f"reach: {got.states:,} states, {got.transitions:,} transitions, "
        f"{len(asked)} checks in {time.monotonic() - t0:.1f} s")
    out: dict[str, dict[int, tuple[float, float]]] = {}
    if comp is None:
        out[""] = {n: (0.0, 0.0) for n in unreachable}
    if not model.prob_intervals:
        for i, (agent, _, n) in enumerate(targets):
            vs = [got.values[query(i, op)] for op in ops]
            out.setdefault(agent, {})[n] = (min(vs), max(vs))
    else:
        # the bounds over every fixed value of the interval probabilities, as verify's
        # min and max (docs/verification.md, "What a result means"), not the midpoint's
        over, engine = reach_bounds(model, [(query(i, ""), E.Binary(
            "==", E.VarRef(var, E.Type.INT), E.lit(n), E.Type.BOOL))
            for i, (_, var, n) in enumerate(targets)])
        say(f"reach: the bounds over the interval probabilities ({engine})")
        for i, (agent, _, n) in enumerate(targets):
            out.setdefault(agent, {})[n] = over[query(i, "")]
        mdp = True
    return out, mdp


def _reach_error(f: StormFailure, model: ir.Model | None = None) -> CompileError:
    """Storm's failure at --reach in the diagram's words: E405 too big, E406 out of
    memory, E612 anything else."""
    if f.stage == "too-big":
        large = large_variables(model) if model is not None else ""
        return _error(codes.E405, " ".join(f.message.split())
                      + (f"; the largest ranges: {large}" if large else ""),
                      "raise --max-states if the machine has the memory (the sparse engine "
                      "needs about 250 bytes per state), or draw a smaller instance with "
                      "--const")
    if f.stage == "memory":
        return _error(codes.E406, " ".join(f.message.split()),
                      "draw a smaller instance with --const")
    return _error(codes.E612, f"Storm could not compute the reachability of the modes: "
                  f"{' '.join(f.message.split()) or f.stage}",
                  hint="check the model with `afsmc compile -t prism`")


def reach_overlay(reach: dict[int, tuple[float, float]], mdp: bool) -> Overlay:
    modes = {n: f"P(reach) {span_text(lo, hi)}" for n, (lo, hi) in sorted(reach.items())}
    caption = ("P(reach): probability of ever reaching the mode" +
               (", min – max over interval choices" if mdp else ""))
    return Overlay(modes=modes, caption=caption)


def render(g: graphviz.Digraph, fmt: str) -> bytes:
    try:
        data: bytes = g.pipe(format=fmt, engine="dot")
    except graphviz.ExecutableNotFound:
        raise _error(codes.E610, "the Graphviz program `dot` was not found on PATH",
                     hint="install Graphviz (e.g. `apt-get install graphviz`), or write the "
                          "DOT source with `afsmc compile FILE -t dot` and render it elsewhere"
                     ) from None
    except graphviz.CalledProcessError as exc:
        stderr = exc.stderr.decode("utf-8", "replace").strip() if exc.stderr else ""
        raise _error(codes.E613, f"Graphviz `dot` failed: {stderr or exc}") from None
    return data


