"""Semantic checks of a resolved model, one rule per module.

Each rule is a small function `(model, reporter) -> None` that reports every problem it
finds; `run` applies them all, so an author sees every error of a file at once.
"""

from __future__ import annotations

from collections.abc import Callable

from afsmc.check import distributions, modegraph, ranges, undefined, unused, weights
from afsmc.check.sim_sources import check_sim_sources
from afsmc.diagnostics import Diagnostic, Reporter
from afsmc.model import ir
from afsmc.model.evaluate import EvalError
from afsmc.model.search import Undecided

Rule = Callable[[ir.Model, Reporter], None]

RULES: tuple[Rule, ...] = (
    undefined.check_undefined,
    weights.check_weight_range,
    weights.check_weight_uniqueness,
    weights.check_deadlock,
    distributions.check_distributions,
    ranges.check_update_ranges,
    unused.check_unused,
    check_sim_sources,
    modegraph.check_unreachable, modegraph.check_cannot_end, modegraph.check_never_fires,
)


def register(rule: Rule) -> None:
    """Add a rule (used by later stages, e.g. the mode-graph analysis)."""
    global RULES
    if rule not in RULES:
        RULES = (*RULES, rule)


def run(model: ir.Model) -> list[Diagnostic]:
    rep = Reporter()
    for rule in RULES:
        try:
            rule(model, rep)
        except (Undecided, EvalError) as exc:
            # An unproven property is said, never passed over in silence.
            name = rule.__name__.removeprefix("check_").replace("_", " ")
            rep.warning("W309", f"the {name} check could not be completed: {exc}", None,
                        hint="the model may still violate it; simplify the expressions involved")
    return rep.sorted()
