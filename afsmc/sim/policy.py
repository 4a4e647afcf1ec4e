"""Runs under a given strategy (`afsmc simulate --strategy`): in a state where an
interval constant is resolved, the run takes the command a table names for that state.

The table (from `afsmc.verify.core.policy`) lists states as values of variables ("mode" among
them) and a lowered command per state. Each state is encoded as one integer (its values
over the variables' ranges, mixed radix), so that the runs of a batch look theirs up at
once with a binary search.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import numpy.typing as npt

from afsmc.model import ir


@dataclass(frozen=True)
class Table:
    """The strategy as plain data; `key` names it (the property and direction), so that a
    worker's compiled program is reused for its batches."""

    key: str
    variables: tuple[str, ...]
    states: tuple[tuple[int, ...], ...] = field(compare=False, hash=False)
    commands: tuple[int, ...] = field(compare=False, hash=False)


class Lookup:
    """The table compiled: `command(state, idx)` gives each run's command (-1: none)."""

    def __init__(self, table: Table, model: ir.Model) -> None:
        ranges: list[tuple[int, int]] = []
        for v in table.variables:
            if v == "mode":
                numbers = [m.number for m in model.modes]
                ranges.append((min(numbers), max(numbers)))
            else:
                var = model.variable(v)
                ranges.append((0, 1) if var.type.name == "BOOL" else (int(var.lo), int(var.hi)))
        self.variables = table.variables
        self.lows = [lo for lo, _ in ranges]
        self.radix = [hi - lo + 1 for lo, hi in ranges]
        states = np.array(table.states, dtype=np.int64).reshape(len(table.states),
                                                                  len(table.variables))
        keys = self._encode([states[:, i] for i in range(len(table.variables))])
        order = np.argsort(keys, kind="stable")
        self.keys = keys[order]
        self.commands = np.array(table.commands, dtype=np.int64)[order]

    def _encode(self, cols: Sequence[npt.NDArray[Any]]) -> npt.NDArray[np.int64]:
        key = np.zeros(len(cols[0]) if cols else 0, dtype=np.int64)
        for col, lo, r in zip(cols, self.lows, self.radix, strict=True):
            key = key * r + (np.asarray(col, dtype=np.int64) - lo)
        return key

    def command(self, state: Mapping[str, npt.NDArray[Any]], mode: int,
                idx: npt.NDArray[np.intp] | None, size: int) -> npt.NDArray[np.int64]:
        """The strategy's command for each run (all, or those of `idx`), in mode `mode`."""
        n = size if idx is None else len(idx)
        cols = [np.full(n, mode, dtype=np.int64) if v == "mode" else
                (state[v] if idx is None else state[v][idx]) for v in self.variables]
        key = self._encode(cols)
        if len(self.keys) == 0:
            return np.full(n, -1, dtype=np.int64)
        pos = np.minimum(np.searchsorted(self.keys, key), len(self.keys) - 1)
        return np.where(self.keys[pos] == key, self.commands[pos], -1)
