"""Reading the robot's logs (docs/robot.md, "The log format"): JSON Lines, one object per
step, or CSV with the same columns (a file whose name ends in .csv).

A step: `mode` (the mode the step starts in) and `action` (the action or preemptive
hazard taken), both required; `outcome` (an index into the action's outcomes, 0 for the
first written, or a hazard's name) or `changes` (the variables the step changed, by name,
`mode` among them when it changed), at least one; `duration` (the measured value of the
interval constant the outcome's updates read, a number; {NAME: number} for several);
`run` (steps of one run share it, within one file; a file without it is one run) and
`step` (any number, for people). Every error is collected, each at its file and line:
E710 a file that cannot be read, E711 a line that is not a step (not JSON, not an object,
a truncated line, a CSV row whose cells do not match the header), E712 a missing field or
a value of the wrong kind.
"""

from __future__ import annotations

import csv
import json
import math
from collections.abc import Iterator
from dataclasses import dataclass
from typing import Any

from afsmc.diagnostics import Diagnostic, Severity, Source, Span, codes

Number = int | float
Duration = Number | dict[str, Number] | None
COLUMNS = ("run", "step", "mode", "action", "outcome", "duration", "changes")
MAX_ERRORS = 100  # a file of garbage is said in this many errors, not in one per line


@dataclass(frozen=True)
class Step:
    span: Span  # the step's line in its log
    run: str  # "" when the log has no run field (the file is one run)
    mode: str
    action: str
    outcome: int | str | None
    changes: dict[str, Any] | None
    duration: Duration

    def field_span(self, key: str) -> Span:
        """Where `key` stands on the step's line (the whole line if it cannot be found)."""
        src, line = self.span.source, self.span.line
        text = src.line(line)
        at = text.find(f'"{key}"')
        if at < 0:
            return self.span
        return Span.at_position(src, line, at + 1, line, at + len(key) + 3)


def read(paths: list[str], errors: list[Diagnostic]) -> Iterator[Step]:
    """Every step of the logs that reads, in order, one file in memory at a time; every
    error found is appended to `errors` (at most MAX_ERRORS)."""
    for path in paths:
        if len(errors) >= MAX_ERRORS:
            return
        try:
            with open(path, encoding="utf-8", newline="") as f:
                text = f.read()
        except (OSError, UnicodeDecodeError) as exc:
            why = exc.strerror if isinstance(exc, OSError) and exc.strerror else str(exc)
            errors.append(Diagnostic(codes.E710, Severity.ERROR,
                                     f"cannot read log {path}: {why}", None))
            continue
        source = Source(path, text)
        parse = _csv if path.lower().endswith(".csv") else _jsonl
        yield from parse(source, errors)


def _line_span(source: Source, line: int) -> Span:
    return Span.at_position(source, line, 1, line, max(1, source.line_length(line)) + 1)


def _error(errors: list[Diagnostic], code: str, span: Span, message: str,
           hint: str | None = None) -> None:
    errors.append(Diagnostic(code, Severity.ERROR, message, span, hint=hint))


def _jsonl(source: Source, errors: list[Diagnostic]) -> Iterator[Step]:
    for i, raw in enumerate(source.text.split("\n"), 1):
        if not raw.strip() or len(errors) >= MAX_ERRORS:
            continue
        span = _line_span(source, i)
        try:
            obj = json.loads(raw)
        except json.JSONDecodeError as exc:
            truncated = not raw.rstrip().endswith("}")
            _error(errors, codes.E711, span, f"line {i} is not a JSON object: {exc.msg} (column {exc.colno})"
                   + (" (the line ends before the object does: truncated?)" if truncated else ""),
                   hint="a log is JSON Lines: one JSON object per line, e.g. "
                        '{"mode": "Patrol", "action": "Move", "outcome": 0}')
            continue
        if not isinstance(obj, dict):
            _error(errors, codes.E711, span,
                   f"line {i} is a JSON {type(obj).__name__}, not an object (one step)")
            continue
        step = _step(obj, span, errors)
        if step is not None:
            yield step


def _step(obj: dict[str, Any], span: Span, errors: list[Diagnostic]) -> Step | None:
    """The step of a line's fields, or None (its errors added)."""
    before = len(errors)
    line = span.line

    def bad(key: str, why: str) -> None:
        at = Step(span, "", "", "", None, None, None).field_span(key)
        _error(errors, codes.E712, at, f"line {line}: {why}")

    for key in ("mode", "action"):
        if key not in obj:
            bad(key, f"the step has no '{key}' (every step gives mode and action)")
        elif not isinstance(obj[key], str) or not obj[key]:
            bad(key, f"'{key}' is {json.dumps(obj[key])}, not a name")
    outcome = obj.get("outcome")
    if outcome is not None and (isinstance(outcome, bool) or
                                not isinstance(outcome, (int, str))):
        bad("outcome", f"'outcome' is {json.dumps(outcome)}: an index (0 for the action's "
                       "first outcome) or a hazard's name")
    changes = obj.get("changes")
    if changes is not None and not isinstance(changes, dict):
        bad("changes", f"'changes' is {json.dumps(changes)}, not an object of variables")
    if outcome is None and changes is None:
        bad("action", "the step gives neither 'outcome' nor 'changes': what happened?")
    duration = _duration(obj.get("duration"), lambda why: bad("duration", why))
    run = obj.get("run", "")
    if len(errors) > before:
        return None
    return Step(span, str(run), obj["mode"], obj["action"], outcome, changes, duration)


def _duration(value: Any, bad: Any) -> Duration:
    def number(v: Any) -> bool:
        return isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v)

    if value is None or number(value):
        return value  # type: ignore[no-any-return]
    if isinstance(value, dict) and all(number(v) for v in value.values()):
        return value
    bad(f"'duration' is {json.dumps(value)}: a number (the measured value of the interval "
        "constant the outcome reads), or an object of them by name")
    return None


def _csv(source: Source, errors: list[Diagnostic]) -> Iterator[Step]:
    lines = source.text.splitlines()
    rows = csv.reader(lines)
    try:
        header = next(rows)
    except (StopIteration, csv.Error):
        return
    header = [h.strip() for h in header]
    missing = [c for c in ("mode", "action") if c not in header]
    if missing:
        _error(errors, codes.E712, _line_span(source, 1),
               f"the CSV header has no column {', '.join(missing)}",
               hint=f"the columns are {', '.join(COLUMNS)} (mode and action required)")
        return
    for i, row in enumerate(rows, 2):
        if not any(c.strip() for c in row) or len(errors) >= MAX_ERRORS:
            continue
        span = _line_span(source, i)
        if len(row) > len(header):
            _error(errors, codes.E711, span, f"line {i} has {len(row)} cells, the header "
                                             f"{len(header)}")
            continue
        obj: dict[str, Any] = {}
        for key, cell in zip(header, row, strict=False):
            cell = cell.strip()
            if cell:
                obj[key] = cell
        if len(row) < len(header):
            _error(errors, codes.E711, span,
                   f"line {i} has {len(row)} cells, the header {len(header)}: truncated?")
            continue
        if "outcome" in obj and obj["outcome"].lstrip("-").isdigit():
            obj["outcome"] = int(obj["outcome"])
        if "changes" in obj:
            obj["changes"] = _pairs(obj["changes"], cells=True)
        if "duration" in obj:
            d = obj["duration"]
            obj["duration"] = _pairs(d, cells=False) if "=" in d else _number(d)
        step = _step(obj, span, errors)
        if step is not None:
            yield step


def _number(text: str) -> Any:
    try:
        v = float(text)
    except ValueError:
        return text  # reported as not a number
    return int(v) if v.is_integer() and "." not in text and "e" not in text.lower() else v


def _pairs(text: str, cells: bool) -> Any:
    """`a=1 b=true mode=Dock` as a dict (values: ints, booleans, else the text)."""
    out: dict[str, Any] = {}
    for part in text.split():
        name, eq, value = part.partition("=")
        if not eq:
            return text  # not pairs: reported as the wrong kind
        if cells and value in ("true", "false"):
            out[name] = value == "true"
        else:
            v = _number(value)
            out[name] = v if not isinstance(v, str) or cells else value
    return out
