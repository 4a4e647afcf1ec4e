"""JANI backend: the lowered model as one JANI 1 model (JSON), properties included.

A pure function of the lowered IR (the same `Lowered` the PRISM backend prints), so both
routes into Storm describe the same Markov chain or MDP by construction:

* one automaton with one location; the mode is the bounded int variable `mode`;
* every lowered command is one edge (final-mode self-loops are silent), every branch
  one destination;
* JANI has no formulas: formulas and `w(A)` are inlined;
* labels are transient bool variables set in the location's `transient-values`;
* a reward structure is a transient real variable: its state rewards are set in the
  location, its action rewards on every destination of the edges of that action
  (the same value on all destinations, so Storm reads them as choice rewards, as PRISM's
  `[a] g : r` are).

`dumps` serialises once; the output is byte-deterministic.
"""

from __future__ import annotations

import json
import os
from typing import Any

from afsmc.backends.prism import describe, property_variants
from afsmc.backends.storm_safe import signed_pow
from afsmc.diagnostics import Diagnostic, Severity, Span, codes
from afsmc.lower.lowering import Command, Lowered
from afsmc.model import expr as E
from afsmc.model import ir
from afsmc.model.semantics import bounded_globally, globally_dual

Json = Any  # a JSON-ready value: dict, list, str, int, float, bool

JANI_OPS = {"&&": "∧", "||": "∨", "=>": "⇒", "==": "=", "!=": "≠", "<": "<", "<=": "≤",
            ">": ">", ">=": "≥", "+": "+", "-": "-", "*": "*", "/": "/"}
LOCATION = "l"


def _unique(base: str, taken: set[str]) -> str:
    name = base
    while name in taken:
        name += "_"
    taken.add(name)
    return name


class _Names:
    """JANI has one namespace for constants and variables (transient ones included)."""

    def __init__(self, low: Lowered):
        model = low.model
        taken = {c.name for c in model.constants} | {v.name for v in model.variables} | set(
            low.bounds) | {"mode"}
        self.labels = {lb.name: _unique(lb.name, taken) for lb in model.labels}
        self.rewards = {r.name: _unique(r.name, taken) for r in model.rewards}


class _Exprs:
    """IR expressions -> JANI expressions, formulas and weights inlined."""

    def __init__(self, low: Lowered, names: _Names):
        self.low = low
        self.names = names
        self.formulas = {f.name: f.value for f in low.model.formulas}

    def __call__(self, e: E.Expr) -> Json:
        if isinstance(e, E.Lit):
            if e.type is E.Type.BOOL or isinstance(e.value, bool):
                return bool(e.value)
            if e.type is E.Type.DOUBLE:
                return float(e.value)
            return int(e.value)
        if isinstance(e, (E.VarRef, E.ConstRef)):
            return e.name
        if isinstance(e, E.ModeVal):
            return e.number
        if isinstance(e, E.CurrentMode):
            return "mode"
        if isinstance(e, E.FormulaRef):
            return self(self.formulas[e.name])
        if isinstance(e, E.WeightRef):
            return self(self.low.weights[e.action])
        if isinstance(e, E.LabelRef):
            return self.names.labels[e.name]
        if isinstance(e, E.Unary):
            if e.op == "!":
                return {"op": "¬", "exp": self(e.operand)}
            inner = self(e.operand)
            if isinstance(inner, (int, float)) and not isinstance(inner, bool):
                return -inner
            zero: Json = 0.0 if e.type is E.Type.DOUBLE else 0
            return {"op": "-", "left": zero, "right": inner}
        if isinstance(e, E.Binary):
            return {"op": JANI_OPS[e.op], "left": self(e.left), "right": self(e.right)}
        if isinstance(e, E.Ite):
            return {"op": "ite", "if": self(e.cond), "then": self(e.then), "else": self(e.other)}
        if isinstance(e, E.Call):
            safe = signed_pow(e, self.low)
            if safe is not None:
                return self(safe)
            args = [self(a) for a in e.args]
            if e.func in ("floor", "ceil"):
                return {"op": e.func, "exp": args[0]}
            op = {"mod": "%"}.get(e.func, e.func)
            out = args[0]
            for a in args[1:]:  # min/max of several arguments: fold left
                out = {"op": op, "left": out, "right": a}
            return out
        raise TypeError(type(e).__name__)


def _where(span: Span) -> str:
    return f"{os.path.basename(span.source.path)}:{span.line}"


def _num(v: ir.Value, t: E.Type) -> Json:
    if t is E.Type.BOOL:
        return bool(v)
    if t is E.Type.DOUBLE:
        return float(v)
    return int(v)


def _jani_type(t: E.Type) -> str:
    return {E.Type.INT: "int", E.Type.DOUBLE: "real", E.Type.BOOL: "bool"}[t]


def _never_assigned(low: Lowered) -> set[str]:
    """The variables (`mode` too) that no command assigns. Storm's JANI builder drops such a
    variable and then evaluates the expressions that read it wrongly (`G cfg == 1` is 0
    for a `cfg` that stays 1), so they are written as constants of their initial value, which
    is what they are."""
    assigned = {var for c in low.commands for b in c.branches for var, _ in b.updates}
    return {v.name for v in low.model.variables if v.name not in assigned} | (
        set() if "mode" in assigned else {"mode"})


def _constants(low: Lowered) -> list[Json]:
    model = low.model
    out: list[Json] = []
    fixed = _never_assigned(low)
    if "mode" in fixed:
        out.append({"name": "mode", "type": "int", "value": model.initial_mode.number,
                    "comment": "the mode, never changed: a constant (see _never_assigned)"})
    for v in (v for v in model.variables if v.name in fixed):
        out.append({"name": v.name, "type": _jani_type(v.type), "value": _num(v.init, v.type),
                    "comment": f"{v.display}, {_where(v.span)}, never assigned: a constant"})
    for c in model.constants:
        if c.is_interval:
            continue  # replaced by the generated bounds below
        if c.name in low.parameters:  # left undefined: Storm's parametric engine
            out.append({"name": c.name, "type": _jani_type(c.type),
                        "comment": "parameter, " + _where(c.span)})
            continue
        out.append({"name": c.name, "type": _jani_type(c.type), "value": _num(c.value, c.type),
                    "comment": ("param, " if c.is_param else "") + _where(c.span)})
    for gen, (src, value) in sorted(low.bounds.items(), key=lambda kv: (kv[1][0], kv[1][1])):
        c = model.constant(src)
        assert c.interval is not None
        out.append({"name": gen, "type": "int", "value": value,
                    "comment": f"{src} in [{c.interval[0]}, {c.interval[1]}], {_where(c.span)}"})
    return out


def _variables(low: Lowered, names: _Names) -> list[Json]:
    model = low.model
    numbers = [m.number for m in model.modes]
    fixed = _never_assigned(low)  # written as constants
    out: list[Json] = [] if "mode" in fixed else [{
        "name": "mode",
        "type": {"kind": "bounded", "base": "int", "lower-bound": min(numbers),
                 "upper-bound": max(numbers)},
        "initial-value": model.initial_mode.number,
        "comment": "modes: " + ", ".join(f"{m.name}={m.number}" for m in model.modes),
    }]
    for v in model.variables:
        if v.name in fixed:
            continue
        note = f"{v.display}, {_where(v.span)}" + (", clamped" if v.clamp else "")
        if v.type is E.Type.BOOL:
            out.append({"name": v.name, "type": "bool", "initial-value": bool(v.init),
                        "comment": note})
        else:
            out.append({"name": v.name,
                        "type": {"kind": "bounded", "base": "int", "lower-bound": v.lo,
                                 "upper-bound": v.hi},
                        "initial-value": int(v.init), "comment": note})
    for lb in model.labels:
        out.append({"name": names.labels[lb.name], "type": "bool", "transient": True,
                    "initial-value": False, "comment": f'label "{lb.name}", {_where(lb.span)}'})
    for r in model.rewards:
        out.append({"name": names.rewards[r.name], "type": "real", "transient": True,
                    "initial-value": 0.0, "comment": f'rewards "{r.name}", {_where(r.span)}'})
    return out


def _reward_sum(items: list[ir.RewardItem], ex: _Exprs) -> Json:
    """sum of ite(guard, value, 0) over the items."""
    total: Json = None
    for it in items:
        value = ex(it.value)
        if not (isinstance(it.guard, E.Lit) and it.guard.value is True):
            zero: Json = 0.0 if it.value.type is E.Type.DOUBLE else 0
            value = {"op": "ite", "if": ex(it.guard), "then": value, "else": zero}
        total = value if total is None else {"op": "+", "left": total, "right": value}
    return total


def _location(low: Lowered, names: _Names, ex: _Exprs) -> Json:
    model = low.model
    values: list[Json] = [{"ref": names.labels[lb.name], "value": ex(lb.value)}
                          for lb in model.labels]
    for r in model.rewards:
        state = [it for it in r.items if it.action is None]
        if state:
            values.append({"ref": names.rewards[r.name], "value": _reward_sum(state, ex)})
    loc: Json = {"name": LOCATION}
    if values:
        loc["transient-values"] = values
    return loc


def _edge(cmd: Command, low: Lowered, names: _Names, ex: _Exprs) -> Json:
    model = low.model
    modes = ", ".join(model.mode_by_number(n).name for n in cmd.modes)
    comment = f"{describe(cmd, modes)}: {_where(cmd.span)}"
    if cmd.choice:
        comment += " (" + ", ".join(f"{c}={end}" for c, end in cmd.choice) + ")"
    edge: Json = {"location": LOCATION}
    rewards: list[Json] = []
    if not cmd.silent:
        edge["action"] = cmd.action
        for r in model.rewards:
            items = [it for it in r.items if it.action == cmd.action]
            if items:
                rewards.append({"ref": names.rewards[r.name], "value": _reward_sum(items, ex)})
    edge["guard"] = {"exp": ex(cmd.guard)}
    dests = []
    for b in cmd.branches:
        assignments = [{"ref": var, "value": ex(val)} for var, val in b.updates]
        dests.append({"location": LOCATION, "probability": {"exp": ex(b.prob)},
                      "assignments": assignments + rewards})
    edge["destinations"] = dests
    edge["comment"] = comment
    return edge


# ---- properties -------------------------------------------------------------------


def _path(prop: ir.Property, opt: str, names: _Names, ex: _Exprs) -> Json:
    path = prop.path
    # a DTMC has one value: Storm accepts Pmin/Emin there and they equal Pmax/Emax
    op_p, op_e = ("Pmax", "Emax") if opt == "max" else ("Pmin", "Emin")
    if isinstance(path, ir.Path):
        target = ex(path.target)
        inner: Json
        if path.kind == "X":
            # Storm's JANI parser has no X: "φ at step 1" is true U[1,1] φ
            inner = {"op": "U", "left": True, "right": target,
                     "step-bounds": {"lower": 1, "upper": 1}}
        elif path.kind == "G":
            assert path.bound is None  # _properties writes a bounded G as its dual
            inner = {"op": "G", "exp": target}
        elif path.kind == "U":
            assert path.left is not None
            inner = {"op": "U", "left": ex(path.left), "right": target}
        else:
            inner = {"op": "F", "exp": target}
        if path.bound is not None:
            inner["step-bounds"] = {"upper": ex(path.bound)}
        return {"op": op_p, "exp": inner}
    assert prop.reward is not None
    # Storm's accumulation: "steps" collects the edges' (action) rewards, "exit" the
    # locations' (state) rewards when a state is left -- together PRISM's C and F rewards.
    # Without "accumulate", a step-instant is an instantaneous reward (I=k).
    out: Json = {"op": op_e, "exp": names.rewards[prop.reward]}
    if path.kind == "F":
        assert path.target is not None
        out["accumulate"] = ["steps", "exit"]
        out["reach"] = ex(path.target)
    elif path.kind == "C":
        out["accumulate"] = ["steps", "exit"]
        if path.bound is not None:
            out["step-instant"] = ex(path.bound)
    else:
        assert path.bound is not None
        out["step-instant"] = ex(path.bound)
    return out


def dual_name(low: Lowered, name: str) -> str:
    """The JANI name of the property that gives `name` (a step-bounded G) as 1 - its value:
    NAME_complement, unless the file has a property of that name."""
    taken = {n for p in low.model.properties for n, _ in property_variants(low, p)}
    out = f"{name}_complement"
    while out in taken:
        out += "_"
    return out


def _properties(low: Lowered, names: _Names, ex: _Exprs) -> list[Json]:
    out = []
    for prop in low.model.properties:
        for name, opt in property_variants(low, prop):
            asked, comment = prop, _where(prop.span)
            if bounded_globally(prop):
                # Storm's JANI has no step-bounded G: the file holds the dual, and says so
                comment = f"1 - this value is {name} (P [ G<=k φ ] = 1 - P [ F<=k !φ ]" \
                          f"{', min and max swapped' if opt else ''}); {comment}"
                asked, name = globally_dual(prop, name), dual_name(low, name)
                opt = {"min": "max", "max": "min"}.get(opt, "")
            out.append({
                "name": name,
                "expression": {"op": "filter", "fun": "values",
                               "values": _path(asked, opt, names, ex),
                               "states": {"op": "initial"}},
                "comment": comment,
            })
    return out


def notes(low: Lowered) -> list[Diagnostic]:
    """W401 for each step-bounded G, which the file holds as its dual."""
    out = []
    for prop in low.model.properties:
        if bounded_globally(prop):
            variants = property_variants(low, prop)
            said = ", ".join(f"{n} = 1 - {dual_name(low, n)}" for n, _ in variants)
            out.append(Diagnostic(
                codes.W401, Severity.WARNING,
                f"property {prop.name}: Storm's JANI has no step-bounded G, so the file asks "
                f"P [ F<=k !(...) ] instead: {said}"
                # a DTMC's one value has no min and max to swap (_properties agrees)
                + (" (min and max swapped)" if any(opt for _, opt in variants) else ""),
                prop.span, hint="`afsmc verify` reports the G values; `-t prism` keeps G<=k"))
    return out


# ---- public API -------------------------------------------------------------------


def header(low: Lowered, what: str, actions: list[str]) -> dict[str, Any]:
    """A model's keys before its variables: the name, type, provenance (`what` the file
    holds), actions and constants."""
    model = low.model
    return {
        "jani-version": 1,
        "name": model.name,
        "type": low.kind,
        "features": ["derived-operators"],
        "metadata": {"description": f"Generated by afsmc from {os.path.basename(model.source.path)}"
                                    f" ({what}), interval constants resolved: "
                                    f"{low.resolution}. Do not edit: edit the .afsm file."},
        "actions": [{"name": a} for a in actions],
        "constants": _constants(low),
    }


def emit(low: Lowered) -> dict[str, Any]:
    """The JANI model of `low` (properties included) as a JSON-ready dict."""
    if low.network is not None:
        from afsmc.backends.jani_network import emit_network

        return emit_network(low)
    model = low.model
    names = _Names(low)
    ex = _Exprs(low, names)
    actions = sorted({c.action for c in low.commands if not c.silent})
    return {
        **header(low, f"machine {model.name}", actions),
        "variables": _variables(low, names),
        "properties": _properties(low, names, ex),
        "automata": [{
            "name": model.name,
            "locations": [_location(low, names, ex)],
            "initial-locations": [LOCATION],
            "edges": [_edge(c, low, names, ex) for c in low.commands],
        }],
        "system": {"elements": [{"automaton": model.name}],
                   "syncs": [{"synchronise": [a], "result": a} for a in actions]},
    }


# Nesting levels written one item a line, indented; anything deeper is written on one line.
INDENTED_LEVELS = 24


def dumps(model: dict[str, Any]) -> str:
    """Deterministic JSON text: insertion order, indent 2, UTF-8 operators, final newline;
    a value nested deeper than INDENTED_LEVELS on one line. JANI has only binary operators,
    so a sum of n terms nests n levels: indented all the way, each level's lines carried
    the indentation of every level above (a 4,000-term guard became 300 MB of JANI, its
    PRISM 150 KB); on one line, the text grows with the expression."""
    return _dump(model, 0) + "\n"


def _dump(value: Any, level: int) -> str:
    """`json.dumps(value, indent=2)` at nesting `level`, down to INDENTED_LEVELS."""
    if level >= INDENTED_LEVELS or not isinstance(value, (dict, list)) or not value:
        return json.dumps(value, ensure_ascii=False, allow_nan=False)
    inner = "\n" + "  " * (level + 1)
    if isinstance(value, dict):
        items = [json.dumps(str(k), ensure_ascii=False) + ": " + _dump(v, level + 1)
                 for k, v in value.items()]
        return "{" + inner + ("," + inner).join(items) + "\n" + "  " * level + "}"
    items = [_dump(v, level + 1) for v in value]
    return "[" + inner + ("," + inner).join(items) + "\n" + "  " * level + "]"


def property_names(low: Lowered) -> list[str]:
    """The JANI properties' names, in order: those of the PRISM backend's properties file,
    but for the dual of each step-bounded G."""
    return [dual_name(low, name) if bounded_globally(prop) else name
            for prop in low.model.properties for name, _ in property_variants(low, prop)]


def files(low: Lowered) -> dict[str, str]:
    """`afsmc compile -t jani`: one .jani file."""
    return {".jani": dumps(emit(low))}
