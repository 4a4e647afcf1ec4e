"""Semantic checks of a resolved model, one rule per module.

Each rule is a small function `(model, reporter) -> None` that reports every problem it
finds; `run` applies them all, so an author sees every error of a file at once.
"""

from __future__ import annotations

from collections.abc import Callable

from afsmc.check import distributions, modegraph, ranges, unused, weights
from afsmc.diagnostics import Diagnostic, Reporter
from afsmc.model import ir
from afsmc.sim.check_sources import check_sim_sources

Rule = Callable[[ir.Model, Reporter], None]

RULES: tuple[Rule, ...] = (
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
        rule(model, rep)
    return rep.sorted()
