"""Semantic checks of a resolved model, one rule per module.

Each rule is a small function `(model, reporter) -> None` that reports every problem it
finds; `run` applies them all, so an author sees every error of a file at once.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable, Sequence

from afsmc.check import (
    distributions,
    int_pow,
    mode_numbers,
    modegraph,
    overflow,
    ranges,
    storm_depth,
    storm_refuses,
    undefined,
    unused,
    weights,
)
from afsmc.check.sim_sources import check_sim_sources
from afsmc.diagnostics import Diagnostic, Reporter, codes
from afsmc.model import ir
from afsmc.model.evaluate import EvalError
from afsmc.model.search import Undecided

Rule = Callable[[ir.Model, Reporter], None]

RULES: tuple[Rule, ...] = (
    overflow.check_overflow,
    undefined.check_undefined,
    int_pow.check_int_pow,
    weights.check_weight_range,
    weights.check_weight_uniqueness,
    weights.check_weight_refs,
    weights.check_deadlock,
    distributions.check_distributions,
    storm_refuses.check_prob_intervals,
    storm_refuses.check_total_rewards,
    ranges.check_update_ranges,
    unused.check_unused,
    check_sim_sources,
    mode_numbers.check_mode_numbers,
    storm_depth.check_storm_depth,
    modegraph.check_unreachable, modegraph.check_cannot_end, modegraph.check_never_fires,
)


def register(rule: Rule) -> None:
    """Add a rule (used by later stages, e.g. the mode-graph analysis)."""
    global RULES
    if rule not in RULES:
        RULES = (*RULES, rule)


# Rules that read the model's structure only. After an integer overflow (E307) only these
# run: the others search states with 64-bit arithmetic and would report what the wrapped
# values make of the model (a deadlock, an update out of range) that is not there.
STRUCTURAL: tuple[Rule, ...] = (unused.check_unused, check_sim_sources, weights.check_weight_refs,
                                 mode_numbers.check_mode_numbers, storm_depth.check_storm_depth)


def run(model: ir.Model, *, used_names: frozenset[str] = frozenset()) -> list[Diagnostic]:
    """Every rule's diagnostics, sorted. `used_names`: the names the source refers to
    where the IR keeps no reference (`afsmc.resolve.Resolved.used_names`), for W303/W304.
    A composed mission: every rule on each agent, and the composition's own rules."""
    if model.composition is not None:
        from afsmc.check.composition import check_composition

        return check_composition(model, used_names, run)
    return _apply(RULES, model, used_names)


def _apply(rules: Sequence[Rule], model: ir.Model,
           used_names: frozenset[str] = frozenset()) -> list[Diagnostic]:
    rep = Reporter()
    for rule in rules:
        if rule is not overflow.check_overflow and rule not in STRUCTURAL and any(
                d.code == codes.E307 for d in rep.diagnostics):
            continue
        try:
            if rule is unused.check_unused:
                unused.check_unused(model, rep, used_names)
            else:
                rule(model, rep)
        except (Undecided, EvalError, OverflowError) as exc:
            # OverflowError: a value beyond numpy's int64 (E307 says where).
            # An unproven property is said, never passed over in silence.
            name = rule.__name__.removeprefix("check_").replace("_", " ")
            rep.warning(codes.W309, f"the {name} check could not be completed: {exc}", None,
                        hint="the model may still violate it; simplify the expressions involved")
    return rep.sorted()


# The rules that look at a property's expressions (through undefined.sites).
PROPERTY_RULES: tuple[Rule, ...] = (overflow.check_overflow, undefined.check_undefined,
                                    int_pow.check_int_pow, storm_depth.check_storm_depth)


def run_properties(model: ir.Model, props: Sequence[ir.Property]) -> list[Diagnostic]:
    """The diagnostics of properties added to a checked model (afsmc.compiler.
    with_properties): the rules that read property expressions, on the model with only
    those properties and none of its rewards, actions or hazards, whose diagnostics `run`
    gave already (its labels stay: a property reads them; the caller drops what they
    say again). A composed mission's properties are checked in no
    agent (`check_composition` keeps each agent's own diagnostics), so neither are these."""
    if model.composition is not None:
        return []
    view = dataclasses.replace(model, actions=(), hazards=(), rewards=(),
                               properties=tuple(props), memo=ir.Memo())
    return _apply(PROPERTY_RULES, view)
