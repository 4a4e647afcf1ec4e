"""Run one check rule on a resolved model, without the other rules."""

from __future__ import annotations

from afsmc.check import RULES, Rule
from afsmc.compiler import load
from afsmc.diagnostics import Diagnostic, Reporter


def run_rule(rule: Rule, text: str) -> list[Diagnostic]:
    """The diagnostics `rule` reports on the model of `text` (resolved, not checked)."""
    assert rule in RULES, f"{rule.__name__} is not one of afsmc.check.RULES"
    model = load("spec.afsm", text=text, run_checks=False).model
    rep = Reporter()
    rule(model, rep)
    return rep.sorted()


def codes(rule: Rule, text: str) -> list[str]:
    return [d.code for d in run_rule(rule, text)]


def line_of(d: Diagnostic, text: str) -> int:
    """The 1-based line of the diagnostic's span in `text`."""
    assert d.span is not None
    return text.count("\n", 0, d.span.start) + 1
