"""`afsmc diagram FILE [-o out.svg|.png|.pdf] [--reach] [--results results.json]`.

Builds the mission diagram (afsmc.backends.dot) and renders it with the Graphviz `dot`
program. `--reach` asks Storm, for every mode, the probability of ever reaching it
(`P=? [F mode=N]`; Pmin and Pmax when interval constants make the model an MDP) and
writes it into the mode's box. `--results` draws the numbers of `afsmc verify --json`.
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import math
import os
import sys
from typing import Any

from afsmc.api.diagram import (  # noqa: F401  (mode_reachability, _reach_error: the tests')
    FORMATS,
    _reach_error,
    mode_reachability,
    reach_modes,
    render,
)
from afsmc.backends.dot import Overlay, diagram
from afsmc.commands.common import (
    add_consts,
    add_file,
    add_resolve,
    fail,
    overrides,
    report,
    usage_error,
)
from afsmc.commands.render import diagram_strategy
from afsmc.commands.verify import positive
from afsmc.compiler import load
from afsmc.diagnostics import CompileError, Diagnostic, Severity, codes
from afsmc.files import check_writable, write_atomic
from afsmc.model import ir
from afsmc.text import short
from afsmc.verify.engines.guard import MAX_STATES_LIMIT


def add_arguments(p: argparse.ArgumentParser) -> None:
    add_file(p)
    p.add_argument("-o", "--output", metavar="FILE",
                   help="the picture: .svg, .png or .pdf (default: <stem>.svg in the current "
                        "directory)")
    add_consts(p)
    p.add_argument("--reach", action="store_true",
                   help="compute with Storm the probability of ever reaching each mode and "
                        "write it into the mode's box")
    add_resolve(p, default=None, extra="; with --reach")
    p.add_argument("--max-states", type=positive, metavar="N",
                   help="with --reach: stop (exit 1) if the model has more states than N, at "
                        f"most {MAX_STATES_LIMIT:,} (default: what 70%% of the free memory "
                        "holds, at most 50 M; without it, a counter wider than that is refused "
                        "up front, E420)")
    p.add_argument("--results", metavar="JSON",
                   help="overlay the results of `afsmc verify --json` (a box of property values; "
                        "per-mode numbers from its \"modes\" list, if any)")
    diagram_strategy.add_arguments(p)


def _error(code: str, message: str, hint: str | None = None) -> CompileError:
    return CompileError([Diagnostic(code, Severity.ERROR, message, None, hint=hint)])


def _range(lo: object, hi: object) -> str:
    a, b = short(lo), short(hi)
    return a if a == b else f"{a} – {b}"


def _value(entry: dict[str, Any]) -> str:
    """min – max, or the value; `afsmc verify --json` writes null for what it did not ask
    and lists infinite values under "infinite"."""
    inf = entry.get("infinite") or []

    def get(key: str) -> object:
        return math.inf if key in inf else entry.get(key)

    if get("min") is not None or get("max") is not None:
        text = _range(get("min"), get("max"))
    else:
        text = short(get("value"))
    if get("uniform") is not None:
        text += f" (uniform {short(get('uniform'))})"
    return text


MODES_HINT = 'each entry is {"mode": NAME or "number": N, then "min"/"max" or "value"}'


def _check_numbers(path: str, entry: dict[str, Any], what: str,
                   probability: bool = False) -> None:
    """E611 unless each value is null or a number (a probability for a mode's P(reach))."""
    for key in ("min", "max", "value", "uniform"):
        v = entry.get(key)
        if v is None:
            continue
        if isinstance(v, bool) or not isinstance(v, (int, float)):
            raise _error(codes.E611, f"{path}: {what} has {key} {v!r}, not a number",
                         hint="pass the output of `afsmc verify --json`")
        if not math.isfinite(v):
            # Python's json reads NaN and Infinity; verify writes neither (null + "infinite")
            raise _error(codes.E611, f"{path}: {what} has {key} {v!r}, not a finite number",
                         hint="`afsmc verify --json` writes an infinite value as null and "
                         "names it in \"infinite\"")
        if probability and not 0 <= v <= 1:
            raise _error(codes.E611, f"{path}: {what} has {key} {v!r}, not a probability",
                         hint="a mode's number is the probability of reaching it, in [0, 1]")
    low, high = entry.get("min"), entry.get("max")
    if isinstance(low, (int, float)) and isinstance(high, (int, float)) and low > high:
        raise _error(codes.E611, f"{path}: {what} has min {low!r} above its max {high!r}",
                     hint="pass the output of `afsmc verify --json`")


def read_results(path: str, model: ir.Model) -> Overlay:
    """The overlay of an `afsmc verify --json` file (see docs/diagrams.md)."""
    try:
        with open(path, encoding="utf-8") as f:
            data = json.load(f)
    except OSError as exc:
        raise _error(codes.E611, f"cannot read {path}: {exc.strerror or exc}") from None
    except (json.JSONDecodeError, UnicodeDecodeError) as exc:
        raise _error(codes.E611, f"{path} is not JSON: {exc}",
                     hint="pass the output of `afsmc verify --json`") from None
    if not isinstance(data, dict) or not isinstance(data.get("properties"), list) or not all(
            isinstance(e, dict) and isinstance(e.get("name"), str) for e in data["properties"]):
        raise _error(codes.E611, f"{path}: expected an object with a \"properties\" list of "
                     "named results", hint="pass the output of `afsmc verify --json`")
    if "points" in data:
        raise _error(codes.E611, f"{path} is the output of `afsmc sweep`, a value per point: the "
                     "diagram takes one result per property",
                     hint="pass the output of `afsmc verify --json` at the constants drawn")
    if "runs" in data or any("estimate" in e for e in data["properties"]):
        # its numbers would show as n/a: they are estimates, not min/max/uniform/value
        raise _error(codes.E611, f"{path} is the output of `afsmc simulate`, estimates with "
                     "confidence intervals: the diagram shows the values Storm computes",
                     hint="pass the output of `afsmc verify --json`")
    if data["properties"] and not any(k in e for e in data["properties"]
                                      for k in ("min", "max", "uniform", "value")):
        raise _error(codes.E611, f"{path}: no property has a min, max, uniform or value",
                     hint="pass the output of `afsmc verify --json`")
    machine = data.get("machine")
    if isinstance(machine, str) and machine != model.name:
        raise _error(codes.E611, f"{path} holds the results of machine {machine}, not {model.name}",
                     hint=f"run `afsmc verify --json` on the file of machine {model.name}")
    given = data.get("constants")
    if given is not None and not isinstance(given, dict):
        raise _error(codes.E611, f"{path}: \"constants\" is not an object of NAME: value",
                     hint="pass the output of `afsmc verify --json`")
    if isinstance(given, dict):
        # The diagram shows no constants: numbers of another instance would pass unnoticed.
        here = {c.name: c.value for c in model.constants if c.is_param}
        differ = sorted(n for n in set(given) | set(here)
                        if n not in here or n not in given or given[n] != here[n])
        if differ:
            theirs = ", ".join(f"{n}={given.get(n, 'unset')}" for n in differ)
            mine = ", ".join(f"{n}={here.get(n, 'unset')}" for n in differ)
            raise _error(codes.E611, f"{path} holds results for {theirs}; the diagram is of {mine}",
                         hint="pass the --const values the results were computed with")
    notes: list[str] = []
    seen: set[str] = set()
    for entry in data.get("properties", []):
        if entry["name"] in seen:
            raise _error(codes.E611, f"{path}: property {entry['name']} is listed twice",
                         hint="give each property one entry")
        seen.add(entry["name"])
        _check_numbers(path, entry, f"property {entry['name']}")
        verdict = entry.get("verdict")
        notes.append(f"{entry['name']}: {_value(entry)}"
                     + (f": {verdict}" if isinstance(verdict, str) else ""))
    by_name = {m.name: m.number for m in model.modes}
    modes: dict[int, str] = {}
    listed = data.get("modes", []) or []
    if not isinstance(listed, list):
        raise _error(codes.E611, f"{path}: \"modes\" is not a list", hint=MODES_HINT)

    def no_mode(which: object) -> CompileError:
        return _error(codes.E611, f"{path}: machine {model.name} has no mode {which!r}",
                      hint="modes are named as in the .afsm file, or numbered")
    for entry in listed:
        if not isinstance(entry, dict):
            raise _error(codes.E611, f"{path}: an entry of \"modes\" is not an object",
                         hint=MODES_HINT)
        named = by_name.get(str(entry["mode"])) if "mode" in entry else None
        if "mode" in entry and named is None:
            raise no_mode(entry["mode"])
        number = entry.get("number", named)
        if isinstance(number, bool) or not isinstance(number, int) or \
                number not in model.mode_names:
            raise no_mode(number)
        if named is not None and number != named:
            raise _error(codes.E611, f"{path}: an entry of \"modes\" names mode "
                         f"{entry['mode']} (number {named}) and number {number} "
                         f"({model.mode_names[number]})", hint=MODES_HINT)
        if all(entry.get(k) is None for k in ("min", "max", "value", "uniform")):
            raise _error(codes.E611, f"{path}: mode {model.mode_names[number]} has no value",
                         hint=MODES_HINT)
        if number in modes:
            raise _error(codes.E611, f"{path}: mode {model.mode_names[number]} is listed twice in "
                         "\"modes\"", hint="give each mode one entry")
        _check_numbers(path, entry, f"mode {model.mode_names[number]}", probability=True)
        modes[number] = f"P(reach) {_value(entry)}"
    return Overlay(modes=modes, notes=notes)


def output_path(args: argparse.Namespace) -> tuple[str, str]:
    if args.output is None:
        stem = os.path.splitext(os.path.basename(args.file))[0]
        return stem + ".svg", "svg"
    fmt = os.path.splitext(args.output)[1].lstrip(".").lower()
    if fmt not in FORMATS and args.output.strip():  # an empty name: E003 in run
        usage_error(f"-o {args.output}: the picture must end in .svg, .png or .pdf")
    return args.output, fmt


def _say(text: str) -> None:
    print(text, file=sys.stderr, flush=True)


def run(args: argparse.Namespace) -> int:
    path, fmt = output_path(args)
    if not args.reach:
        given = [o for o, v in (("--resolve", args.resolve), ("--max-states", args.max_states))
                 if v is not None]
        if given:
            verb = "only applies" if len(given) == 1 else "only apply"
            usage_error(f"{' and '.join(given)} {verb} to --reach (the probabilities "
                        "Storm computes); add --reach, or leave them out")
    try:
        check_writable(path, protect=(args.file,))  # before the model is built and drawn
        checked = load(args.file, overrides(args))
        report(checked.diagnostics)
        model = checked.model
        modes: dict[int, str] = {}
        notes: list[str] = []
        caption = ""
        agents: dict[str, Overlay] = {}
        if args.results:
            ov = read_results(args.results, model)
            modes.update(ov.modes)
            notes += ov.notes
        if args.reach:
            ov = reach_modes(model, args.resolve or "nondet", max_states=args.max_states,
                             progress=_say)
            modes.update(ov.modes)
            agents.update(ov.agents)
            caption = ov.caption
        drawn, more = diagram_strategy.overlay(args, model)
        for name, mine in drawn.agents.items():
            # a composed mission's agent: its modes' numbers (--reach) and its strategy or path
            agents[name] = dataclasses.replace(mine, modes=agents[name].modes) \
                if name in agents else mine
        data = render(diagram(model, Overlay(modes, notes + more, caption, drawn.ends,
                                             drawn.path, drawn.moved, agents)), fmt)
        write_atomic(path, data, protect=(args.file,))
        print(f"wrote {path}", file=sys.stderr)
    except CompileError as exc:
        return fail(exc)
    return 0
