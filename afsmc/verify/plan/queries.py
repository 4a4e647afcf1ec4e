"""The queries afsmc asks Storm for a property, and how their answers give its value.

A query is one Storm check: a property, or an MDP property's min or its max. Some are asked
in another form that needs less memory or that Storm's engines check at all:

- a bounded `P [G<=k φ]` is asked as its dual, 1 - P [F<=k !φ] (`dual`, `duals_of`);
- on the hybrid engine a Pmax [F target] is asked as 1 - Pmin [F (final & !target)] when
  every path ends in a final mode (`complements`, `rewrite`).

The hybrid engine needs far more memory for Pmax than for Pmin: for a maximum Storm
removes end components from the explicit matrix of the "maybe" states, a second copy of
it (on the paper's scenario 1 one such check passed 19 GB; its Pmin fitted). When the
target lies inside the final (absorbing) modes and every path ends in a final mode
(Pmin [F final] = 1, which Storm decides by graph analysis alone), the events "F target"
and "F (final & !target)" are complementary under every scheduler, so
Pmax [F target] = 1 - Pmin [F (final & !target)], exactly.

The internal query names (TERMINATES, REST..., DUAL...) never reach the user: `query_text`
and `readable` say what each one gives.
"""

from __future__ import annotations

import math
import re
from collections.abc import Mapping, Sequence

from afsmc.diagnostics import Diagnostic, Severity, codes
from afsmc.model import expr as E
from afsmc.model import ir
from afsmc.model.evaluate import Env, EvalError, evaluate
from afsmc.model.semantics import bounded_globally, globally_dual, inline, static_value

Query = tuple[ir.Property, str]
"""A property and the name of one of its queries (`success_min`, `__afsmc_rest_success`)."""

TERMINATES = "__afsmc_terminates"  # Pmin [F final]: does every path end?
REST = "__afsmc_rest_"  # Pmin [F (final & !target)], giving a Pmax as 1 - it
DUAL = "__afsmc_dual_"  # P[G<=k φ] asked as 1 - P[F<=k !φ]


def dual(p: ir.Property) -> ir.Property:
    """The query that gives a bounded-G property as 1 - its value: P[F<=k !φ], named
    DUAL + the property's name, with min and max swapped."""
    return globally_dual(p, DUAL + p.name)


def _conjuncts(e: E.Expr) -> list[E.Expr]:
    """`a && b && c` -> [a, b, c]."""
    if isinstance(e, E.Binary) and e.op == "&&":
        return _conjuncts(e.left) + _conjuncts(e.right)
    return [e]


def _within_final(target: E.Expr, model: ir.Model) -> bool:
    """Whether a conjunct of `target` that reads only the mode is false in every
    non-final mode."""
    others = [m.number for m in model.modes if not m.final]
    for c in _conjuncts(inline(target, model)):
        if E.vars_read(c) or not E.reads_mode(c):
            continue
        try:
            if not any(bool(evaluate(c, Env(mode=m, consts=model.const_values)))
                       for m in others):
                return True
        except EvalError:
            continue
    return False


def complements(model: ir.Model, props: Sequence[ir.Property]) -> dict[str, ir.Property]:
    """`NAME_max` -> the property Pmin [F (final & !target)] that gives it as 1 - value."""
    finals = {m.number for m in model.modes if m.final}
    if not finals or not model.is_nondeterministic:
        return {}
    final = E.mode_in(finals, model.mode_names)
    out = {}
    for p in props:
        path = p.path
        if p.kind != "P" or p.opt == "min" or not isinstance(path, ir.Path) \
                or path.kind != "F" or path.bound is not None \
                or not _within_final(path.target, model):
            continue
        name = p.name if p.opt == "max" else f"{p.name}_max"
        out[name] = ir.Property(f"{REST}{p.name}", "P", "min",
                                ir.Path("F", E.conj(final, E.neg(path.target))), None, p.span)
    if out:
        out[TERMINATES] = ir.Property(TERMINATES, "P", "min", ir.Path("F", final), None,
                                      props[0].span)
    return out


def rewrite(queries: list[Query],
             comp: dict[str, ir.Property]) -> list[Query]:
    """Ask the complementary Pmin (and whether every path ends) instead of each Pmax."""
    out: list[Query] = []
    for p, n in queries:
        if n in comp:
            if TERMINATES not in [m for _, m in out]:
                out.append((comp[TERMINATES], TERMINATES))
            out.append((comp[n], comp[n].name))
        else:
            out.append((p, n))
    return out


def unanswered(queries: list[Query], vals: dict[str, float],
                comp: dict[str, ir.Property]) -> list[Query]:
    """The queries without an answer yet; a Pmax whose complementary Pmin has one (and
    termination, which decides how it is used) counts as answered."""
    return [(p, n) for p, n in queries if n not in vals
            and not (n in comp and comp[n].name in vals and TERMINATES in vals)]



def not_failed(queries: list[Query], failed: set[str],
                comp: dict[str, ir.Property]) -> list[Query]:
    """The queries to ask still: not one that failed, nor a Pmax whose complementary Pmin
    failed (Pmax itself needs more memory)."""
    return [(p, n) for p, n in queries
            if n not in failed and not (n in comp and comp[n].name in failed)]


def duals_of(props: Sequence[ir.Property]) -> dict[str, tuple[str, str]]:
    """The queries of the duals (`dual`) -> the query of the bounded-G property whose value
    each gives, as 1 - value, and the progress lines' wording of it (from the property
    itself: its own name may end in `_min`)."""
    out = {}
    for p in props:
        if bounded_globally(p):
            # a DTMC, or an MDP property with Pmin/Pmax: the dual asks the other bound
            asked = {"min": "max", "max": "min"}.get(p.opt or "", "")
            out[DUAL + p.name] = (p.name, f"{p.name} as 1 - P{asked} [F<=k !φ]")
            if not p.opt:
                out[f"{DUAL}{p.name}_min"] = (f"{p.name}_max",
                                              f"{p.name}_max as 1 - Pmin [F<=k !φ]")
                out[f"{DUAL}{p.name}_max"] = (f"{p.name}_min",
                                              f"{p.name}_min as 1 - Pmax [F<=k !φ]")
    return out


def kept_note(done: Sequence[tuple[str, dict[str, float]]], comp: Mapping[str, ir.Property],
          duals: Mapping[str, str] | None = None,
          heading: str = "answered before this") -> list[Diagnostic]:
    """A note with the values answered before a failure: a long run keeps what it got."""
    gives = {p.name: name for name, p in comp.items()}  # complementary Pmin -> its Pmax
    lines = []
    for what, vals in done:
        ends = vals.get(TERMINATES) == 1.0
        for name, value in vals.items():
            if name == TERMINATES or (name in gives and not ends):
                continue
            if name in gives:
                name, value = gives[name], 1.0 - value
            if duals and name in duals:
                name, value = duals[name], 1.0 - value
            lines.append(f"  {name} = {value!r} on the {what}")
    if not lines:
        return []
    return [Diagnostic(codes.N412, Severity.NOTE, f"{heading}:\n" + "\n".join(lines), None)]


def query_text(name: str, duals: Mapping[str, str]) -> str:
    """The one wording for a query, in every progress line: the queries afsmc asks instead
    of a Pmax or a bounded G are named by what they give, not by their internal names."""
    if name == TERMINATES:
        return "termination"
    if name.startswith(REST):
        return f"{name[len(REST):]}_max as 1 - Pmin"
    return duals.get(name, name)


def unit_text(unit: list[Query], i: int,
               units: list[list[Query]], duals: Mapping[str, str]) -> str:
    """'query 3 of 14 (missed_min)' or 'process 1 of 2: 10 queries (success_min, ...)'."""
    if len(unit) == 1:
        order = list(dict.fromkeys(n for u in units for _, n in u))
        return (f"query {order.index(unit[0][1]) + 1} of {len(order)} "
                f"({query_text(unit[0][1], duals)})")
    names = ", ".join(query_text(n, duals) for _, n in unit)
    return f"process {i + 1} of {len(units)}: {len(unit)} queries ({names})"


def readable(text: str, duals: Mapping[str, str]) -> str:
    """The guard's progress lines carry the internal names; say what they are."""
    return re.sub(re.escape(REST) + r"\w+|" + re.escape(DUAL) + r"\w+|" + re.escape(TERMINATES),
                  lambda m: query_text(m.group(0), duals), text)



IN_PROCESS_WORK = 500_000_000


def steps(p: ir.Property, model: ir.Model) -> int:
    """The step bound of `p` (F<=k, C<=k, I=k, ...), or 1 if it has none."""
    k = p.path.bound
    v = static_value(k, model) if k is not None else None
    return max(1, int(v)) if v is not None and math.isfinite(v) else 1
