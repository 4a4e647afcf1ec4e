"""How to verify: one frozen `VerifyOptions`, the options of `afsmc verify` that change what
is computed or how, passed whole from the front-ends (the command line, the Python API,
sweeps) to `run` and `check` and on to the engines."""

from __future__ import annotations

import typing
from dataclasses import dataclass, fields
from typing import Any

from afsmc.lower.reduce import Reductions
from afsmc.verify.engines.storm import Engine, Via
from afsmc.verify.engines.storm_solvers import Solver


def check_choice(option: str, value: object, allowed: object) -> None:
    """The API's Literal options, checked: a misspelt engine or via ran as sparse/PRISM."""
    names = typing.get_args(allowed)
    if value not in names:
        raise ValueError(f"{option} must be one of " + ", ".join(map(repr, names))
                         + f"; got {value!r}")


@dataclass(frozen=True)
class VerifyOptions:
    """Every option of a verification (docs/verification.md has each in its section).

    `via`: Storm's input language; `engine`: Storm's engine ("auto" picks); `solver`: how
    the equations are solved; `max_states`: stop above this many states (None: what the
    free memory holds, for the sparse engine); `memory_budget`: bytes "auto" may give the
    sparse engine (None: 70% of the free memory); `uniform`: also the uniform resolution
    of the interval constants; `isolate`: Storm in a watched child process (None: when
    the model may be large); `reductions`: afsmc's exact reductions (None: all);
    `bisimulation`: minimise the sparse model; `split`: one Storm process per query;
    `precision`: sound mode, every value within it (None: a requirement's default, else
    Storm's own stopping rule); `exact`: rational arithmetic; `strategy`: the min and max
    strategies in mission terms; `witness`: the K most probable paths of one query
    (query name or None for the only property, K); `witness_dir`, `witness_target`: whose
    strategy the paths follow ("min"/"max"), and into which target; `scratch`: a directory
    whose disk holds afsmc's own exploration, layer by layer, so that its memory is that of
    a window of layers (afsmc.verify.stream; None: the system temp directory, taken only
    once the in-memory exploration would not fit comfortably); `no_scratch`: in memory
    always (not with `scratch`, E419).

    A misspelt `via`, `engine` or `solver` is a ValueError when the options are made."""

    via: Via = "prism"
    engine: Engine = "sparse"
    solver: Solver = "auto"
    max_states: int | None = None
    memory_budget: int | None = None
    uniform: bool = True
    isolate: bool | None = None
    reductions: Reductions | None = None
    bisimulation: bool = False
    split: bool = False
    precision: float | None = None
    exact: bool = False
    strategy: bool = False
    witness: tuple[str | None, int] | None = None
    witness_dir: str | None = None
    witness_target: str | None = None
    scratch: str | None = None
    no_scratch: bool = False

    def __post_init__(self) -> None:
        check_choice("via", self.via, Via)
        check_choice("engine", self.engine, Engine)
        check_choice("solver", self.solver, Solver)

    @classmethod
    def of(cls, options: VerifyOptions | None, values: dict[str, Any]) -> VerifyOptions:
        """`options`, or the options named in `values` (the keyword arguments of `run`
        and `sweep`); a TypeError names an unknown one."""
        if options is not None and values:
            raise TypeError("give either options=VerifyOptions(...) or keyword options, "
                            "not both: " + ", ".join(sorted(values)))
        if options is not None:
            return options
        known = {f.name for f in fields(cls)}
        unknown = sorted(set(values) - known)
        if unknown:
            raise TypeError("unknown verification option(s): " + ", ".join(unknown)
                            + "; the options are " + ", ".join(sorted(known)))
        return cls(**values)
