"""Storm's schedulers in mission terms: which interval constant takes its floor or its
ceiling, in which action and mode, in how many of the states the scheduler reaches, and a
threshold on one variable that separates the two ends where there is one.

The Storm process summarises a scheduler per PRISM command and mode
(:mod:`afsmc.verify.engines.strategy_storm`); the lowered model names each command's action and
the interval constants it fixes (`Command.choice`).
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable, Mapping, Sequence, Set
from dataclasses import dataclass
from typing import Any

from afsmc.backends.prism import property_variants, variant_label
from afsmc.diagnostics import CompileError, Diagnostic, Severity, codes
from afsmc.lower.lowering import Lowered
from afsmc.lower.reduce import Reductions
from afsmc.model import ir
from afsmc.verify.engines.storm import Via
from afsmc.verify.engines.strategy_storm import Extract, Extracted, Group, RawPath, WitnessRequest
from afsmc.verify.outcome.results import Checks, PropertyResult
from afsmc.verify.outcome.strategy_compose import action_text, displays, mover, range_text
from afsmc.verify.outcome.witness import describe

END = {"lo": "floor", "hi": "ceil"}


@dataclass(frozen=True)
class StrategyEntry:
    """One interval constant at one end, in one action and mode: in `states` of the
    states the scheduler reaches; `when` a condition on one variable that holds in exactly
    those of them (against the other end), or None."""

    constant: str
    end: str  # "floor" | "ceil"
    value: int
    action: str
    mode: str
    states: int
    when: str | None = None
    # further states of this action and mode that the strategy reaches, where both ends
    # give the same value (Storm's choice there is arbitrary and not counted in `states`)
    indifferent: int = 0
    # a composed mission: the agents the action moves, `action` their own name of it (for
    # the diagram's clusters; not in the JSON, where `mode` names them)
    agents: tuple[str, ...] = ()

    def to_json(self) -> dict[str, object]:
        return {"constant": self.constant, "end": self.end, "value": self.value,
                "action": self.action, "mode": self.mode, "states": self.states,
                "when": self.when, "indifferent": self.indifferent}

    def text(self) -> str:
        return f"{self.constant} = {self.value} ({self.end}) in {self.action}, mode {self.mode}" \
            + (f" when {self.when}" if self.when else "")


@dataclass(frozen=True)
class TurnEntry:
    """A composed mission whose agents' turns are a choice: the scheduler moves `action`
    ("uav1: Look", or a synchronised "Launch (uav1, uav2)") in `states` of the states it
    reaches where the choice matters, with its agents in `mode`."""

    action: str
    mode: str
    states: int
    # the agents it moves and their own name of the action ("uav1", "Look"; for the
    # diagram's clusters; not in the JSON, where `action` names them)
    agents: tuple[str, ...] = ()
    local: str = ""

    def to_json(self) -> dict[str, object]:
        return {"action": self.action, "mode": self.mode, "states": self.states}


def turns_open(low: Lowered) -> bool:
    """Whether the scheduler also chooses which agent moves (interleaving, ties nondet)."""
    net = low.network
    return net is not None and low.kind == "mdp" and (
        net.kind == "interleaving" or net.ties == "nondet")


def decisive(low: Lowered) -> tuple[int, ...]:
    """The commands where the scheduler chooses: a floor/ceil variant of an action; in a
    composed mission whose turns are a choice, every agent's command."""
    every = turns_open(low)
    return tuple(i for i, c in enumerate(low.commands) if c.choice or (every and not c.silent))


def turns(groups: Sequence[Group], variables: Sequence[str], low: Lowered) -> list[TurnEntry]:
    """Which agent the scheduler moves, where the choice matters, per action and modes."""
    count: dict[tuple[str, str], int] = {}
    moves: dict[str, tuple[tuple[str, ...], str]] = {}
    for g in groups:
        if g.matters:
            cmd = low.commands[g.command]
            _, mode = _where(low, g, variables)
            key = (action_text(low, cmd), str(mode))
            count[key] = count.get(key, 0) + g.states
            who, local = mover(low, cmd)
            moves[key[0]] = (tuple(a.name for a in who), local)
    return [TurnEntry(a, m, n, *moves[a]) for (a, m), n in sorted(count.items())]


@dataclass
class _Range:
    states: int
    low: list[int]
    high: list[int]


def summarise(groups: Sequence[Group], variables: Sequence[str],
              low: Lowered) -> list[StrategyEntry]:
    """The entries of a scheduler from its groups (`variables`: the Storm model's)."""
    model = low.model
    mode_i = list(variables).index("mode") if "mode" in variables else -1
    ranges: dict[tuple[str, str, int | str], dict[str, _Range]] = {}
    same: dict[tuple[str, str, int | str], int] = {}
    who: dict[tuple[str, str, int | str], tuple[str, ...]] = {}
    for g in groups:
        cmd = low.commands[g.command]
        action, mode = _where(low, g, variables)
        if model.composition is not None:
            for const, _ in cmd.choice:
                who[(const, action, mode)] = tuple(a.name for a in mover(low, cmd)[0])
        for const, end in cmd.choice:
            if not g.matters:
                same[(const, action, mode)] = same.get((const, action, mode), 0) + g.states
                continue
            by_end = ranges.setdefault((const, action, mode), {})
            r = by_end.get(end)
            if r is None:
                by_end[end] = _Range(g.states, list(g.low), list(g.high))
            else:
                r.states += g.states
                r.low = [min(a, b) for a, b in zip(r.low, g.low, strict=True)]
                r.high = [max(a, b) for a, b in zip(r.high, g.high, strict=True)]
    display = {v.name: v.display for v in model.variables}
    skip = {mode_i}
    if model.composition is not None:
        display = displays(low)
        # a threshold on a mode number says nothing to people: the modes are named
        skip |= {i for i, v in enumerate(variables) if v.endswith("_mode") and any(
            a.mode_var == v for a in model.composition.agents)}
    out = []
    for (const, action, mode), by_end in sorted(ranges.items()):
        c = model.constant(const)
        assert c.interval is not None
        conds = _separate(by_end, [i for i in range(len(variables)) if i not in skip],
                          [display.get(v, v) for v in variables])
        for end in ("lo", "hi"):
            r = by_end.get(end)
            if r is None:
                continue
            value = int(c.interval[0] if end == "lo" else c.interval[1])
            out.append(StrategyEntry(const, END[end], value, action,
                                     mode if isinstance(mode, str) else
                                     model.mode_by_number(mode).name, r.states, conds.get(end),
                                     same.get((const, action, mode), 0),
                                     who.get((const, action, mode), ())))
    return out


def _where(low: Lowered, g: Group, variables: Sequence[str]) -> tuple[str, int | str]:
    """A group's action and mode: the mode's number in a machine; in a composed mission,
    the agent's action and the modes of the agents it moves ("uav2: Search")."""
    cmd = low.commands[g.command]
    if low.model.composition is None:
        return cmd.action, g.mode
    who, action = mover(low, cmd)
    names = list(variables)
    return action, "; ".join(range_text(a, g.low[names.index(a.mode_var)],
                                        g.high[names.index(a.mode_var)]) for a in who)


def _separate(by_end: dict[str, _Range], columns: list[int],
              names: list[str]) -> dict[str, str]:
    """A threshold on one variable between the two ends' states, if one separates them."""
    lo, hi = by_end.get("lo"), by_end.get("hi")
    if lo is None or hi is None:
        return {}
    for i in columns:
        if lo.high[i] < hi.low[i]:
            return {"lo": f"{names[i]} <= {lo.high[i]}", "hi": f"{names[i]} >= {hi.low[i]}"}
        if hi.high[i] < lo.low[i]:
            return {"hi": f"{names[i]} <= {hi.high[i]}", "lo": f"{names[i]} >= {lo.low[i]}"}
    return {}


def stepped(p: ir.Property) -> bool:
    """A step-bounded property: its optimal strategy counts the steps (it needs memory),
    and Storm extracts no scheduler for it."""
    return getattr(p.path, "bound", None) is not None


def request(low: Lowered, strategy: bool, witness: WitnessRequest | None,
            queries: Sequence[str], asked_as: Mapping[str, str],
            skip: Set[str] = frozenset()) -> Extract | None:
    """What the Storm job of `queries` (as asked: a bounded G's dual) on the lowered MDP,
    or only DTMC, extracts: every query's scheduler, and the witness paths of the one
    the witness follows. `skip`: queries without a scheduler (step-bounded ones)."""
    mine = tuple(queries)
    w = None
    if witness is not None:
        asked = asked_as.get(witness.query, witness.query)
        w = dataclasses.replace(witness, query=asked) if asked in mine else None
    kept = tuple(q for q in mine if q not in skip) if strategy and low.kind == "mdp" else ()
    if not kept and w is None:
        return None
    return extract_for(low, kept, None, w)


def extract_for(low: Lowered, strategies: tuple[str, ...], policy: str | None,
                witness: WitnessRequest | None) -> Extract:
    """The Extract of a job on `low`'s PRISM model emitted with variant labels."""
    cmds = decisive(low)
    # a composed mission's commands are all labelled apart (the agent that moved)
    labels = {i: variant_label(low, i) for i, c in enumerate(low.commands)
              if i in cmds or (low.network is not None and not c.silent)}
    return Extract(strategies, policy, witness, cmds, tuple(labels[i] for i in cmds),
                   tuple((labels.get(i, "" if c.silent else c.action), c.modes)
                         for i, c in enumerate(low.commands)))


def attach(results: Sequence[PropertyResult], props: Sequence[ir.Property], low: Lowered,
           extracted: Sequence[Extracted], asked_as: Mapping[str, str]
           ) -> list[PropertyResult]:
    """The results of `props` (as `results`) with the schedulers and paths extracted."""
    groups: dict[str, list[Group]] = {}
    variables: tuple[str, ...] = ()
    paths: list[RawPath] = []
    note = ""
    for x in extracted:
        groups |= x.groups
        variables = x.variables or variables
        if x.paths or x.witness_note:
            paths, note = x.paths, x.witness_note
    out = []
    for r, p in zip(results, props, strict=True):
        more: dict[str, Any] = {}
        for name, opt in property_variants(low, p):
            query = asked_as.get(name, name)
            if query in groups and opt in ("min", "max"):
                more.setdefault("strategy", dict(r.strategy or {}))[opt] = summarise(
                    groups[query], variables, low)
                if turns_open(low):
                    more.setdefault("turns", dict(r.turns or {}))[opt] = turns(
                        groups[query], variables, low)
            if any(query == x.witness_query for x in extracted if x.witness_query):
                more |= {"witnesses": describe(paths, variables, low), "witness_note": note,
                         "witness_of": opt or "value"}
        out.append(dataclasses.replace(r, **more) if more else r)
    return out


def turns_chosen(model: ir.Model) -> bool:
    """Whether a composed mission leaves its agents' turns to the scheduler (interleaving
    of two or more agents, timed with `ties nondet`), as `Lowered.kind` decides."""
    comp = model.composition
    return comp is not None and ((comp.kind == "interleaving" and len(comp.agents) > 1
                                  and comp.ties != "uniform")
                                 or (comp.kind == "timed" and comp.ties == "nondet"))


def has_choices(model: ir.Model) -> bool:
    """Whether the model is an MDP, whose min and max strategies choose: interval
    constants (floor or ceil), or the agents' turns (`turns_chosen`)."""
    return model.is_nondeterministic or turns_chosen(model)


MAX_WITNESSES = 1000  # --witness K: the paths are found one by one and all kept


def refuse(message: str, hint: str | None = None) -> CompileError:
    return CompileError([Diagnostic(codes.E415, Severity.ERROR, message, None, hint=hint)])


def check_request(model: ir.Model, props: Sequence[ir.Property], strategy: bool,
                  witness: tuple[str | None, int] | None) -> None:
    """Refuse what has no strategy or no witness (E415), before Storm is started."""
    if strategy and not has_choices(model):
        raise refuse(f"--strategy: {model.source.path} has no interval constants: its model "
                     "is a DTMC, which has no choices for a strategy to make",
                     hint="a strategy resolves interval constants such as "
                          "'const int T = [10, 12];'")
    if witness is None:
        return
    name, k = witness
    if not 1 <= k <= MAX_WITNESSES:
        raise refuse(f"--witness {k:,}: the number of paths must be from 1 to {MAX_WITNESSES:,}",
                     hint="each path is searched for and kept: ask for the few most probable")
    if name is None and len(props) != 1:
        raise refuse(f"--witness {k}: the paths are of one property, and {len(props)} are "
                     "checked", hint="name the property with -p NAME (or give one --formula)")
    prop = next((p for p in props if p.name == name or name is None), None)
    if prop is None:
        raise refuse(f"--witness: no property named '{name}' is checked",
                     hint="name the property with -p NAME")
    name = prop.name
    if prop.kind != "P" or not isinstance(prop.path, ir.Path) or prop.path.kind not in (
            "F", "U"):
        raise refuse(f"--witness: property '{name}' ({prop.text}) has no target states for "
                     "paths to reach", hint="witnesses are paths of P [ F target ] and P [ left U target ], "
                     "possibly step-bounded")


DIRECTIONS = ("min", "max")


def witness_request(model: ir.Model, props: Sequence[ir.Property], strategy: bool,
                    witness: tuple[str | None, int] | None, direction: str | None,
                    target: str | None = None) -> WitnessRequest | None:
    """The witness query: `witness` = (property, K); an MDP's paths follow the scheduler
    of `direction` ("min" or "max"; default: the property's own, else "max"). `target`: a
    PRISM state formula the paths go into instead of the property's target. Refuses a
    request that has no answer (E415)."""
    check_request(model, props, strategy, witness)
    if witness is None:
        if direction is not None:
            raise refuse("--witness-dir: give --witness K as well")
        return None
    prop = next(p for p in props if p.name == witness[0] or witness[0] is None)
    name, k = prop.name, witness[1]
    avoid = False
    if prop.threshold is not None and target is None and direction is None:
        # A requirement's paths show how it is violated, under the strategy that decides
        # its verdict: for `>=`/`>` the min's paths into states where the property can no
        # longer hold; for `<=`/`<` the max's paths into its target.
        lower = prop.threshold.op in (">=", ">")
        avoid = lower and not stepped(prop)
        direction = ("min" if lower else "max") if has_choices(model) else None
    return _request(model, prop, name, k, direction, target, avoid)


def _request(model: ir.Model, prop: ir.Property, name: str, k: int, direction: str | None,
             target: str | None, avoid: bool) -> WitnessRequest:
    if not has_choices(model):
        if direction is not None:
            raise refuse(f"--witness-dir {direction}: {model.source.path} has no interval "
                         "constants: its model is a DTMC, whose paths follow no strategy")
        return WitnessRequest(name, k, target, avoid)
    if stepped(prop):
        raise refuse(f"--witness: property '{name}' ({prop.text}) is step-bounded: its min "
                     "and max strategies count the steps, and Storm gives no scheduler for "
                     "them", hint="choose a property without a step bound")
    if direction is not None and direction not in DIRECTIONS:
        raise refuse(f"--witness-dir {direction!r}: expected min or max")
    if prop.opt:
        if direction is not None and direction != prop.opt:
            raise refuse(f"--witness-dir {direction}: property '{name}' asks for P{prop.opt} "
                         "only", hint=f"use --witness-dir {prop.opt}, or none")
        return WitnessRequest(name, k, target, avoid)
    return WitnessRequest(f"{name}_{direction or 'max'}", k, target, avoid)


def extras(checks: Checks, check: Callable[..., Checks], model: ir.Model,
           props: Sequence[ir.Property], strategy: bool, witness: WitnessRequest | None, *,
           max_states: int | None, progress: Callable[[str], None] | None,
           reductions: Reductions | None, via: Via) -> Checks:
    """Schedulers and paths come from the sparse engine. A check on a symbolic engine
    (chosen, or picked by "auto") gave none: check the MDP again with the sparse engine
    if it fits (E416 if not); `checks` with what it extracts."""
    missing = [p for p, r in zip(props, checks.properties, strict=True)
               if (strategy and r.strategy is None and not stepped(p))
               or (witness is not None and r.witnesses is None and _owns(p, witness))]
    if not missing:
        return checks
    if progress is not None:
        progress(f"the {checks.model.engine} engine (via {via}) gives no scheduler: the MDP "
                 "is checked again with the sparse engine, via PRISM, for the strategies "
                 "and paths")
    try:
        again = check(model, missing, via="prism", engine="sparse", max_states=max_states,
                      uniform=False, progress=progress, reductions=reductions,
                      strategy=strategy, witness=witness)
    except CompileError as exc:
        raise CompileError([Diagnostic(
            codes.E416, Severity.ERROR, f"--strategy/--witness: the {checks.model.engine} "
            "engine checked the model, but schedulers and paths come from the sparse engine, "
            "and the sparse check failed: " + "; ".join(d.message for d in exc.diagnostics
                                                        if d.severity is Severity.ERROR),
            None, hint="a smaller instance (--const), or raise --max-states if the memory "
                       "allows")]) from None
    by_name = {r.name: r for r in again.properties}
    out = []
    for r in checks.properties:
        got = by_name.get(r.name)
        if got is not None:
            r = dataclasses.replace(r, strategy=r.strategy or got.strategy)
            if got.witnesses is not None:
                r = dataclasses.replace(r, witnesses=got.witnesses, witness_of=got.witness_of,
                                        witness_note=got.witness_note)
        out.append(r)
    return dataclasses.replace(checks, properties=out)


def _owns(p: ir.Property, w: WitnessRequest) -> bool:
    return w.query == p.name or w.query in (f"{p.name}_min", f"{p.name}_max")
