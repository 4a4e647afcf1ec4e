"""A property's value at fixed parameter values, from an ordinary (numeric) Storm model
built afresh: the oracle the parametric results are held to."""

from __future__ import annotations

import dataclasses
import os
import tempfile
from collections.abc import Mapping

from afsmc.backends.prism import emit
from afsmc.compiler import lowered
from afsmc.model import ir


def at(model: ir.Model, values: Mapping[str, float]) -> ir.Model:
    """`model` with the constants `values` fixed (interval probabilities included)."""
    consts = tuple(dataclasses.replace(c, value=float(values[c.name]), prob_interval=None)
                   if c.name in values else c for c in model.constants)
    return dataclasses.replace(model, constants=consts)


def value(model: ir.Model, values: Mapping[str, float], formula: str) -> float:
    """`formula` (PRISM syntax on the generated model) at the fixed `values`."""
    import stormpy

    low = lowered(at(model, values), "nondet")
    with tempfile.TemporaryDirectory() as tmp:
        path = os.path.join(tmp, "m.prism")
        with open(path, "w", encoding="utf-8") as f:
            f.write(emit(low).model)
        prog = stormpy.parse_prism_program(path)
    props = stormpy.parse_properties(formula, prog)
    m = stormpy.build_model(prog, props)
    return float(stormpy.model_checking(m, props[0]).get_value(m.initial_states[0]))
