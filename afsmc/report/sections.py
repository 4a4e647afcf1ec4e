"""The report's content as plain blocks (paragraphs, tables, the picture), one list per
section, which afsmc.report.html and afsmc.report.markdown lay out. Every number is the
verification's own, printed as `afsmc verify --json` prints it (Python's shortest
round-trip form), so that a reader or a test can compare them digit for digit.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from fractions import Fraction

from afsmc.report.baseline import shown
from afsmc.report.case import Case
from afsmc.report.causes import Split
from afsmc.text import num
from afsmc.verify.core.uncertainty import described
from afsmc.verify.outcome.results import PropertyResult, symmetry_words


@dataclass(frozen=True)
class Para:
    text: str
    kind: str = ""  # "pre": kept as written (the mission's own words), "note": small print


@dataclass(frozen=True)
class Table:
    head: list[str]
    rows: list[list[str]]
    cls: str = ""


@dataclass(frozen=True)
class Picture:
    svg: str


Block = Para | Table | Picture


@dataclass(frozen=True)
class Section:
    id: str
    title: str
    blocks: list[Block] = field(default_factory=list)


def number(v: float | None) -> str:
    """As `afsmc verify --json` writes it: shortest round-trip; "-" for none."""
    if v is None:
        return "-"
    if math.isinf(v):
        return "infinity" if v > 0 else "-infinity"
    return repr(float(v))


def bounds(p: PropertyResult) -> str:
    if p.value is not None:
        return number(p.value)
    if p.min is None and p.max is None:
        return "-"
    return f"{number(p.min)} – {number(p.max)}"


def deciding(p: PropertyResult) -> tuple[str, float | None]:
    """The bound a requirement's verdict rests on (the verdict's `decided_by`) and its
    value."""
    v = p.verdict
    if v is None or v.decided_by is None:
        return "", None
    return v.decided_by, {"min": p.min, "max": p.max, "value": p.value}[v.decided_by]


def margin(p: PropertyResult) -> float | None:
    """How far the deciding bound lies from the threshold, on the side that meets it:
    positive where it meets it, negative where it misses it (exact arithmetic on the two
    numbers, then one rounding)."""
    _, v = deciding(p)
    t = p.threshold
    if v is None or t is None or not math.isfinite(v):
        return None
    d = Fraction(v) - Fraction(t.exact)
    return float(d if t.op in (">=", ">") else -d)


def _mission(case: Case) -> Section:
    blocks: list[Block] = []
    if case.description:
        blocks.append(Para(case.description, "pre"))
    else:
        blocks.append(Para("The file has no description comment above `machine "
                           f"{case.machine};`."))
    modes = [[m.name, str(m.number), "initial" if m.initial else "final" if m.final else ""]
             for m in sorted(case.modes, key=lambda m: m.number)]
    blocks.append(Table(["mode", "number", "kind"], modes))
    if case.agents:
        blocks.append(Para("Agents: " + ", ".join(case.agents) + "."))
        sym = symmetry_words(case.result.symmetry)
        if sym is not None:
            blocks.append(Para(sym[0].upper() + sym[1:] + ".", "note"))
    if case.constants:
        blocks.append(Para("Instance: " + ", ".join(f"{k} = {v}" for k, v
                                                    in case.constants.items()) + "."))
    if case.svg:
        blocks.append(Picture(case.svg))
    else:
        blocks.append(Para(f"No diagram: {case.svg_note}.", "note"))
    return Section("mission", f"The mission: {case.machine}", blocks)


def _decides(case: Case, p: PropertyResult) -> str:
    """Which uncertainty the deciding bound is taken over."""
    name, _ = deciding(p)
    res = case.result
    if name in ("", "value"):
        return "nothing uncertain: one value"
    over = described(res.uncertainty, res.probability, res.composition) or \
        "the model's choices"
    where = ""
    if p.attained_at and name in p.attained_at:
        where = " (attained at " + ", ".join(f"{k} = {number(v)}" for k, v in
                                             p.attained_at[name].items()) + ")"
    return f"the {name} over {over}{where}"


def _requirements(case: Case) -> Section:
    reqs = [p for p in case.result.properties if p.threshold is not None]
    blocks: list[Block] = []
    if reqs:
        rows = []
        for p in reqs:
            assert p.threshold is not None and p.verdict is not None
            name, v = deciding(p)
            m = margin(p)
            rows.append([p.name, p.formula, p.verdict.kind, f"{name} {number(v)}",
                         f"{p.threshold.op} {p.threshold.exact}",
                         "-" if m is None else number(m),
                         "-" if p.error is None else number(p.error), _decides(case, p)])
        blocks.append(Table(["requirement", "formula", "verdict", "deciding bound",
                             "threshold", "margin", "± error", "decided by"], rows,
                            "requirements"))
        blocks += [Para(f"{p.name}: {p.verdict.reason}.") for p in reqs if p.verdict]
        blocks.append(Para("What min, max and a verdict mean: docs/verification.md, "
                           "\"What a result means\". The margin is the deciding bound's "
                           "distance from the threshold (negative: it misses it), each "
                           "value within the error shown.", "note"))
    else:
        blocks.append(Para("The mission states no requirement (a property with a "
                           "threshold, such as `P>=0.9 [ ... ]`)."))
    others = [p for p in case.result.properties if p.threshold is None]
    if others:
        blocks.append(Table(["property", "formula", "value (min – max)"],
                            [[p.name, p.formula, bounds(p)] for p in others], "values"))
    return Section("requirements", "Requirements", blocks)


def _matters(case: Case) -> Section:
    blocks: list[Block] = []
    if case.sensitivity is None:
        blocks.append(Para("Not computed for this report (--no-sensitivity)."))
    elif not case.sensitivity:
        blocks.append(Para("No requirement with a verdict, or no figure to vary (a `param "
                           "double` or a probability): nothing to rank."))
    else:
        rows = []
        for s in case.sensitivity:
            f = s.figure
            rng = "-" if f.range is None else f"[{number(f.range[0])}, {number(f.range[1])}]"
            flip = (f"{number(s.flip)} ({s.bound} {number(s.flip_bound)} there)"
                    if s.flip is not None else s.note or "-")
            rows.append([s.requirement, f"{s.bound}", f.name, f.kind, number(f.value), rng,
                         "-" if s.derivative is None else number(s.derivative), flip])
        blocks.append(Table(["requirement", "bound", "figure", "kind", "value", "range",
                             "derivative", "verdict flips at"], rows, "sensitivity"))
        blocks.append(Para("Each derivative is that of the deciding bound by the figure at "
                           "its value in the file, from two verifications a small step "
                           "either side; most influential first, per requirement.", "note"))
    return Section("what-matters-most", "What matters most", blocks)


def _paths(s: Split) -> list[Block]:
    """The most probable paths into a split's largest cause, one row per path."""
    if not s.causes or (not s.paths and not s.paths_note):
        return []
    out: list[Block] = [Para(f"The most probable ways into the largest cause, "
                             f"{s.causes[0].text}:")]
    rows = []
    for i, w in enumerate(s.paths, 1):
        steps = " → ".join(f"{st.mode}: {st.hazard + ' in ' if st.hazard else ''}{st.action}"
                           for st in w.steps)
        rows.append([str(i), number(w.probability), f"{steps} → {w.end_mode}"])
    if rows:
        out.append(Table(["path", "probability", "steps (mode: action)"], rows, "paths"))
    if s.paths_note:
        out.append(Para(s.paths_note, "note"))
    return out


def _fails(case: Case) -> Section:
    blocks: list[Block] = []
    if case.causes is None:
        blocks.append(Para("Not computed for this report (--no-causes)."))
        return Section("how-it-fails", "How it fails", blocks)
    for name, splits in case.causes.items():
        p = case.property(name)
        for s in splits:
            at = p.reference if s.midpoint and p.reference is not None else p
            shown = {"min": at.min, "max": at.max, "value": at.value}[s.under]
            head = (f"{name} = {number(shown)}" if s.under == "value"
                    else f"{name}, its {s.under} {number(shown)}: under the scheduler "
                         "that attains it")
            if s.midpoint:
                head += ", with the interval probabilities at their midpoint (the reference)"
            rows = [[c.kind, c.event, c.during or "-", c.mode, number(c.probability)]
                    for c in s.causes]
            rows.append(["sum", "", "", "", number(s.summed)])
            blocks.append(Para(head))
            blocks.append(Table(["cause", "event", "during", "mode entered", "probability"],
                                rows, "causes"))
            blocks += _paths(s)
    blocks += [Para(n, "note") for n in case.notes]
    if not case.causes:
        blocks.append(Para("No property is the probability of reaching a target: there "
                           "is nothing to split by cause."))
    return Section("how-it-fails", "How it fails", blocks)


def worst_ends(case: Case) -> list[tuple[PropertyResult, str]]:
    """The strategies the worst case shows: each requirement's at the bound its verdict
    rests on, and each failure property's at its max (the most failures)."""
    out = []
    for p in case.result.properties:
        if not case.strategies.get(p.name):
            continue
        if p.verdict is not None and p.verdict.decided_by in ("min", "max"):
            out.append((p, p.verdict.decided_by))
        elif p.threshold is None and p.name in (case.causes or {}):
            out.append((p, "max"))
    return out


def _worst(case: Case) -> Section:
    blocks: list[Block] = []
    if not case.worst_case:
        blocks.append(Para("Not computed for this report (--no-worst-case)."))
        return Section("worst-case", "The worst case", blocks)
    for p, end in worst_ends(case):
        entries = case.strategies[p.name].get(end) or []
        what = "the verdict rests on" if p.threshold is not None else "the most failures"
        blocks.append(Para(f"{p.name}, its {end} {number(getattr(p, end))} ({what}): "
                           + ("the choices that attain it" if entries else
                              "no choice that matters: every state it reaches gives the "
                              "same value either way")))
        if entries:
            blocks.append(Table(["in mode", "action", "constant", "takes", "when", "states"],
                                [[e.mode, e.action, e.constant, f"{e.end} {e.value}",
                                  e.when or "always", f"{e.states:,}"] for e in entries],
                                "playbook"))
    if not blocks:
        blocks.append(Para("Nothing in the mission is chosen (no interval constant, no "
                           "choice of the agents' order), or no requirement or failure "
                           "property depends on a choice: there is no worst case beyond "
                           "the values above."))
    return Section("worst-case", "The worst case", blocks)


def _figures(case: Case) -> Section:
    blocks: list[Block] = []
    if not case.figures:
        blocks.append(Para("No constant is declared `from sim` or `from data`."))
        return Section("figures", "Where the figures come from", blocks)
    rows = []
    for f in case.figures:
        e = f.evidence
        check = "not re-checked" if e is None else (
            f"{e.verdict}: mean {num(e.mean)} in [{num(e.mean_low)}, {num(e.mean_high)}] "
            f"over {e.runs:,} " + ("runs" if e.seed is not None else "rows of data"))
        rows.append([f.name, f.declared, f.source, f.confidence, check])
    blocks.append(Table(["constant", "declared", "source", "confidence", "fresh sim-check"],
                        rows, "figures"))
    blocks.append(Para("Not re-checked: `afsmc report --recheck RUNS` re-runs every "
                       "simulation; `afsmc sim-check` does the same alone."
                       if not case.rechecked else
                       f"Re-checked for this report: {case.rechecked:,} runs per "
                       "simulated constant, seed 0.", "note"))
    return Section("figures", "Where the figures come from", blocks)


def _changed(case: Case) -> Section | None:
    c = case.baseline
    if c is None:
        return None
    rows = []
    for ch in c.changes:
        flag = ("worse" if ch.worse else "flip" if ch.flipped else
                f"only in the {ch.only} run" if ch.only else
                "moved" if ch.flagged else "")
        rows.append([ch.name, shown(ch.old, number), shown(ch.new, number),
                     ch.old_verdict or "-",
                     ch.new_verdict or "-", flag])
    return Section("what-changed", "What changed", [
        Para(f"Against {c.baseline or 'the baseline'}; a bound that moved by more than "
             f"{number(c.tolerance)} or a verdict that flipped is flagged."),
        Table(["property", "old", "new", "old verdict", "new verdict", "flag"], rows,
              "changes")])


def _reproduce(case: Case) -> Section:
    rows = [[k, v] for k, v in case.reproduce]
    if case.command:
        rows.append(["command", case.command])
    return Section("reproducibility", "Reproducibility", [
        Table(["what", "value"], rows, "reproduce"),
        Para(case.generated, "note")])


def sections(case: Case) -> list[Section]:
    out = [_mission(case), _requirements(case), _matters(case), _fails(case), _worst(case),
           _figures(case)]
    changed = _changed(case)
    if changed is not None:
        out.append(changed)
    out.append(_reproduce(case))
    return out
