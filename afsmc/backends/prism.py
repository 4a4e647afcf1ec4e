"""PRISM backend: the lowered model as a PRISM model file and a properties file.

A pure function of the lowered IR; the output is byte-deterministic and points back
to the .afsm source with `// file:line` comments.
"""

from __future__ import annotations

import os
from dataclasses import dataclass
from typing import ClassVar

from afsmc import __version__
from afsmc.backends.storm_safe import signed_pow
from afsmc.lower.lowering import Command, Lowered
from afsmc.model import expr as E
from afsmc.model import ir
from afsmc.model.limits import INT64
from afsmc.model.pretty import Printer, number


@dataclass(frozen=True)
class PrismOutput:
    model: str
    properties: str
    property_names: tuple[str, ...]  # in the order of the properties file


class PrismPrinter(Printer):
    ops: ClassVar[dict[str, str]] = {"&&": "&", "||": "|", "=>": "=>", "==": "=", "!=": "!="}

    def __init__(self, weight_names: dict[str, str], low: Lowered | None = None):
        super().__init__()
        self.weight_names = weight_names
        self.low = low

    def show(self, e: E.Expr, ctx: int) -> str:
        safe = signed_pow(e, self.low) if self.low is not None else None
        return super().show(e if safe is None else safe, ctx)

    def atom(self, e: E.Expr) -> str:
        if isinstance(e, E.Lit):
            return pnum(e.value)
        if isinstance(e, E.ModeVal):
            return pnum(e.number)
        if isinstance(e, E.WeightRef):
            return self.weight_names[e.action]
        return super().atom(e)


def pnum(v: int | float | bool) -> str:
    """A number as PRISM reads it: Storm's parser takes the literal without its sign, so
    -2^63 overflows as written ("expecting <no 64-bit integer overflow>")."""
    if isinstance(v, int) and not isinstance(v, bool) and v == INT64[0]:
        return f"({INT64[0] + 1} - 1)"
    return number(v)


def prange(lo: int | float, hi: int | float) -> str:
    """A PRISM range `[lo..hi]`; a single value's is written `[lo..lo+1]`. Storm's PRISM
    state generator gives a variable of one value no bits, and an update of it overwrites
    a bit of the variable stored after it (a wrong state, so wrong values); the value
    lo+1 is never reached (every update stays in the variable's range, E303), so the
    states are the same."""
    return f"[{pnum(lo)}..{pnum(hi if hi > lo else lo + 1)}]"


def describe(cmd: Command, modes: str) -> str:
    """What a command stands for, for the generated file's comments."""
    if cmd.kind == "deadlock":
        return f"no action enabled in {modes}: the machine stays there"
    what = {"action": "action", "preemptive": "hazard", "final": "final mode"}[cmd.kind]
    return f"{what} {cmd.action} in {modes}"


def weight_formula_names(low: Lowered) -> dict[str, str]:
    """`w_<action>` for every action some weight refers to, avoiding the file's names."""
    model = low.model
    taken = {c.name for c in model.constants} | {v.name for v in model.variables} | {
        f.name for f in model.formulas} | set(low.bounds)
    used = sorted({n.action for a in model.actions for n in E.walk(a.weight)
                   if isinstance(n, E.WeightRef)})
    out = {}
    for a in used:
        name = f"w_{a}"
        while name in taken:
            name += "_"
        taken.add(name)
        out[a] = name
    return out


def where(span: object) -> str:
    from afsmc.diagnostics import Span

    assert isinstance(span, Span)
    return f"{os.path.basename(span.source.path)}:{span.line}"


def variant_label(low: Lowered, index: int) -> str:
    """The action label of command `index` when each floor/ceil variant is labelled apart
    (`emit(..., variant_labels=True)`): Storm's choice labels then name the variant."""
    return f"{low.commands[index].action}__c{index}"


def _constants(low: Lowered) -> list[str]:
    """The constants section: point-valued constants (interval probabilities at their
    midpoint, or undefined as parameters) and the generated floor/ceil bounds."""
    model = low.model
    out: list[str] = []
    w = out.append
    consts = [c for c in model.constants if not c.is_interval]
    if consts or low.bounds:
        w("// ---- constants")
    for c in consts:
        t = "int" if c.type is E.Type.INT else "double" if c.type is E.Type.DOUBLE else "bool"
        kind = "param, " if c.is_param else ""
        if c.prob_interval is not None:
            kind = f"in [{number(c.prob_interval[0])}, {number(c.prob_interval[1])}], "
        if c.name in low.parameters:  # left undefined: Storm's parametric engine
            w(f"const {t} {c.name}; // parameter, {kind}{where(c.span)}")
            continue
        kind += "its midpoint, " if c.prob_interval is not None else ""
        w(f"const {t} {c.name} = {pnum(c.value)}; // {kind}{where(c.span)}")
    for gen, (src, value) in sorted(low.bounds.items(), key=lambda kv: (kv[1][0], kv[1][1])):
        c = model.constant(src)
        assert c.interval is not None
        w(f"const int {gen} = {pnum(value)}; // {src} in [{c.interval[0]}, {c.interval[1]}], "
          f"{where(c.span)}")
    return out


def emit(low: Lowered, variant_labels: bool = False) -> PrismOutput:
    """The PRISM model. `variant_labels`: each command that resolves an interval constant
    gets its own action label (`variant_label`), and the action rewards of its action are
    repeated for each such label, so that the values stay the same."""
    composed = low.network is not None
    if composed and not variant_labels:
        from afsmc.backends.prism_network import emit_network

        return emit_network(low)
    # A composed mission with its commands labelled apart is one module of the mission's
    # commands (the product its modules form): Storm's choice labels then name the command
    # and so the agent that moved (afsmc.verify.outcome.strategy).
    model = low.model
    labels = {i: "" if c.silent else variant_label(low, i)
              if variant_labels and (c.choice or composed) else
              c.action for i, c in enumerate(low.commands)}
    wnames = weight_formula_names(low)
    p = PrismPrinter(wnames, low)
    out: list[str] = []
    w = out.append
    w(f"// Generated by afsmc {__version__} from {os.path.basename(model.source.path)} "
      f"(machine {model.name}). Do not edit: edit the .afsm file.")
    if model.is_nondeterministic:
        how = {"nondet": "a nondeterministic floor/ceil choice (min/max bounds)",
               "uniform": "a uniform random floor/ceil choice",
               "lo": "their floor", "hi": "their ceiling"}[low.resolution]
        w(f"// Interval constants are resolved by {how}.")
    if low.reductions:
        w(f"// Exact reductions: {', '.join(low.reductions)} (afsmc compile --no-reduce: none).")
    w(low.kind)
    w("")

    out.extend(_constants(low))
    if model.formulas:
        w("")
        w("// ---- formulas")
    for f in model.formulas:
        w(f"formula {f.name} = {p(f.value)}; // {where(f.span)}")
    if wnames:
        w("")
        w("// ---- weights w(s, a) that other weights refer to (0 where the action is disabled)")
    for action, name in wnames.items():
        w(f"formula {name} = {p(low.weights[action])};")
    w("")

    w(f"module {model.name}")
    modes = ", ".join(f"{m.name}={m.number}" for m in model.modes)
    w(f"  // modes: {modes}")
    numbers = [m.number for m in model.modes]
    w(f"  mode : {prange(min(numbers), max(numbers))} init "
      f"{pnum(model.initial_mode.number)};")
    for v in model.variables:
        note = f" // {v.display}, {where(v.span)}" + (", clamped" if v.clamp else "")
        if v.type is E.Type.BOOL:
            w(f"  {v.name} : bool init {number(bool(v.init))};{note}")
        else:
            w(f"  {v.name} : {prange(v.lo, v.hi)} init {pnum(v.init)};{note}")
    last = None
    for ci, cmd in enumerate(low.commands):
        if cmd.span != last:
            w("")
            modes_txt = ", ".join(f"{model.mode_by_number(n).name}" for n in cmd.modes)
            w(f"  // {describe(cmd, modes_txt)}: {where(cmd.span)}")
            last = cmd.span
        if cmd.choice:
            w("  // " + ", ".join(f"{c}={end}" for c, end in cmd.choice))
        w(f"  [{labels[ci]}] {p(cmd.guard)} ->")
        branches = []
        for b in cmd.branches:
            ups = " & ".join(f"({var}'={p(val)})" for var, val in b.updates) or "true"
            branches.append(f"{p.show(b.prob, 8)} : {ups}")
        w("    " + "\n  + ".join(branches) + ";")
    w("endmodule")

    if model.labels:
        w("")
    for lb in model.labels:
        w(f'label "{lb.name}" = {p(lb.value)}; // {where(lb.span)}')
    for r in model.rewards:
        w("")
        w(f'rewards "{r.name}" // {where(r.span)}')
        for it in r.items:
            acts = sorted({lb for i, lb in labels.items() if low.commands[i].action == it.action
                           and not low.commands[i].silent}) if it.action else [""]
            for a in acts or [it.action or ""]:
                act = f"[{a}] " if a else ""
                w(f"  {act}{p(it.guard)} : {p(it.value)};")
        if not r.items:
            w("  true : 0; // an empty structure: Storm's PRISM parser needs an item")
        w("endrewards")
    w("")

    names, props = properties(low, p)
    return PrismOutput("\n".join(out), "\n".join(props) + "\n" if props else "", tuple(names))


def property_variants(low: Lowered, prop: ir.Property) -> list[tuple[str, str]]:
    """(name, optimisation) pairs: an MDP's `P=?` is asked as both Pmin and Pmax."""
    if low.kind == "dtmc":
        return [(prop.name, "")]
    if prop.opt:
        return [(prop.name, prop.opt)]
    return [(f"{prop.name}_min", "min"), (f"{prop.name}_max", "max")]


def formula_text(prop: ir.Property, opt: str, p: Printer) -> str:
    path = prop.path
    if isinstance(path, ir.Path):
        b = f"<={p.show(path.bound, 10)}" if path.bound is not None else ""
        if path.kind == "U":
            assert path.left is not None
            body = f"{p.show(path.left, 5)} U{b} {p.show(path.target, 5)}"
        elif path.kind == "X":
            body = f"X {p.show(path.target, 5)}"
        else:
            body = f"{path.kind}{b} {p.show(path.target, 5)}"
        return f"P{opt}=? [ {body} ]"
    if path.kind == "F":
        assert path.target is not None
        body = f"F {p.show(path.target, 5)}"
    elif path.kind == "C":
        body = "C" + (f"<={p.show(path.bound, 10)}" if path.bound is not None else "")
    else:
        assert path.bound is not None
        body = f"I={p.show(path.bound, 10)}"
    return f'R{{"{prop.reward}"}}{opt}=? [ {body} ]'


def properties(low: Lowered, p: Printer) -> tuple[list[str], list[str]]:
    names: list[str] = []
    lines: list[str] = []
    for prop in low.model.properties:
        for name, opt in property_variants(low, prop):
            names.append(name)
            lines.append(f'"{name}": {formula_text(prop, opt, p)};')
    return names, lines


def files(low: Lowered) -> dict[str, str]:
    """`afsmc compile -t prism`: the model and its properties."""
    out = emit(low)
    return {".prism": out.model, ".props": out.properties}
