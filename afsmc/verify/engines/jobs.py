"""A Storm job for a lowered model: its PRISM or JANI text, the queries to ask, and the
engine; `choose_engine` settles "auto" for a model small enough to need no count."""

from __future__ import annotations

import importlib
from collections.abc import Sequence
from typing import Any

from afsmc.backends.prism import emit as prism_emit
from afsmc.backends.prism import property_variants
from afsmc.diagnostics import CompileError, Diagnostic, Severity, codes
from afsmc.lower.compose import action_agents
from afsmc.lower.lowering import Lowered
from afsmc.model import ir
from afsmc.text import count
from afsmc.verify.engines.guard import mem_available
from afsmc.verify.engines.storm import Engine, Job, Via

# Below this upper bound (modes × variable ranges) "auto" goes straight to the sparse
# engine. The bound overestimates reachable states by 10^3-10^4 on missions like the UAV,
# so such models are small; if one is not, the memory guard stops the build. Above it, a
# symbolic build counts the states first (a few seconds of fixed cost).
AUTO_SPARSE_BOUND = 1_000_000_000


def choose_engine(engine: Engine, bound: int) -> tuple[Engine, str]:
    """`auto` with a small upper bound is simply sparse; otherwise the job decides."""
    if engine == "auto" and bound <= AUTO_SPARSE_BOUND:
        return "sparse", (f"at most {count(bound)} states by the variables' ranges: few "
                          "enough for the sparse engine")
    return engine, ""



def unfair(how: str, hint: str) -> CompileError:
    """E404 for what min and max over fair schedulers are not computed with."""
    return CompileError([Diagnostic(
        codes.E404, Severity.ERROR, "min and max over fair schedulers ('compose interleaving "
        f"fair') are computed {how}", None, hint=hint)])


def make_job(low: Lowered, props: Sequence[ir.Property], via: Via, engine: Engine,
             max_states: int | None, what: str, bisimulation: bool = False,
             memory_budget: int | None = None, only: tuple[str, ...] | None = None,
             hybrid_skip: tuple[str, ...] = (),
             hybrid_extra: tuple[str, ...] = (), exact: bool = False) -> Job:
    """The Storm input for a lowered model whose `properties` are exactly `props`.
    `memory_budget`: what "auto" may give the sparse engine (default: 70% of free memory);
    `only`: check just these queries (property variants, e.g. `success_min`);
    `hybrid_skip`: queries "auto" leaves to another process if it picks hybrid;
    `hybrid_extra`: queries (of `low`'s properties) it checks only if it picks hybrid."""
    names = tuple(n for p in props for n, _ in property_variants(low, p)
                  if only is None or n in only)
    avail = mem_available()
    budget = memory_budget
    if budget is None:
        budget = int(avail * 0.7) if avail is not None else None
    skip, extra = (hybrid_skip, hybrid_extra) if engine == "auto" else ((), ())
    net = low.network
    if net is not None and net.ties == "fair":
        if engine not in ("auto", "sparse") or via != "prism" or exact:
            raise unfair("on the sparse engine via PRISM, in floating point",
                         "leave --engine and --via at their defaults, without --exact")
        out = prism_emit(low)
        return Job("prism", out.model, out.properties, names, "sparse", max_states, what,
                   False, budget, fair=tuple(sorted(action_agents(net).items())),
                   agents=len(net.parts))
    if via == "prism":
        out = prism_emit(low)
        return Job("prism", out.model, out.properties, names, engine, max_states, what,
                   bisimulation, budget, skip, extra)
    try:
        jani: Any = importlib.import_module("afsmc.backends.jani")
    except ImportError:
        raise CompileError([Diagnostic(codes.E408, Severity.ERROR,
                                       "the JANI backend (afsmc.backends.jani) is not available",
                                       None, hint="use --via prism")]) from None
    return Job("jani", jani.dumps(jani.emit(low)), "", names, engine, max_states, what,
               bisimulation, budget, skip, extra)
