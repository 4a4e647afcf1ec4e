"""What `afsmc verify`'s Storm engines would refuse, or answer wrongly, that the spec alone
shows: said by `check` and the editor before anything is built.

Over interval probabilities, `verify` bounds every property over their box with Storm's
parametric engine, which needs every transition kept in the whole box and checks neither
`X`, `I=k` nor an unbounded `C`:

- W307: at a corner of the box a branch probability leaves (0, 1]: an outcome's
  probability is 0 (`[0, 0.15]` for `SLIP: ...`), or a hazard's is 0 or 1 (at 1 the
  actions' own outcomes disappear). verify stops there with E440.
- W308: a property of a kind the parametric engine cannot check; verify stops with E443.

And whatever the probabilities:

- W310: a total reward (`R [C]`, no step bound) of a structure that may be negative. Storm
  refuses it on an MDP, and on a DTMC it may answer +inf where the runs earn -inf without
  end (a negative state reward in a final mode): verify refuses it before building (E404).

Warnings, not errors: `compile` and `simulate` take such a file as it is. The corners are
those verify tries (afsmc.verify.engines.parametric.well_defined_ir); a probability that
reads the state is searched for a state where it leaves (0, 1], as E304 is.
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Iterator, Mapping

from afsmc.check.ranges import value_at
from afsmc.diagnostics import Reporter, codes
from afsmc.model import expr as E
from afsmc.model import ir
from afsmc.model.bounds import bounds
from afsmc.model.evaluate import EvalError, scalar
from afsmc.model.expr import Type
from afsmc.model.search import find
from afsmc.model.semantics import enabled, inline

MAX_CORNERS = 64  # corners tried per probability (2^6 interval probabilities read)
_HINT = ("verify bounds every property over the interval probabilities with Storm's parametric "
         "engine (parameter lifting), which needs every transition to keep a positive "
         "probability in the whole box")


def signed_total(p: ir.Property, model: ir.Model) -> str | None:
    """The reward structure of `p` if `p` is a total reward (`R [C]`, no step bound) of a
    structure that may be negative (interval arithmetic over the variables' ranges); else
    None. `verify` refuses such a property (E404), `check` warns of it (W310)."""
    if p.kind != "R" or p.path.kind != "C" or p.path.bound is not None:
        return None
    name = p.reward if p.reward is not None else (model.rewards[0].name
                                                  if model.rewards else "")
    r = next((r for r in model.rewards if r.name == name), None)
    return name if r is not None and any(bounds(it.value, model)[0] < 0 for it in r.items) \
        else None


def check_total_rewards(model: ir.Model, rep: Reporter) -> None:
    """W310 at each `R [C]` without a step bound whose reward structure may be negative."""
    for p in model.properties:
        name = signed_total(p, model)
        if name is not None:
            rep.warning(codes.W310, f"property '{p.name}' asks the total reward of \"{name}\", "
                        "which may be negative: a total reward that gains and loses without "
                        "end has no value, Storm refuses it on an MDP and on a DTMC may "
                        "answer +inf where the runs lose without end (verify refuses it, "
                        "E404)",
                        p.span, hint="ask R{...}=? [ C<=k ] for the first k steps, or R{...}=? "
                        "[ F ... ] up to the mission's end; or keep every reward >= 0")


def check_prob_intervals(model: ir.Model, rep: Reporter) -> None:
    box = {c.name: c.prob_interval for c in model.prob_intervals if c.prob_interval}
    if not box:
        return
    _check_corners(model, box, rep)
    _check_properties(model, box, rep)


def _sites(model: ir.Model) -> Iterator[tuple[E.Expr, str, bool, dict[int, E.Expr]]]:
    """(probability, what it is, whether it must stay below 1, the modes where it applies
    and when) of every branch: each outcome, and each hazard woven into the actions."""
    for a in model.actions:
        when = {m: enabled(model, a, m) for m in a.modes}
        owner = f"{'hazard' if a.kind == 'preemptive' else 'action'} {a.name}"
        for o in a.outcomes:
            yield o.prob, f"an outcome of {owner}", False, when
    for h in model.hazards:
        when = {m: E.disj(*(enabled(model, a, m) for a in model.actions_in(m)))
                for m in h.modes}
        yield h.prob, f"hazard {h.name}", True, when
        for o in h.outcomes:
            yield o.prob, f"an outcome of hazard {h.name}", False, when


def _check_corners(model: ir.Model, box: dict[str, tuple[float, float]], rep: Reporter) -> None:
    said: set[tuple[str, float]] = set()  # (constant, end) already warned about
    consts = dict(model.const_values)
    for prob, what, below_one, when in _sites(model):
        e = inline(prob, model)
        names = sorted(E.consts_read(e) & set(box))
        if not names or 2 ** len(names) > MAX_CORNERS:
            continue
        stateful = bool(E.vars_read(e)) or E.reads_mode(e)
        for ends in itertools.product(*(box[n] for n in names)):
            corner = dict(zip(names, ends, strict=True))
            if any((n, v) in said for n, v in corner.items()):
                continue
            value = _leaves(model, e, corner, below_one, when) if stateful \
                else _static(e, corner, consts, below_one)
            if value is None:
                continue
            at = ", ".join(f"{n} = {v:g}" for n, v in corner.items())
            edge = [n for n, v in corner.items() if v in (0.0, 1.0)] or names
            const = model.constant(edge[0])
            rep.warning(codes.W307, f"at {at} the probability of {what} is {value}: "
                        "`afsmc verify` cannot bound the properties over the interval "
                        "probabilities there, and would stop with E440", const.span,
                        hint=f"{_HINT}: {_open_bounds(model, edge, box)}")
            said |= set(corner.items())
            break


def _static(e: E.Expr, corner: dict[str, float], consts: Mapping[str, object],
            below_one: bool) -> str | None:
    """The value of a state-free probability at `corner`, if it leaves (0, 1] (or (0, 1)
    for a hazard's); else None."""
    try:
        v = float(scalar(e, {**consts, **corner}))
    except (EvalError, ZeroDivisionError, OverflowError):
        return None
    if math.isnan(v) or (0.0 < v < 1.0) or (v == 1.0 and not below_one):
        return None
    return f"{v:g}"


def _leaves(model: ir.Model, e: E.Expr, corner: dict[str, float], below_one: bool,
            when: dict[int, E.Expr]) -> str | None:
    """The same for a probability that reads the state: its value in a state where it
    leaves (0, 1] while it applies, found by the exact search E304 uses; None if none."""
    at = E.transform(e, lambda n: E.lit(corner[n.name]) if isinstance(n, E.ConstRef)
                     and n.name in corner else None)
    bad = E.disj(E.Binary("<=", at, E.lit(0.0), Type.BOOL),
                 E.Binary(">=" if below_one else ">", at, E.lit(1.0), Type.BOOL))
    for mode, cond in when.items():
        wit = find(model, mode, E.conj(cond, bad))
        if wit is not None:
            return f"{value_at(model, at, wit, mode)} in the state {wit}"
    return None


def _open_bounds(model: ir.Model, names: list[str], box: dict[str, tuple[float, float]]) -> str:
    """The declarations with open ends: `const prob SLIP = [1e-6, 0.15];`."""
    def end(x: float, low: bool) -> str:
        return "1e-6" if low and x == 0.0 else "0.999999" if not low and x == 1.0 else f"{x:g}"
    edges = [n for n in names if box[n][0] == 0.0 or box[n][1] == 1.0]
    if not edges:
        return "narrow the interval so that every probability stays in (0, 1]"
    return "use an open bound, e.g. " + " ".join(
        f"const prob {n} = [{end(box[n][0], True)}, {end(box[n][1], False)}];" for n in edges)


_UNSUPPORTED = {("P", "X"): "X (next)", ("R", "I"): "I=k (an instantaneous reward)"}


def _check_properties(model: ir.Model, box: dict[str, tuple[float, float]],
                      rep: Reporter) -> None:
    names = ", ".join(sorted(box))
    for p in model.properties:
        kind = _UNSUPPORTED.get((p.kind, p.path.kind))
        if p.kind == "R" and p.path.kind == "C" and p.path.bound is None:
            kind = "C (an unbounded cumulative reward)"
        if kind is None:
            continue
        rep.warning(codes.W308, f"property '{p.name}' asks {kind}, which Storm's parametric "
                    f"engine cannot check: `afsmc verify` bounds every property over the "
                    f"interval probabilities {names}, and would stop with E443", p.span,
                    hint=_ASK_INSTEAD[kind[0]])


_ASK_INSTEAD = {
    "X": "P=? [ F<=1 ... ] is the same where the target does not hold at the start; or give "
         "the probability one value (`const prob P = 0.1;`) to verify it, or estimate it "
         "with `afsmc simulate`",
    "I": "give the probability one value (`const prob P = 0.1;`) to verify it, or estimate "
         "it with `afsmc simulate`",
    "C": "ask R{...}=? [ C<=k ] for the first k steps, or R{...}=? [ F ... ] up to the "
         "mission's end",
}
