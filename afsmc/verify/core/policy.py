"""A scheduler whole, for `afsmc simulate --strategy min:NAME|max:NAME`: Storm's choice
in every state the scheduler reaches where an interval constant is resolved, keyed by the
variables' values.

The MDP is the plain lowering (`lower(model, "nondet")`, no reductions), the one the
simulator runs, so a run's state is one of these valuations as it is.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

from afsmc.backends.prism import emit, property_variants
from afsmc.diagnostics import CompileError, Diagnostic, Severity, codes
from afsmc.lower.lowering import lower
from afsmc.model import ir
from afsmc.model.names import did_you_mean
from afsmc.model.semantics import bounded_globally
from afsmc.verify.engines.explicit import applies
from afsmc.verify.engines.guard import Progress, default_max_states, run_job, upper_bound
from afsmc.verify.engines.jobs import make_job
from afsmc.verify.outcome.strategy import DIRECTIONS, extract_for, has_choices, refuse, stepped
from afsmc.verify.plan.queries import dual


@dataclass(frozen=True)
class Policy:
    """The scheduler of `property`'s `direction` ("min"|"max"), whose value is `value`:
    in the state with values `states[i]` (of `variables`, "mode" among them) it takes the
    lowered command `commands[i]`."""

    property: str
    direction: str
    value: float
    variables: tuple[str, ...]
    states: tuple[tuple[int, ...], ...]
    commands: tuple[int, ...]


def parse(text: str) -> tuple[str, str]:
    """`min:NAME` -> ("min", "NAME"); E415 otherwise."""
    direction, sep, name = text.partition(":")
    if not sep or direction not in DIRECTIONS or not name:
        raise refuse(f"--strategy {text!r}: expected min:NAME or max:NAME (a property's "
                     "min or max strategy)")
    return direction, name


def extract(model: ir.Model, text: str, *, max_states: int | None = None,
            progress: Progress | None = None) -> Policy:
    """The scheduler `text` (min:NAME or max:NAME) of the loaded model, from Storm."""
    direction, name = parse(text)
    if not has_choices(model):
        raise refuse(f"--strategy {text}: {model.source.path} has no interval constants: its "
                     "model is a DTMC, which has no choices for a strategy to make",
                     hint="simulate it without --strategy")
    prop = next((p for p in model.properties if p.name == name), None)
    if prop is None:
        names = [p.name for p in model.properties]
        raise CompileError([Diagnostic(
            codes.E407, Severity.ERROR, f"--strategy {text}: no property named '{name}' in "
            f"{model.source.path}", None, hint=did_you_mean(name, names) or (
                "properties: " + ", ".join(names) if names else None))])
    if prop.opt and prop.opt != direction:
        raise refuse(f"--strategy {text}: property '{name}' asks for P{prop.opt} only",
                     hint=f"use {prop.opt}:{name}")
    if stepped(prop):
        raise refuse(f"--strategy {text}: property '{name}' is step-bounded: its strategies "
                     "count the steps, and Storm gives no scheduler for them",
                     hint="choose a property without a step bound")
    asked, opt = prop, direction
    if bounded_globally(prop):  # asked as 1 - its dual, whose min is the property's max
        asked, opt = dual(prop), {"min": "max", "max": "min"}[direction]
    low = lower(dataclasses.replace(model, properties=(asked,)), "nondet")
    query = next(n for n, o in property_variants(low, asked) if o == opt)
    limit = default_max_states() if max_states is None else max_states
    job = make_job(low, [asked], "prism", "sparse", limit, "MDP", only=(query,))
    job = dataclasses.replace(job, extract=extract_for(low, (), query, None),
                              model_text=emit(low, variant_labels=True).model,
                              explicit=low if applies(low, "sparse", "auto", False) else None)
    res = run_job(job, upper_bound(model), isolate=None, progress=progress)
    if res.failure is not None or res.extracted is None or query not in res.values:
        why = res.failure.message if res.failure is not None else "Storm returned no scheduler"
        raise CompileError([Diagnostic(codes.E416, Severity.ERROR,
                                       f"--strategy {text}: Storm's sparse check of the MDP "
                                       f"failed: {why}", None)])
    value = res.values[query]
    if asked is not prop:
        value = 1.0 - value
    x = res.extracted
    return Policy(name, direction, value, x.variables, tuple(x.policy_states),
                  tuple(x.policy_commands))
