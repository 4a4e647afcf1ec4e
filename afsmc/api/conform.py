"""`Conformance`: a mission's logged runs (the robot's, or `simulate --traces-out x.jsonl`)
checked against its spec: every step the spec does not allow (E720), and every
probability and interval constant the steps exercise estimated and judged by sim-check's
rules (drifted: E721); `afsmc conform` runs through :func:`conform_file`.
"""

from __future__ import annotations

import os
from collections.abc import Mapping
from dataclasses import dataclass, field

from afsmc.api.errors import AfsmError
from afsmc.api.sim_check import load_sourced, update_constants
from afsmc.conform import estimate, logs, replay
from afsmc.controllers.layout import refuse_composed
from afsmc.diagnostics import CompileError, Diagnostic, Severity, codes
from afsmc.sim.evidence import Evidence


@dataclass(frozen=True)
class Conformance:
    """``violations`` (E720, one per step the spec does not allow, at its log line),
    ``evidence`` (one :class:`afsmc.sim.evidence.Evidence` per estimated constant),
    ``errors`` (E721 drifted, E508 drifted with no value its rule accepts), ``unexercised``
    (constants the logs could estimate but do not exercise), ``updated`` (constants
    `update` rewrote), ``ambiguous`` (steps whose changes fit several outcomes, not
    counted as evidence of which)."""

    path: str
    logs: tuple[str, ...]
    runs: int
    steps: int
    violations: list[Diagnostic]
    evidence: list[Evidence]
    errors: list[Diagnostic] = field(default_factory=list)
    unexercised: list[str] = field(default_factory=list)
    updated: list[Evidence] = field(default_factory=list)
    ambiguous: int = 0

    @property
    def ok(self) -> bool:
        """No violation and no drift (or each drifted constant updated): exit 0."""
        return not self.violations and not self.errors

    @property
    def diagnostics(self) -> list[Diagnostic]:
        return self.violations + self.errors

    def to_json(self) -> dict[str, object]:
        """The object `afsmc conform --json` prints (schema: `afsmc schema conform`)."""
        return {"file": self.path, "logs": list(self.logs), "runs": self.runs,
                "steps": self.steps, "ambiguous": self.ambiguous,
                "violations": [d.to_json() for d in self.violations],
                "constants": [e.to_json() for e in self.evidence],
                "unexercised": self.unexercised,
                "updated": [e.name for e in self.updated],
                "diagnostics": [d.to_json() for d in self.errors]}


def origin(paths: list[str]) -> str:
    """The logs, as the evidence and a provenance comment name them."""
    names = [os.path.basename(p) for p in paths]
    shown = ", ".join(names[:3]) + (f" and {len(names) - 3} more" if len(names) > 3 else "")
    return f"logs {shown}"


def conform_file(path: str, consts: Mapping[str, str], log_paths: list[str], *,
                 update: bool = False, confidence: float | None = None,
                 text: str | None = None) -> Conformance:
    """Replay the logs against the mission at `path` and judge its constants by them.
    `update` rewrites each drifted constant in the file with a provenance comment (as
    `sim-check --update` does), if the new text checks. Violations and drifts are results;
    raises AfsmError for the file's errors, a composed mission (E701) and bad logs
    (E710-E713, every one, each at its line). `text`: the mission's source (default: the
    file, as it is on disk; always so for `update`)."""
    if update:
        try:
            with open(path, encoding="utf-8", newline="") as f:
                text = f.read()  # newline="": an update keeps every other byte
        except (OSError, UnicodeDecodeError):
            text = None  # loading reports it (E001)
    checked = load_sourced(path, consts, text, lambda _: None)
    model = checked.model
    try:
        refuse_composed(model, "'conform' replays the logs of one machine")
    except CompileError as exc:
        raise AfsmError.of(exc) from None
    bad: list[Diagnostic] = []  # the logs' errors, found as the steps are replayed
    result = replay.Checker(model).replay(logs.read(log_paths, bad))
    if bad or result.errors:  # every bad line, those that parse but name unknown things too
        raise AfsmError(sorted([*bad, *result.errors], key=Diagnostic.sort_key)[:logs.MAX_ERRORS])
    evidence, idle = estimate.judged(model, result.trials, origin(log_paths), confidence)
    drifted = [e for e in evidence if not e.consistent]
    by_name = {c.name: c for c in model.constants}
    unfit = [Diagnostic(
        codes.E508, Severity.ERROR,
        f"constant '{e.name}' has drifted from the {e.ref} (mean {e.mean:.4g}), and no "
        f"{by_name[e.name].type.value} fits the rule: it accepts {e.accept}",
        by_name[e.name].span) for e in drifted if not e.fits]
    drifted = [e for e in drifted if e.fits]
    updated: list[Evidence] = []
    # a param is the scenario's, given with --const: its default is not rewritten
    fixable = [e for e in drifted if not by_name[e.name].is_param]
    if update and fixable:
        if text is None:
            text = checked.model.source.text
        update_constants(path, consts, text, fixable, by_name)
        updated = fixable
    errors = unfit + [Diagnostic(
        codes.E721, Severity.ERROR,
        f"{'param' if by_name[e.name].is_param else 'constant'} '{e.name}' = {e.declared} "
        f"has drifted from the {e.ref} (mean {e.mean:.4g} over {e.runs:,} trials; the rule "
        f"accepts {e.accept})", by_name[e.name].span,
        hint=f"the logs suggest {e.suggestion}; " + (
            "a param is not rewritten: give --const or change its default"
            if by_name[e.name].is_param else "`afsmc conform --update` rewrites it"))
        for e in drifted if e not in updated]
    return Conformance(path, tuple(log_paths), result.runs, result.steps, result.violations,
                       evidence, errors, idle, updated, result.ambiguous)
