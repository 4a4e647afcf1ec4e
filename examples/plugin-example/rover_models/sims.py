"""The simulators this plugin registers: the entry point `rover_models.sims:SIMULATORS`.

A simulator is plain Python that afsmc runs in a child process (under a time and memory
limit) when `afsmc sim-check` judges a constant that names one of its outputs.
"""

from __future__ import annotations

from typing import Any

import numpy as np
import numpy.typing as npt

from afsmc.simlib import Simulator

CELL = 2.0  # m
SPEED = 0.18  # m/s on flat ground
STUCK = 0.01  # per cell: the rover bogs down and must be recovered


def _drive(runs: int, rng: np.random.Generator) -> dict[str, npt.NDArray[Any]]:
    """One cell of driving per run. All randomness comes from `rng`, so a run of
    sim-check is reproducible for its (runs, seed)."""
    slope = rng.uniform(0.0, 0.25, runs)  # the terrain's grade
    speed = SPEED * (1.0 - slope) * rng.lognormal(0.0, 0.05, runs)
    duration = CELL / speed  # s
    battery = 0.02 * duration * (1.0 + 2.0 * slope)  # % of a full battery
    stuck = rng.random(runs) < STUCK * (1.0 + 4.0 * slope)
    return {"duration": duration, "battery": battery, "stuck": stuck}


SIMULATORS = (
    Simulator(
        name="rover.drive",  # dotted lower-case identifiers
        description="A rover drives one 2 m cell of rough ground.",
        outputs={"duration": "duration", "battery": "battery", "stuck": "probability"},
        run=_drive,  # (runs, rng) -> one array of shape (runs,) per output
    ),
)
