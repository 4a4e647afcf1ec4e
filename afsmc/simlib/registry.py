"""Registry of small-scale simulators, referenced from specs as ``"<simulator>.<output>"``.

Simulators come only from the ``afsmc.simulators`` entry-point group (the built-in
UAV library is registered there too).  A reference is only ever a key into that
table: it is never imported, evaluated or used for attribute access, so a hostile
spec file cannot run code through it.
"""

from __future__ import annotations

import difflib
import functools
import re
import warnings
import zlib
from collections.abc import Callable, Iterable, Mapping
from dataclasses import dataclass
from importlib.metadata import entry_points
from types import MappingProxyType
from typing import Any

import numpy as np
import numpy.typing as npt

ENTRY_POINT_GROUP = "afsmc.simulators"
KINDS = frozenset({"duration", "battery", "probability"})
_NAME = re.compile(r"^[a-z][a-z0-9_]*(\.[a-z][a-z0-9_]*)*$")
_OUTPUT = re.compile(r"^[a-z][a-z0-9_]*$")

RunFn = Callable[[int, np.random.Generator], Mapping[str, npt.NDArray[Any]]]


@dataclass(frozen=True)
class Simulator:
    """One small-scale simulation model of an abstract action.

    `run(runs, rng)` returns one array of shape ``(runs,)`` per output: float seconds
    for "duration", float charge units (full battery = 100) for "battery", bool
    Bernoulli samples for "probability".
    """

    name: str
    description: str
    outputs: Mapping[str, str]
    run: RunFn

    def __post_init__(self) -> None:
        if not _NAME.match(self.name):
            raise ValueError(
                f"invalid simulator name {self.name!r} (dotted lower_case identifiers)"
            )
        if not self.outputs:
            raise ValueError(f"simulator {self.name!r} declares no outputs")
        for out, k in self.outputs.items():
            if not _OUTPUT.match(out):
                raise ValueError(f"simulator {self.name!r}: invalid output name {out!r}")
            if k not in KINDS:
                raise ValueError(
                    f"simulator {self.name!r}: output {out!r} has kind {k!r}, not one of {sorted(KINDS)}"
                )
        # Freeze the mapping so the registry's view cannot be mutated behind its back.
        object.__setattr__(self, "outputs", MappingProxyType(dict(self.outputs)))


class UnknownSimulator(LookupError):
    """A reference that names no registered simulator output."""


class BadOutput(ValueError):
    """A simulator returned what is not samples of its outputs: a missing output, a wrong
    shape, values that are not real numbers of the declared kind."""


def _builtin() -> tuple[Simulator, ...]:
    from afsmc.simlib.uav import SIMULATORS

    return SIMULATORS


def _collect(group: Iterable[tuple[str, object]]) -> dict[str, Simulator]:
    table: dict[str, Simulator] = {}
    for origin, items in group:
        if not isinstance(items, Iterable):
            warnings.warn(
                f"{ENTRY_POINT_GROUP} entry point {origin!r} is not iterable; ignored", stacklevel=3
            )
            continue
        for sim in items:
            if not isinstance(sim, Simulator):
                warnings.warn(
                    f"{origin!r} yielded {type(sim).__name__}, not a Simulator; ignored",
                    stacklevel=3,
                )
            elif sim.name in table:
                warnings.warn(
                    f"simulator {sim.name!r} from {origin!r} is already registered; ignored",
                    stacklevel=3,
                )
            else:
                table[sim.name] = sim
    return table


@functools.cache
def _registry() -> Mapping[str, tuple[Simulator, str]]:
    """The reference table "<simulator>.<output>" -> (simulator, output), loaded once."""
    loaded: list[tuple[str, object]] = []
    builtin_seen = False
    # Built-in first so a plugin cannot shadow a built-in name; sorted for a stable order.
    eps = sorted(
        entry_points(group=ENTRY_POINT_GROUP),
        key=lambda ep: (not ep.value.startswith("afsmc."), ep.name),
    )
    for ep in eps:
        try:
            obj = ep.load()
        except (Exception, SystemExit) as exc:  # a broken plugin must not take the compiler down
            warnings.warn(
                f"cannot load {ENTRY_POINT_GROUP} entry point {ep.name!r}: {exc}", stacklevel=2
            )
            continue
        builtin_seen |= ep.value.startswith("afsmc.simlib.")
        loaded.append((f"{ep.name} = {ep.value}", obj))
    if not builtin_seen:  # running from a source tree without installed metadata
        loaded.insert(0, ("afsmc.simlib.uav:SIMULATORS", _builtin()))
    table: dict[str, tuple[Simulator, str]] = {}
    for sim in _collect(loaded).values():
        for out in sim.outputs:
            table[f"{sim.name}.{out}"] = (sim, out)
    return MappingProxyType(table)


def reload() -> None:
    """Forget the cached registry and samples (e.g. after installing a plugin)."""
    _registry.cache_clear()
    _simulate.cache_clear()


def available() -> list[str]:
    """All references "<simulator>.<output>", sorted."""
    return sorted(_registry())


def simulators() -> list[Simulator]:
    """The registered simulators, sorted by name."""
    seen = {sim.name: sim for sim, _ in _registry().values()}
    return [seen[k] for k in sorted(seen)]


def lookup(ref: str) -> tuple[Simulator, str]:
    """Resolve a reference such as "uav.approach.duration" to (simulator, output)."""
    table = _registry()
    hit = table.get(ref) if isinstance(ref, str) else None
    if hit is None:
        close = difflib.get_close_matches(str(ref), list(table), n=3, cutoff=0.6)
        hint = f"; did you mean {', '.join(repr(c) for c in close)}?" if close else ""
        raise UnknownSimulator(f"unknown simulator output {ref!r}{hint}")
    return hit


def kind(ref: str) -> str:
    """The kind of a referenced output: "duration", "battery" or "probability"."""
    sim, out = lookup(ref)
    return sim.outputs[out]


def _stream(name: str, seed: int) -> np.random.Generator:
    # Per-simulator stream: adding or changing one simulator leaves the others' samples alone.
    return np.random.default_rng([seed, zlib.crc32(name.encode("utf-8"))])


@functools.lru_cache(maxsize=32)
def _simulate(name: str, runs: int, seed: int) -> Mapping[str, npt.NDArray[Any]]:
    sim, _ = next(v for v in _registry().values() if v[0].name == name)
    raw = sim.run(runs, _stream(name, seed))
    result: dict[str, npt.NDArray[Any]] = {}
    for out, k in sim.outputs.items():
        if out not in raw:
            raise BadOutput(f"simulator {name!r} returned no output {out!r}")
        arr = np.asarray(raw[out])
        if arr.shape != (runs,):
            raise BadOutput(
                f"simulator {name!r} output {out!r} has shape {arr.shape}, expected ({runs},)"
            )
        why = not_real(arr, k)
        if why is not None:
            raise BadOutput(f"simulator {name!r} output {out!r} {why}")
        arr = arr.astype(bool) if k == "probability" else arr.astype(np.float64)
        arr.setflags(write=False)  # cached: callers get copies
        result[out] = arr
    return MappingProxyType(result)


def not_real(arr: npt.NDArray[Any], kind: str) -> str | None:
    """Why `arr` is not samples of its kind ("holds complex numbers"), or None. A duration
    or a battery figure is an array of real numbers (integers or floats); a probability's
    samples are outcomes, booleans or numbers that are all 0 or 1. Nothing is cast: a
    complex number would lose its imaginary part, an object its meaning."""
    dtype = arr.dtype
    if dtype.kind == "c":
        return "holds complex numbers, not real ones"
    if dtype.kind not in "biuf":
        return f"holds values of type {dtype.name!r}, not numbers"
    if kind == "probability":
        if dtype.kind != "b" and not bool(np.all((arr == 0) | (arr == 1))):
            return "holds values other than 0 and 1 (True and False): a probability's " \
                "samples are outcomes"
    elif dtype.kind == "b":
        return f"holds booleans, not the numbers of a {kind} figure"
    return None


def simulate(name: str, runs: int, seed: int) -> dict[str, npt.NDArray[Any]]:
    """All outputs of simulator `name` for `runs` runs; deterministic for (name, runs, seed)."""
    if not any(sim.name == name for sim, _ in _registry().values()):
        raise UnknownSimulator(f"unknown simulator {name!r}")
    if runs < 1:
        raise ValueError("runs must be positive")
    return {k: v.copy() for k, v in _simulate(name, int(runs), int(seed)).items()}


def sample(ref: str, runs: int, seed: int) -> npt.NDArray[Any]:
    """`runs` samples of one output; deterministic for (ref, runs, seed).

    Outputs of the same simulator come from the same runs, so e.g. the duration and
    battery samples of "uav.approach" are paired.
    """
    sim, out = lookup(ref)
    return simulate(sim.name, runs, seed)[out]


def summary_rows(runs: int = 100_000, seed: int = 0) -> list[tuple[str, str, str, str, str]]:
    """(reference, kind, mean, std, hull-or-estimate) for every output, as in the docs table.

    For durations and battery the hull is the integer hull [floor(q2.5%), ceil(q97.5%)]
    of the central 95 % of the samples; for probabilities the estimate of P(true).
    """
    rows = []
    for ref in available():
        k = kind(ref)
        x = np.asarray(sample(ref, runs, seed), dtype=np.float64)
        if k == "probability":
            p = float(np.mean(x))
            rows.append((ref, k, f"{p:.4f}", f"{float(np.std(x)):.4f}", f"p = {p:.4f}"))
        else:
            lo, hi = np.quantile(x, [0.025, 0.975])
            hull = f"[{int(np.floor(lo))}, {int(np.ceil(hi))}]"
            rows.append((ref, k, f"{float(np.mean(x)):.3f}", f"{float(np.std(x)):.3f}", hull))
    return rows


def summary_table(runs: int = 100_000, seed: int = 0) -> str:
    """The docs/simulation.md table of every output (markdown)."""
    lines = [
        "| reference | kind | mean | std | central 95 % integer hull / estimate |",
        "|---|---|---:|---:|---|",
    ]
    lines += [f"| `{r}` | {k} | {m} | {s} | {h} |" for r, k, m, s, h in summary_rows(runs, seed)]
    return "\n".join(lines)
