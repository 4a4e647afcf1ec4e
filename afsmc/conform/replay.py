"""Replaying logged steps against the spec: each run starts in the initial state, and each
step is checked as the robot's controller checks it (the module `compile -t python`
writes, made from the same checked model and run here in memory): the action must be
the one the spec chooses in the state, the outcome one the action can have there
(probability > 0), the duration within its interval, the changes those the outcome
makes. What is wrong is a violation (E720) at the step's line, with the state.

A step that names what the spec does not declare (a mode, an action, a variable, an
outcome) is E713, a bad log rather than a violation. After a violation the run goes on
from what the log says happened (its mode, and its changes where it gives them); a run
whose state the log no longer tells is not checked further (said in the violation).
"""

from __future__ import annotations

import itertools
import math
import types
from collections.abc import Iterable
from dataclasses import dataclass, field
from typing import Any

from afsmc.conform.logs import Step
from afsmc.controllers.python import module
from afsmc.diagnostics import Diagnostic, Severity, codes
from afsmc.model import ir

MAX_GUESSES = 4096  # duration values tried for a step that gives changes but no duration


@dataclass
class Trial:
    """What one checked step tells the estimates: the mode it ran in, the action, its
    outcome's key (None when the changes fit several outcomes) and the measured values
    of the interval constants it read."""

    mode: str
    action: str
    outcome: int | str | None
    durations: dict[str, float]


@dataclass
class Replay:
    steps: int = 0
    runs: int = 0
    violations: list[Diagnostic] = field(default_factory=list)
    errors: list[Diagnostic] = field(default_factory=list)  # E713
    trials: list[Trial] = field(default_factory=list)
    ambiguous: int = 0  # steps whose changes fit more than one outcome


def controller(model: ir.Model) -> types.ModuleType:
    """The generated Python controller of `model`, as a module in memory."""
    mod = types.ModuleType(f"afsmc_conform_{model.name}")
    exec(compile(module(model), f"<controller of {model.name}>", "exec"), mod.__dict__)
    return mod


class Checker:
    """Replays steps through the generated controller `ctl`. An outcome there is a tuple
    (key, probability(s, K), updates(s, K) -> {variable: value}, interval constants read);
    `ctl._outcomes(s, action)` gives them with their probabilities, hazards woven in."""

    def __init__(self, model: ir.Model) -> None:
        self.model = model
        self.ctl = controller(model)
        self.display = model.display_names()
        self.flat = {v.display: v.name for v in model.variables} | {
            v.name: v.name for v in model.variables}
        self._choice: dict[tuple[Any, ...], str | None] = {}
        self._outcomes: dict[tuple[Any, ...], list[tuple[Any, float]]] = {}

    # ---- the spec, memoised per state (runs share most of their states) ----

    def key(self, s: dict[str, Any]) -> tuple[Any, ...]:
        return tuple(s.values())

    def choose(self, s: dict[str, Any]) -> str | None:
        k = self.key(s)
        if k not in self._choice:
            self._choice[k] = self.ctl.choose(s)
        return self._choice[k]

    def outcomes(self, s: dict[str, Any], action: str) -> list[tuple[Any, float]]:
        k = (*self.key(s), action)
        if k not in self._outcomes:
            self._outcomes[k] = self.ctl._outcomes(s, action)
        return self._outcomes[k]

    def state_text(self, s: dict[str, Any]) -> str:
        return " ".join([f"mode={s['mode']}"] + [
            f"{self.display[n]}={_value(v)}" for n, v in s.items() if n != "mode"])

    # ---- one step ----

    def replay(self, steps: Iterable[Step]) -> Replay:
        out = Replay()
        # a run is its log's: each file is a run of its own where it names none
        states: dict[tuple[str, str], dict[str, Any] | None] = {}
        for step in steps:
            run = (step.span.source.path, step.run)
            if run not in states:
                states[run] = self.ctl.initial()
                out.runs += 1
            s = states[run]
            if not self._names_ok(step, out):
                states[run] = None
                continue
            if s is None:
                continue  # lost after a violation that left the state unknown
            out.steps += 1
            states[run] = self._step(step, s, out)
        return out

    def _names_ok(self, step: Step, out: Replay) -> bool:
        model = self.model
        before = len(out.errors)
        wrong: list[tuple[str, str]] = []
        if step.mode not in self.ctl.MODES:
            wrong.append(("mode", f"mode '{step.mode}'"))
        if not any(a[0] == step.action for a in self.ctl.ACTIONS):
            wrong.append(("action", f"action '{step.action}'"))
        for name, value in (step.changes or {}).items():
            if name == "mode":
                if value not in self.ctl.MODES:
                    wrong.append(("changes", f"mode '{value}' (in changes)"))
            elif name not in self.flat:
                wrong.append(("changes", f"variable '{name}'"))
            elif (why := self._bad_value(self.flat[name], value)) is not None:
                out.errors.append(Diagnostic(
                    codes.E712, Severity.ERROR, f"line {step.span.line}: {name} = "
                    f"{_value(value)} in 'changes' is not {why}", step.field_span("changes")))
        for where, what in wrong:
            out.errors.append(Diagnostic(
                codes.E713, Severity.ERROR,
                f"line {step.span.line}: {model.name} declares no {what}", step.field_span(where),
                hint="is the log of another mission, or of another version of it?"))
        return len(out.errors) == before

    def _bad_value(self, name: str, value: Any) -> str | None:
        """Why `value` cannot be variable `name`'s (None: it can)."""
        var = self.model.variable(name)
        if var.type.value == "bool":
            return None if isinstance(value, bool) else "a bool (true or false)"
        if isinstance(value, bool) or not isinstance(value, int):
            return f"an int in [{var.lo}, {var.hi}]"
        return None if var.lo <= value <= var.hi else f"within its range [{var.lo}, {var.hi}]"

    def _step(self, step: Step, s: dict[str, Any], out: Replay) -> dict[str, Any] | None:
        problems: list[str] = []
        if step.mode != s["mode"]:
            problems.append(f"the log says mode {step.mode}, the spec's run is in {s['mode']}")
            s = {**s, "mode": step.mode}
        chosen = self.choose(s)
        if chosen != step.action:
            problems.append(f"the spec chooses {chosen or 'no action'} here, not {step.action}")
            return self._violation(step, s, problems, out)
        return self._outcome(step, s, problems, out)

    def _outcome(self, step: Step, s: dict[str, Any], problems: list[str],
                 out: Replay) -> dict[str, Any] | None:
        pairs = self.outcomes(s, step.action)
        if step.outcome is not None:
            match = [(o, p) for o, p in pairs if o[0] == step.outcome]
            if not match:
                problems.append(f"{step.action} has no outcome {step.outcome!r} in mode "
                                f"{s['mode']} (it has {', '.join(repr(o[0]) for o, _ in pairs)})")
                return self._violation(step, s, problems, out)
            o, p = match[0]
            if p <= 0:
                problems.append(f"outcome {step.outcome!r} of {step.action} has probability 0 "
                                "here")
            values, why = self._durations(o, step.duration)
            if why:
                problems.append(why)
                return self._violation(step, s, problems, out)
            new = self._apply(s, o, values)
            if step.changes is not None:
                problems += self._compare(s, new, step.changes)
        else:
            assert step.changes is not None
            fits = self._fitting(s, pairs, step)
            if not fits:
                problems.append(f"no outcome of {step.action} makes these changes"
                                + ("" if step.duration is None else
                                   f" with duration {_value(step.duration)}"))
                return self._violation(step, s, problems, out)
            o, values, new = fits[0]
            if len({f[0][0] for f in fits}) > 1:  # no evidence of which outcome it was
                out.ambiguous += 1
                o = (None, *o[1:])
        if problems:
            return self._violation(step, s, problems, out, new)
        # only measured values are evidence of an interval (not those guessed from changes)
        measured = {n: float(d) for n in o[3]
                    if (d := _given(step.duration, n, o[3])) is not None}
        out.trials.append(Trial(s["mode"], step.action, o[0], measured))
        return new

    def _durations(self, o: Any, duration: Any) -> tuple[dict[str, int], str | None]:
        names = o[3]
        values: dict[str, int] = {}
        for n in names:
            d = _given(duration, n, names)
            lo, hi = self.ctl.INTERVALS[n]
            if d is None:
                return {}, (f"the outcome reads {n} in [{lo}, {hi}]: the step gives no "
                            "duration")
            if not lo <= d <= hi:
                return {}, f"duration {_value(d)} of {n} is outside its interval [{lo}, {hi}]"
            values[n] = math.floor(d + 0.5)  # the variables are integers
        return values, None

    def _apply(self, s: dict[str, Any], o: Any, values: dict[str, int]) -> dict[str, Any]:
        K = dict(self.ctl.CONSTANTS)
        K.update(values)
        new = dict(s)
        for name, value in o[2](s, K).items():
            if name == "mode":
                new["mode"] = self.model.mode_by_number(value).name
                continue
            var = self.model.variable(name)
            if var.clamp:
                value = min(max(value, var.lo), var.hi)
            new[name] = value
        return new

    def _fitting(self, s: dict[str, Any], pairs: list[tuple[Any, float]],
                 step: Step) -> list[tuple[Any, dict[str, int], dict[str, Any]]]:
        """The outcomes (with the durations) whose changes are the step's."""
        fits = []
        for o, p in pairs:
            if p <= 0:
                continue
            for values in self._guesses(o, step.duration):
                new = self._apply(s, o, values)
                if not self._compare(s, new, step.changes or {}):
                    fits.append((o, values, new))
                    break
        return fits

    def _guesses(self, o: Any, duration: Any) -> Iterable[dict[str, int]]:
        names = o[3]
        if not names:
            return [{}]
        if duration is not None:
            values, why = self._durations(o, duration)
            return [] if why else [values]
        ranges = [range(self.ctl.INTERVALS[n][0], self.ctl.INTERVALS[n][1] + 1) for n in names]
        combos = itertools.islice(itertools.product(*ranges), MAX_GUESSES)
        return [dict(zip(names, c, strict=True)) for c in combos]

    def _compare(self, old: dict[str, Any], new: dict[str, Any],
                 changes: dict[str, Any]) -> list[str]:
        """What the logged changes say that the spec's outcome does not make."""
        said = {("mode" if k == "mode" else self.flat[k]): v for k, v in changes.items()}
        out = []
        for name in new:
            want = new[name]
            if name in said and said[name] != want:
                out.append(f"{self._shown(name)} becomes {_value(said[name])}, the outcome "
                           f"makes it {_value(want)}")
            elif name not in said and want != old[name]:
                out.append(f"the outcome changes {self._shown(name)} to {_value(want)}, the "
                           "log does not")
        return out

    def _shown(self, name: str) -> str:
        return "mode" if name == "mode" else self.display[name]

    def _violation(self, step: Step, s: dict[str, Any], problems: list[str], out: Replay,
                   new: dict[str, Any] | None = None) -> dict[str, Any] | None:
        """Report the step; the state the run goes on from (None: unknown)."""
        if new is None and step.changes is not None:
            new = dict(s)
            for k, v in step.changes.items():
                new["mode" if k == "mode" else self.flat[k]] = v
        where = "" if new is not None else "; the rest of this run is not checked"
        run = f" of run {step.run}" if step.run else ""
        out.violations.append(Diagnostic(
            codes.E720, Severity.ERROR,
            f"step{run} at line {step.span.line} is not allowed by the spec: "
            f"{'; '.join(problems)} (state: {self.state_text(s)}){where}", step.span))
        return new


def _given(duration: Any, name: str, names: tuple[str, ...]) -> Any:
    if isinstance(duration, dict):
        return duration.get(name)
    return duration if len(names) == 1 else None


def _value(v: Any) -> str:
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, float) and v.is_integer():
        return str(int(v))
    return str(v)
