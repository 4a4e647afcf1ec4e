"""One layering across the whole model, for arrays whose layers are many and tiny.

afsmc's explorer lays each bucket of the clock out in layers of its own and puts the
buckets one after the other (afsmc.verify.explorer.explore_graph.assemble). Where a
bucket holds a long chain (a variable that counts up while the clock stands still), each
of its states is a layer of its own, and the backward pass, which pays a fixed cost per
layer, takes far longer than the states warrant: a 701 x 701 grid gives 490,702 layers
for 491,402 states. The states of different buckets need not wait for each other, though:
a state's layer only has to come after its successors'. :func:`relayered` gives such a
model the shallowest layering (each state one layer above its highest successor, by
acyclic.layers_of) and renumbers its arrays to it, as the route from Storm's export does
(afsmc.verify.arrays.umb.arrange). A state's choices and branches keep their order, so
every value, optimal choice and path comes out the same.
"""

from __future__ import annotations

import numpy as np

from afsmc.verify.arrays import acyclic
from afsmc.verify.arrays.acyclic import Arrays

# Arrays with more layers than this, whose layers hold fewer states than MEAN_STATES on
# average, are layered again: below, the per-layer cost is small next to the rest.
MIN_LAYERS = 10_000
MEAN_STATES = 16


def tiny(a: Arrays) -> bool:
    """Whether `a`'s layers are many and tiny (see MIN_LAYERS)."""
    layers = len(a.layers) - 1
    return layers > MIN_LAYERS and (len(a.states) - 1) < MEAN_STATES * layers


def relayered(a: Arrays) -> Arrays | None:
    """`a` with the shallowest layering, its states renumbered to it (`order`, commands,
    labels, rewards, self-loops and the initial state with them); None if its layers do
    not come out fewer, or if it has Storm's packed labels (that route is layered by
    umb.arrange already)."""
    if a.packed:
        return None
    layers = acyclic.layers_of(a.states, a.choices, a.target)
    if layers is None or len(layers) >= len(a.layers) - 1:
        return None
    perm = np.concatenate(layers)
    bounds = np.zeros(len(layers) + 1, np.int64)
    np.cumsum([len(x) for x in layers], out=bounds[1:])
    del layers
    # the probabilities' codes gathered as they are, where they are codes (small integers,
    # exact in a float)
    coded = a.prob if isinstance(a.prob, acyclic.Coded) else None
    states, choices, old_choice, target, gathered, inv = acyclic.renumber(
        a.states, a.choices, a.target,
        np.asarray(a.prob if coded is None else coded.codes, np.float64), perm)
    prob: acyclic.Vec = gathered if coded is None else \
        acyclic.Coded(coded.table, gathered.astype(coded.codes.dtype))
    rewards = {name: acyclic.sparse_or_dense(len(old_choice),
                                             *_nonzero(acyclic.pick(v, old_choice)))
               for name, v in a.rewards.items()}
    return Arrays(states, choices, target, prob,
                  acyclic.self_loops(states, choices, target, prob), bounds,
                  int(inv[a.initial]), {k: v[perm] for k, v in a.labels.items()}, rewards,
                  order=None if a.order is None else a.order[perm],
                  actions=None if a.actions is None else a.actions[old_choice],
                  commands=None if a.commands is None else a.commands[old_choice],
                  action_names=a.action_names)


def _nonzero(values: acyclic.F64) -> tuple[acyclic.I64, acyclic.F64]:
    """The positions and values of the non-zero entries."""
    at = np.flatnonzero(values)
    return at, values[at]
