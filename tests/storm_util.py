"""Build and check our PRISM output with Storm (stormpy): the oracle most tests use."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import stormpy

from afsmc.backends.prism import emit
from afsmc.lower.lowering import Lowered


def storm_prism(low: Lowered, tmp: Path, name: str = "model") -> tuple[Any, dict[str, float]]:
    """(built sparse model, {property name: value at the initial state})."""
    out = emit(low)
    path = tmp / f"{name}.prism"
    path.write_text(out.model)
    prog = stormpy.parse_prism_program(str(path))
    props = stormpy.parse_properties(out.properties.replace("\n", " "), prog) if out.properties else []
    model = stormpy.build_model(prog, props) if props else stormpy.build_model(prog)
    init = model.initial_states[0]
    values = {p.get_name(): float(stormpy.model_checking(model, p).get_value(init)) for p in props}
    return model, values
