"""How a mission fails: a reachability property's probability split by cause.

The cause of a path that reaches the target of `P=? [ F φ ]` (or `ψ U φ`, step-bounded
or not) is the step that first enters φ: the hazard that happened in it, or the action
that fired when no hazard did, and the mode it entered. Every path that reaches φ does
so through exactly one first step, so the probabilities of the causes add up to the
property's value exactly (docs/report.md, "How it fails"). A path whose first state is
in φ already has the cause "initial".

How it is computed. The lowered model gets one more variable, `cause`, 0 at the start;
each branch of each command sets it, in the step that enters φ from outside φ (φ false
before, φ true after the branch's updates), to the number of its (event, mode entered),
and leaves it as it is otherwise. The dynamics are those of the mission, so the value of
`P [ F φ ]` stays what it was, and `P [ F φ & cause = k ]` is the probability of the
k-th cause. In an MDP (interval constants, the agents' order) the causes of the min are
those under the scheduler that attains the min, and likewise for the max: Storm checks
the property with the scheduler extracted, applies it, and checks every cause on the
DTMC it induces. With interval probabilities the causes are those at their midpoint
(the reference the strategies follow).
"""

from __future__ import annotations

import dataclasses
import os
import tempfile
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any, Literal

from afsmc.backends.prism import PrismPrinter, emit, formula_text, weight_formula_names
from afsmc.compiler import lowered
from afsmc.diagnostics import CompileError, Diagnostic, Severity, codes
from afsmc.lower.lowering import Branch, Command, Lowered
from afsmc.model import expr as E
from afsmc.model import ir
from afsmc.model.semantics import inline
from afsmc.report import causes_pass
from afsmc.sim.compile import Scope, fold, static
from afsmc.verify.core.api import load_with_formulas, select
from afsmc.verify.engines.strategy_storm import Extract, Extracted, WitnessRequest
from afsmc.verify.outcome.strategy import extract_for
from afsmc.verify.outcome.witness import Witness, describe

Kind = Literal["hazard", "action", "initial"]
Under = Literal["min", "max", "value"]


@dataclass(frozen=True)
class Cause:
    """One way into a property's target: the `event` (a hazard's or an action's name; the
    mission's name for "initial") of the step that first enters it, and the mode entered."""

    kind: Kind
    event: str
    during: str  # the action a hazard struck ("" for an action or "initial")
    mode: str
    probability: float

    def to_json(self) -> dict[str, object]:
        cause: dict[str, object] = {"kind": self.kind, "event": self.event}
        if self.during:
            cause["during"] = self.during
        cause["mode"] = self.mode
        return {"cause": cause, "probability": self.probability}

    @property
    def text(self) -> str:
        if self.kind == "initial":
            return f"in the target from the start (mode {self.mode})"
        during = f" during {self.during}" if self.during else ""
        return f"{self.kind} {self.event}{during}, into {self.mode}"


@dataclass(frozen=True)
class Split:
    """A property's causes under one scheduler (`under`: "min", "max", or "value" for a
    DTMC's one value), most probable first, and their `total`: Storm's value of the
    property on the instrumented model under that scheduler."""

    name: str
    under: Under
    total: float
    causes: tuple[Cause, ...]
    # the most probable paths into the largest cause (under the max's scheduler, or a
    # DTMC's), as mission traces, and why there are fewer than asked
    paths: tuple[Witness, ...] = ()
    paths_note: str = ""
    midpoint: bool = False  # with the interval probabilities at their midpoint

    @property
    def summed(self) -> float:
        return sum(c.probability for c in self.causes)

    def to_json(self) -> list[dict[str, object]]:
        return [{**c.to_json(), "under": self.under} for c in self.causes]


def splittable(p: ir.Property) -> bool:
    """A probability of reaching a target (`F φ`, `ψ U φ`, step-bounded or not)."""
    return p.kind == "P" and isinstance(p.path, ir.Path) and p.path.kind in ("F", "U")


def why_not(model: ir.Model, p: ir.Property) -> str | None:
    """Why property `p` of `model` cannot be split by cause, or None."""
    if not splittable(p):
        return (f"property {p.name} is not the probability of reaching a target (F or U): "
                "it has no causes to split it by")
    if model.composition is not None:
        return f"{p.name}: the causes are not split in a mission of several agents"
    assert isinstance(p.path, ir.Path)
    if p.path.bound is not None and (model.is_nondeterministic or model.prob_intervals):
        return (f"{p.name} is step-bounded and the mission has choices: Storm gives no "
                "scheduler for a step-bounded property of an MDP, so its causes under the "
                "min and the max cannot be told apart")
    return None


def _fail(message: str, hint: str | None = None) -> CompileError:
    return CompileError([Diagnostic(codes.E417, Severity.ERROR, message, None, hint=hint)])


def _post(e: E.Expr, updates: Sequence[tuple[str, E.Expr]]) -> E.Expr:
    """`e` in the state after the (simultaneous) `updates`."""
    new = dict(updates)

    def fn(n: E.Expr) -> E.Expr | None:
        if isinstance(n, E.CurrentMode) and "mode" in new:
            return new["mode"]
        if isinstance(n, E.VarRef) and n.name in new:
            return new[n.name]
        return None

    return E.transform(e, fn)


@dataclass
class _Numbering:
    """The causes met so far, each with its number (from 1; 0: no entry yet)."""

    keys: dict[tuple[Kind, str, str, int], int] = dataclasses.field(default_factory=dict)

    def of(self, kind: Kind, event: str, during: str, mode: int) -> int:
        return self.keys.setdefault((kind, event, during, mode), len(self.keys) + 1)


def _entries(cmd: Command, b: Branch, low: Lowered, target: E.Expr, base: Scope) -> list[int]:
    """The modes branch `b` of `cmd` may enter `target` in: those where, from a mode of
    `cmd` in which the target may be false, the target after the branch's updates may be
    true, as far as the constants and the modes tell (folded); the others cannot be a
    cause, so they are not numbered (fewer causes: fewer bits in a state, fewer queries)."""
    dest = dict(b.updates).get("mode")
    rest = [(v, x) for v, x in b.updates if v != "mode"]
    out: set[int] = set()
    for m in dict.fromkeys(cmd.modes):
        sc = dataclasses.replace(base, mode=m)
        if _folded(target, sc) is True:  # inside already: no first entry from m
            continue
        into = [m] if dest is None else [dest.number] if isinstance(dest, E.ModeVal) \
            else sorted(low.model.mode_names)
        for n in into:
            after = _post(target, [*rest, ("mode", E.ModeVal(low.model.mode_names[n], n))])
            if _folded(after, sc) is not False:
                out.add(n)
    return sorted(out)


def _folded(e: E.Expr, sc: Scope) -> object:
    """`e`'s value when the constants and the mode decide it, else None (also where it
    reads a constant without a value here: an interval probability's)."""
    try:
        return static(fold(e, sc))
    except KeyError:
        return None


def _entered(modes: list[int], b: Branch, low: Lowered, numbering: _Numbering,
             kind: Kind, event: str, during: str) -> E.Expr:
    """The number of the cause this branch is, by the mode it enters (one of `modes`)."""
    dest = dict(b.updates).get("mode")
    after: E.Expr = E.CurrentMode() if dest is None else dest
    out: E.Expr = E.lit(numbering.of(kind, event, during, modes[-1]))
    for m in reversed(modes[:-1]):
        here = E.Binary("==", after, E.ModeVal(low.model.mode_names[m], m), E.Type.BOOL)
        out = E.Ite(here, E.lit(numbering.of(kind, event, during, m)), out, E.Type.INT)
    return out


def instrument(low: Lowered, target: E.Expr, var: str) -> tuple[Lowered, _Numbering]:
    """`low` with the variable `var` recording the cause of the first entry into
    `target` (inlined: no formulas, labels or weights)."""
    numbering = _Numbering()
    was = E.VarRef(var, E.Type.INT)
    fresh = E.Binary("==", was, E.lit(0), E.Type.BOOL)
    consts: dict[str, object] = {**low.model.const_values,
                                 **{gen: value for gen, (_, value) in low.bounds.items()}}
    base = Scope(consts, {}, {}, low.weights)
    commands = []
    for cmd in low.commands:
        if cmd.kind in ("final", "deadlock"):  # self-loops: they enter nothing
            commands.append(cmd)
            continue
        branches = []
        for b in cmd.branches:
            modes = _entries(cmd, b, low, target, base)
            if not modes:
                branches.append(b)
                continue
            # a probabilistic hazard is a branch of the action it strikes; a preemptive
            # one (`hazard H from S when φ`) is a command of its own
            kind: Kind = "hazard" if b.hazard is not None or cmd.kind == "preemptive" \
                else "action"
            event = b.hazard if b.hazard is not None else cmd.action
            enters = E.conj(fresh, E.neg(target), _post(target, b.updates))
            during = cmd.action if b.hazard is not None else ""
            value = E.Ite(enters, _entered(modes, b, low, numbering, kind, event, during), was,
                          E.Type.INT)
            branches.append(dataclasses.replace(b, updates=(*b.updates, (var, value))))
        commands.append(dataclasses.replace(cmd, branches=tuple(branches)))
    init = low.model.initial_mode
    numbering.of("initial", low.model.name, "", init.number)
    top = len(numbering.keys) + 1  # room for the causes numbered while emitting: none
    span = low.model.variables[0].span if low.model.variables else low.model.modes[0].span
    variable = ir.Variable(var, var, E.Type.INT, 0, top, 0, False, span)
    model = dataclasses.replace(low.model, variables=(*low.model.variables, variable))
    return dataclasses.replace(low, model=model, commands=tuple(commands)), numbering


def _fresh(model: ir.Model) -> str:
    taken = {v.name for v in model.variables} | {c.name for c in model.constants} | {
        f.name for f in model.formulas}
    name = "afsmc_cause"
    while name in taken:
        name += "_"
    return name


def split_file(path: str, consts: Mapping[str, str] | None = None,
               names: Sequence[str] = (), formulas: Sequence[str] = (), *,
               text: str | None = None) -> dict[str, list[Split]]:
    """The causes of the properties `verify` checks with these names and formulas (all
    declared ones by default), by name. A property named (or a formula) that cannot be
    split is E417; among all the declared ones, those are left out."""
    loaded = load_with_formulas(path, consts, formulas, text=text)
    props = select(loaded.model, names, loaded.adhoc)
    model = loaded.model
    if names or formulas:
        bad = [p for p in props if why_not(model, p) is not None]
        if bad:
            raise CompileError([d for p in bad for d in _refusal(model, p).diagnostics])
    return split_all(model, [p for p in props if why_not(model, p) is None])


def _refusal(model: ir.Model, prop: ir.Property) -> CompileError:
    return _fail(why_not(model, prop) or prop.name,
                 hint="--causes splits `P=? [ F φ ]` and `P=? [ ψ U φ ]` properties (an "
                      "MDP's: without a step bound) of one machine")


def split(model: ir.Model, prop: ir.Property, *, low: Lowered | None = None
          ) -> list[Split]:
    """The causes of `prop` (a reachability probability): one Split for a DTMC, two (min,
    max) for an MDP. `low`: the lowered model to instrument (default: the model's
    nondeterministic lowering with every reduction, as verify checks it)."""
    return split_all(model, [prop], low=low)[prop.name]


@dataclass(frozen=True)
class _Asked:
    """One property's queries on the instrumented model: the whole property by each
    scheduler (`whole`), and each cause's part (`parts`, by the cause's key)."""

    prop: ir.Property
    whole: dict[Under, str]
    parts: dict[tuple[Kind, str, str, int], str]
    var: str  # the cause variable
    numbers: dict[tuple[Kind, str, str, int], int]  # each part's value of it


def split_all(model: ir.Model, props: Sequence[ir.Property], *,
              low: Lowered | None = None, paths: int = 0,
              max_bytes: int | None = None, max_states: int | None = None
              ) -> dict[str, list[Split]]:
    """:func:`split` of several properties on one model: each gets a cause variable of
    its own, and Storm builds the model once for all. `paths`: with each property's
    split under its max (a DTMC: its only one), the `paths` most probable paths into its
    largest cause. `max_bytes`, `max_states`: the most memory and states afsmc's own
    exploration of the instrumented model may take (E417 past either; None: no limit)."""
    bad = [p for p in props if why_not(model, p) is not None]
    if bad:
        raise CompileError([d for p in bad for d in _refusal(model, p).diagnostics])
    inst = low if low is not None else lowered(model, "nondet")
    if model.prob_intervals:
        # at the midpoint: every interval probability at the middle of its interval
        inst = dataclasses.replace(inst, parameters=())
    variables = []
    numberings = []
    for prop in props:
        assert isinstance(prop.path, ir.Path)
        var = _fresh(inst.model)
        inst, numbering = instrument(inst, inline(prop.path.target, model), var)
        variables.append(var)
        numberings.append(numbering)
    p = PrismPrinter(weight_formula_names(inst), inst)
    opts: list[Under] = ["min", "max"] if inst.kind == "mdp" else ["value"]
    asked = []
    for prop, var, numbering in zip(props, variables, numberings, strict=True):
        assert isinstance(prop.path, ir.Path)
        whole = {u: formula_text(prop, "" if u == "value" else u, p) for u in opts}
        cause = E.VarRef(var, E.Type.INT)
        parts = {}
        for key, k in numbering.keys.items():
            restricted = E.conj(prop.path.target,
                                E.Binary("==", cause, E.lit(k), E.Type.BOOL))
            path = dataclasses.replace(prop.path, target=restricted)
            parts[key] = formula_text(dataclasses.replace(prop, path=path), "", p)
        asked.append(_Asked(prop, whole, parts, var, dict(numbering.keys)))
    extract = extract_for(inst, (), None, None) if paths else None
    values = _explored(inst, model, asked, opts, paths, extract, (max_bytes, max_states))
    if values is None:
        values = _storm(emit(inst, variant_labels=bool(paths)).model, asked, paths, extract)
    names = model.mode_names
    out: dict[str, list[Split]] = {}
    for a, (got, found) in zip(asked, values, strict=True):
        splits = []
        for u in opts:
            total, shares = got[u]
            causes = tuple(sorted(
                (Cause(kind, event, during, names[mode], v)
                 for (kind, event, during, mode), v in shares.items() if v > 0),
                key=lambda c: (-c.probability, c.kind, c.event, c.during, c.mode)))
            traced: tuple[Witness, ...] = ()
            note = ""
            if found is not None and u == opts[-1]:
                traced = tuple(_without(w, set(variables))
                               for w in describe(found.paths, found.variables, inst))
                note = found.witness_note
            splits.append(Split(a.prop.name, u, total, causes, traced, note,
                                bool(model.prob_intervals)))
        out[a.prop.name] = splits
    return out


def _explored(inst: Lowered, model: ir.Model, asked: Sequence[_Asked], opts: list[Under],
              paths: int, extract: Extract | None, limits: tuple[int | None, int | None]
              ) -> list[tuple[Shares, Extracted | None]] | None:
    """The shares by afsmc's own exploration and backward pass (causes_pass), as
    :func:`_storm` gives them; None where it does not apply: a property with a step bound
    or of the form `ψ U φ`, or a model the explorer does not take."""
    wholes = []
    for a in asked:
        path = a.prop.path
        assert isinstance(path, ir.Path)
        if path.kind != "F" or path.bound is not None:
            return None
        wholes.append(inline(path.target, model))
    got = causes_pass.explored(inst, wholes, [(a.var, [a.numbers[key] for key in a.parts])
                                              for a in asked], opts, paths, extract,
                                     *limits)
    if got is None:
        return None
    return [({u: (total, dict(zip(a.parts, values, strict=True)))
              for u, (total, values) in shares.items()}, traced)
            for a, (shares, traced) in zip(asked, got, strict=True)]


def _without(w: Witness, hidden: set[str]) -> Witness:
    """A path with the cause variables left out of its steps' changes."""
    steps = tuple(dataclasses.replace(st, changes={k: v for k, v in st.changes.items()
                                                   if k not in hidden}) for st in w.steps)
    return dataclasses.replace(w, steps=steps,
                               start={k: v for k, v in w.start.items() if k not in hidden})


Shares = dict[Under, tuple[float, dict[tuple[Kind, str, str, int], float]]]


def _storm(model_text: str, asked: Sequence[_Asked], paths: int = 0,
           extract: Extract | None = None) -> list[tuple[Shares, Extracted | None]]:
    """Storm's sparse engine, in this process, on the model built once: each property's
    whole query (by the scheduler it optimises) with its scheduler applied, and each of
    its parts on the DTMC that induces; with `paths`, the most probable paths into the
    largest part under the last scheduler (`extract`: the commands' labels)."""
    import stormpy
    from stormpy import developer

    from afsmc.verify.engines.strategy_storm import builder_options, induced

    developer.set_log_level(developer.LogLevel.OFF)
    try:
        with tempfile.TemporaryDirectory(prefix="afsmc-") as tmp:
            path = os.path.join(tmp, "model.prism")
            with open(path, "w", encoding="utf-8") as f:
                f.write(model_text)
            program = stormpy.parse_prism_program(path)
        texts = [t for a in asked for t in [*a.whole.values(), *a.parts.values()]]
        parsed = iter(stormpy.parse_properties(";\n".join(texts), program))
        queries = [([next(parsed) for _ in a.whole], [next(parsed) for _ in a.parts])
                   for a in asked]
        every = [q for w, r in queries for q in (*w, *r)]
        built = stormpy.build_model(program, every) if extract is None else \
            stormpy.build_model(program, options=builder_options(stormpy, every, program,
                                                                 extract))
        env = _precise(stormpy)
        init = built.initial_states[0]
        out: list[tuple[Shares, Extracted | None]] = []
        for a, (tops, rest) in zip(asked, queries, strict=True):
            shares: Shares = {}
            found = None
            for u, prop in zip(a.whole, tops, strict=True):
                mdp = u != "value"
                res = stormpy.model_checking(built, prop, extract_scheduler=mdp,
                                             environment=env)
                dtmc = induced(stormpy, built, res)[0] if mdp else built
                start = dtmc.initial_states[0]
                got = {key: float(stormpy.model_checking(dtmc, q, environment=env)
                                  .get_value(start)) for key, q in zip(a.parts, rest, strict=True)}
                shares[u] = (float(res.get_value(init)), got)
                if extract is not None and paths and got:
                    largest = max(range(len(rest)), key=lambda i: list(got.values())[i])
                    found = _traced(stormpy, program, dtmc, rest[largest], paths, extract,
                                    list(got.values())[largest])
            out.append((shares, found))
        return out
    except RuntimeError as exc:
        raise _fail(f"Storm could not split the property by cause: {' '.join(str(exc).split())}"
                    ) from None


def _traced(stormpy: Any, program: Any, dtmc: Any, part: Any, k: int, extract: Extract,
            value: float) -> Extracted:
    """The `k` most probable paths of `dtmc` into the states of a cause (`part`'s target),
    as verify's `--witness` finds them (afsmc.verify.engines.strategy_storm)."""
    from afsmc.verify.engines.strategy_storm import _paths, _valuations, _variables

    variables = _variables(stormpy, program)
    out = Extracted(variables=tuple(n for n, _, _ in variables))
    _paths(stormpy, program, dtmc, part, WitnessRequest("cause", k),
           _valuations(dtmc, variables), extract, out, value)
    return out


def _precise(stormpy: Any) -> Any:
    """Value iteration to a relative 1e-12, so that the causes add up to the value to
    far better than the digits shown."""
    from afsmc.verify.plan.precision import iterative_environment

    return iterative_environment(stormpy, 1024, "VALUE_ITERATION", "POWER",
                                 "1/1000000000000", relative=True)
