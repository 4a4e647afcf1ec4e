"""What changed since a baseline: an earlier `afsmc verify --json` against this run's.

For each property in either, its old and new bounds (min, max, value) and verdict.
A row is flagged where the verdict flips, or where a bound moved by more than the
tolerance (absolute). A flip is *worse* when the new verdict is further from `holds`
(holds > depends, undecided > fails): `verify --baseline` exits 1 on one, for CI.
Nothing is judged here: the verdicts are those of the two runs.
"""

from __future__ import annotations

import json
import math
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from typing import Any

from afsmc.diagnostics import CompileError, Diagnostic, Severity, codes

BOUNDS = ("min", "max", "value")
# how near each verdict is to `holds`; a flip to a lower rank is worse
RANK = {"holds": 3, "depends": 2, "undecided": 2, "fails": 1}


def _fail(message: str, hint: str = "pass the output of `afsmc verify --json`") -> CompileError:
    return CompileError([Diagnostic(codes.E418, Severity.ERROR, message, None, hint=hint)])


@dataclass(frozen=True)
class Change:
    """One property, before and after: `old` / `new` its bounds (None: absent there)."""

    name: str
    old: dict[str, float | None]
    new: dict[str, float | None]
    old_verdict: str | None
    new_verdict: str | None
    moved: float  # the largest change of a bound given in both (inf: one became infinite)
    flipped: bool
    worse: bool
    flagged: bool
    only: str = ""  # "old" | "new": the property is in one run only

    def to_json(self) -> dict[str, object]:
        def bounds(b: dict[str, float | None]) -> dict[str, float | None]:
            return {k: v if v is None or math.isfinite(v) else None for k, v in b.items()}

        out: dict[str, object] = {
            "name": self.name, "old": bounds(self.old), "new": bounds(self.new),
            "old_verdict": self.old_verdict, "new_verdict": self.new_verdict,
            "moved": self.moved if math.isfinite(self.moved) else None,
            "flipped": self.flipped, "worse": self.worse, "flagged": self.flagged}
        if self.only:
            out["only_in"] = self.only
        return out


@dataclass(frozen=True)
class Comparison:
    baseline: str  # where the old results come from
    tolerance: float
    changes: list[Change] = field(default_factory=list)

    @property
    def worse(self) -> list[Change]:
        return [c for c in self.changes if c.worse]

    @property
    def flagged(self) -> list[Change]:
        return [c for c in self.changes if c.flagged]

    def to_json(self) -> dict[str, object]:
        return {"baseline": self.baseline, "tolerance": self.tolerance,
                "changes": [c.to_json() for c in self.changes]}


def shown(b: Mapping[str, float | None], fmt: Callable[[float | None], str]) -> str:
    """A property's bounds in a run: its value, or min – max, or "-" if it has none."""
    if b["value"] is not None:
        return fmt(b["value"])
    if b["min"] is None and b["max"] is None:
        return "-"
    return f"{fmt(b['min'])} – {fmt(b['max'])}"


def read(path: str, machine: str) -> dict[str, Any]:
    """The `afsmc verify --json` object in `path`, of machine `machine`; E418 otherwise."""
    try:
        with open(path, encoding="utf-8") as f:
            data = json.load(f)
    except OSError as exc:
        raise _fail(f"cannot read {path}: {exc.strerror or exc}") from None
    except (json.JSONDecodeError, UnicodeDecodeError) as exc:
        raise _fail(f"{path} is not JSON: {exc}") from None
    if not isinstance(data, dict) or not isinstance(data.get("properties"), list) or not all(
            isinstance(e, dict) and isinstance(e.get("name"), str) for e in data["properties"]):
        raise _fail(f"{path}: expected an object with a \"properties\" list of named results")
    if "points" in data or "runs" in data:
        raise _fail(f"{path} is not the output of `afsmc verify --json` (of sweep or "
                    "simulate?): a baseline is one result per property")
    if data.get("machine") not in (None, machine):
        raise _fail(f"{path} holds the results of machine {data.get('machine')}, not "
                    f"{machine}", hint=f"compare with an earlier run of machine {machine}")
    return data


def _bounds(entry: Mapping[str, Any] | None) -> dict[str, float | None]:
    if entry is None:
        return {k: None for k in BOUNDS}
    inf = entry.get("infinite") or []
    out: dict[str, float | None] = {}
    for k in BOUNDS:
        v = entry.get(k)
        out[k] = math.inf if k in inf else (float(v) if isinstance(v, (int, float))
                                            and not isinstance(v, bool) else None)
    return out


def _moved(a: dict[str, float | None], b: dict[str, float | None]) -> float:
    most = 0.0
    for k in BOUNDS:
        x, y = a[k], b[k]
        if x is None or y is None:
            continue
        if x == y:
            continue
        most = max(most, abs(x - y) if math.isfinite(x) and math.isfinite(y) else math.inf)
    return most


def compare(old: Mapping[str, Any], new: Mapping[str, Any], tolerance: float = 0.0,
            baseline: str = "") -> Comparison:
    """Each property of `old` and `new` (two `afsmc verify --json` objects), in the new
    run's order, then those only in the old one."""
    olds = {e["name"]: e for e in old["properties"]}
    news = {e["name"]: e for e in new["properties"]}
    changes = []
    for name in [*news, *[n for n in olds if n not in news]]:
        o, n = olds.get(name), news.get(name)
        ov = o.get("verdict") if o else None
        nv = n.get("verdict") if n else None
        ob, nb = _bounds(o), _bounds(n)
        moved = _moved(ob, nb)
        flipped = o is not None and n is not None and ov != nv
        worse = flipped and RANK.get(str(nv), 0) < RANK.get(str(ov), 0)
        only = "old" if n is None else "new" if o is None else ""
        changes.append(Change(name, ob, nb, ov, nv, moved, flipped, worse,
                              flipped or moved > tolerance or bool(only), only))
    return Comparison(baseline, tolerance, changes)
