"""The causes of reachability properties by afsmc's own exploration and backward pass.

The model is the one :mod:`afsmc.report.causes` instruments (a cause variable per
property). afsmc's explorer builds it once for every property (as verify's own route
builds a mission whose clock only grows); for each property and each scheduler (min,
max, or a DTMC's only one) one backward pass gives the whole property's value and its
optimal choices (the first optimal choice of each state, as Storm's topological solver
keeps it), all properties and schedulers side by side; one more pass gives every cause's
part, each under its property's scheduler. Exact as verify's pass is: the parts add up to the whole to the last bits.

Where the explorer does not apply (a cycle, a step bound or `U`, a composed mission...)
the caller falls back to Storm (:func:`afsmc.report.causes._storm`).
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Literal

import numpy as np

from afsmc.diagnostics import CompileError, Diagnostic, Severity, codes
from afsmc.lower.lowering import Lowered
from afsmc.model import expr as E
from afsmc.sim.compile import SimError
from afsmc.verify.arrays import acyclic
from afsmc.verify.arrays.acyclic import LABEL
from afsmc.verify.engines import explicit, strategy_arrays
from afsmc.verify.engines.strategy_storm import Extract, Extracted
from afsmc.verify.explorer import explore, explore_graph

Under = Literal["min", "max", "value"]
# per property: each scheduler's (whole value, each part's value), and the paths into
# the largest part under the last scheduler (when asked)
Split = tuple[dict[Under, tuple[float, list[float]]], Extracted | None]


def explored(inst: Lowered, wholes: Sequence[E.Expr], causes: Sequence[tuple[str, list[int]]],
             opts: Sequence[Under], paths: int = 0, extract: Extract | None = None,
             max_bytes: int | None = None, max_states: int | None = None
             ) -> list[Split] | None:
    """Each property's whole target `wholes[i]` and its causes (`causes[i]`: the cause
    variable and the value of each part) on the instrumented model `inst`, under each
    scheduler of `opts`; None if afsmc's explorer does not take the model (Storm then
    does). With `paths` (and `extract`, the commands' labels), the most probable paths
    into the largest part under the last scheduler, as verify's `--witness` finds them.
    Raises CompileError (E417) when the model's arrays outgrow `max_bytes` or it has
    more than `max_states` states."""
    try:
        compiled = explore.compile_model(inst, list(wholes), [], extract is not None)
        found = explore_graph.explore(compiled, None, max_states, max_bytes)
    except (explore.GiveUp, SimError):
        return None
    except explore.TooManyStates as exc:
        room = f"the {max_bytes / 2**30:.1f} GB set aside for it hold" \
            if max_bytes is not None else f"--max-states {max_states:,}"
        raise CompileError([Diagnostic(
            codes.E417, Severity.ERROR,
            f"the causes are not split: their model (the mission with a cause variable per "
            f"property) has {'at least ' if exc.partial else ''}{exc.states:,} states, more "
            f"than {room}", None)]) from None
    a = found.arrays
    if a.order is None or any(var not in compiled.layout.fields for var, _ in causes):
        return None
    # every property's schedulers in one pass
    wanted = [(i, u) for i in range(len(wholes)) for u in opts]
    totals, best = acyclic.schedulers(a, [_query(f"{i}{u}", "" if u == "value" else u, i)
                                          for i, u in wanted])
    # each part's target: the states of the whole target with the cause's value; a part
    # no explored state is in (most: a cause numbered for a branch that never enters the
    # target) has probability 0, exactly, and stays out of the pass
    parts: dict[tuple[int, int], int] = {}  # (property, part) -> its label's number
    for i, (var, numbers) in enumerate(causes):
        field = compiled.layout.fields[var]
        inside = a.labels[LABEL + str(i)]
        value = np.full(len(inside), -1, np.int64)
        at = np.flatnonzero(inside)
        value[at] = compiled.layout.decode(a.order[at])[var] if field.size > 1 else field.lo
        for j, k in enumerate(numbers):
            label = value == k
            if label.any():
                parts[(i, j)] = len(a.labels)
                a.labels[LABEL + str(parts[(i, j)])] = label
    asked = [(w, parts[(i, j)]) for w, (i, _) in enumerate(wanted)
             for j in range(len(causes[i][1])) if (i, j) in parts]
    policy = acyclic.Policy(best, np.asarray([w for w, _ in asked], np.int64))
    values = acyclic.evaluate(a, [_query(str(n), "", t) for n, (_, t) in enumerate(asked)],
                              policy) if asked else []
    got = dict(zip(asked, values, strict=True))
    out: list[Split] = []
    for i, (_, numbers) in enumerate(causes):
        shares: dict[Under, tuple[float, list[float]]] = {}
        traced: Extracted | None = None
        for u in opts:
            w = wanted.index((i, u))
            own = [got[(w, parts[(i, j)])] if (i, j) in parts else 0.0
                   for j in range(len(numbers))]
            shares[u] = (totals[w], own)
            if paths and extract is not None and u == opts[-1] and any(own):
                largest = int(np.argmax(own))
                traced = _traced(a, acyclic.Policy(best, np.asarray([w], np.int64)), inst,
                                 compiled.layout, extract, parts[(i, largest)], paths)
        out.append((shares, traced))
    return out


def _query(name: str, opt: Literal["min", "max", ""], target: int) -> acyclic.Query:
    return acyclic.Query(name, "P", opt, target, "")


def _traced(a: acyclic.Arrays, policy: acyclic.Policy, inst: Lowered, layout: explore.Layout,
            extract: Extract, target: int, k: int) -> Extracted:
    """The `k` most probable paths under the scheduler `policy` into the target states
    of `target` (a part's label), as verify's `--witness` finds them."""
    out = Extracted()
    _, chosen, reach = acyclic.under(a, _query("part", "", target), policy)
    strategy_arrays.paths_into(a, chosen, reach > 0, a.labels[LABEL + str(target)],
                               explicit.view(a, inst, layout, extract), k, out)
    return out
