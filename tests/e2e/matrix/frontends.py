"""The front-ends of the combination matrix (tests/e2e/test_combination_matrix.py): each
runs one front-end on one mission with a set of options and reads back what it shows.

Every reader returns an `Answer`: the diagnostic code of a refusal, or per property the
bounds it shows (`lo`, `hi`), the verdict (if it shows one) and how precisely it shows
them (`digits` significant digits, or `None` for the full float). The test then compares
the answer with `verify --json`'s for the same mission and options (`Reference`).

A front-end that crashes (exit code 3, a traceback) fails the cell at once: `crashed`
raises with the output, never an `Answer`.
"""

from __future__ import annotations

import csv
import html
import io
import json
import math
import re
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any
from xml.etree import ElementTree as ET

from tests.conftest import Result, run_cli

HERE = Path(__file__).resolve().parent
VERDICTS = ("holds", "fails", "depends", "undecided")


@dataclass(frozen=True)
class Shown:
    """One property as a front-end shows it: its bounds (a DTMC's value is both), its
    verdict (None: not shown) and the precision of the numbers (None: full floats)."""

    lo: float | None
    hi: float | None
    verdict: str | None = None
    digits: int | None = None


@dataclass
class Answer:
    """What a front-end answered: a refusal (`code`) or the properties it showed, plus
    the problems the reader found in its own output (`notes`, e.g. a `--witness` that
    printed no path and no reason)."""

    code: str | None = None
    message: str = ""
    shown: dict[str, Shown] = field(default_factory=dict)
    notes: list[str] = field(default_factory=list)


@dataclass(frozen=True)
class Reference:
    """`verify --json`'s answer: per property, its `min`/`max` (a DTMC's `value` stands
    for both) and its `verdict`. These are the headline bounds every front-end must show:
    with interval probabilities they become the sound bounds over the box (issue 44), and
    the matrix follows without a change here."""

    data: Mapping[str, Any]

    def prop(self, name: str) -> Mapping[str, Any]:
        for p in self.data["properties"]:
            if p["name"] == name:
                return p  # type: ignore[no-any-return]
        raise KeyError(name)

    @property
    def names(self) -> list[str]:
        return [p["name"] for p in self.data["properties"]]

    def bounds(self, name: str) -> tuple[float | None, float | None]:
        p = self.prop(name)
        lo = p["min"] if p["min"] is not None else p["value"]
        hi = p["max"] if p["max"] is not None else p["value"]
        return lo, hi

    def verdict(self, name: str) -> str | None:
        return self.prop(name).get("verdict")


def at_midpoint(data: Mapping[str, Any]) -> dict[str, Any]:
    """`verify --json`'s answer at the interval probabilities' midpoint: each property's
    `reference` values in place of its bounds, with no verdict (a reference is never
    judged)."""
    props = []
    for p in data["properties"]:
        ref = p.get("reference") or {}
        props.append({**p, "min": ref.get("min"), "max": ref.get("max"),
                      "value": ref.get("value"), "verdict": None})
    return {**data, "properties": props}


class Crashed(AssertionError):
    """A front-end's internal error: exit code 3 or a Python traceback."""


def crashed(r: Result, what: str) -> None:
    if r.code == 3 or "Traceback (most recent call last)" in r.out + r.err:
        raise Crashed(f"{what}: internal error (exit {r.code})\n{r.err[-3000:]}{r.out[-1000:]}")


def refusal(text: str) -> tuple[str, str] | None:
    """The first error diagnostic of a text output: (code, its line)."""
    m = re.search(r"error\[([EW]\d+)\]: ?(.*)", text)
    return (m.group(1), m.group(0)) if m else None


def json_refusal(data: Mapping[str, Any]) -> tuple[str, str] | None:
    for d in data.get("diagnostics", ()):
        if d.get("severity", "error") == "error":
            return str(d["code"]), str(d.get("message", ""))
    return None


def number(text: str) -> float | None:
    if text in ("-", "n/a", ""):
        return None
    if text == "inf":
        return math.inf
    return float(text)


# -- verify --------------------------------------------------------------------------

def verify_text(argv: Sequence[str]) -> Answer:
    """`afsmc verify` as a table: the row of each property, its last columns the values
    (and the verdict)."""
    r = run_cli("verify", *argv)
    crashed(r, "verify")
    refused = refusal(r.err + r.out)
    if refused:
        return Answer(code=refused[0], message=refused[1])
    lines = r.out.splitlines()
    head = next(i for i, line in enumerate(lines)
                if line.startswith("property") and "formula" in line)
    columns = lines[head].split()[2:]
    answer = Answer()
    for line in lines[head + 1:]:
        if not line.strip():
            break
        cells = line.split()
        row = dict(zip(columns, cells[-len(columns):], strict=True))
        value = number(row.get("value", "-"))
        lo = number(row["min"]) if "min" in row else value
        hi = number(row["max"]) if "max" in row else value
        answer.shown[cells[0]] = Shown(lo, hi, row.get("verdict"), digits=6)
    if "--witness" in argv and "path 1:" not in r.out and "no path" not in r.out + r.err:
        answer.notes.append("--witness printed no path and no reason")
    if "--strategy" in argv and "strategies of" not in r.out and "turns of" not in r.out:
        answer.notes.append("--strategy printed no strategy table")
    return answer


def verify_json(argv: Sequence[str]) -> tuple[Answer, dict[str, Any] | None]:
    """`afsmc verify --json`: its properties' min/max/value/verdict, full floats."""
    r = run_cli("verify", *argv, "--json")
    crashed(r, "verify --json")
    data = json.loads(r.out)
    refused = json_refusal(data)
    if refused:
        return Answer(code=refused[0], message=refused[1]), None
    answer = Answer()
    ref = Reference(data)
    for name in ref.names:
        lo, hi = ref.bounds(name)
        answer.shown[name] = Shown(lo, hi, ref.verdict(name))
    for p in data["properties"]:
        if "--witness" in argv and not p.get("witnesses") and not p.get("witness_note"):
            answer.notes.append(f"--witness: {p['name']} has no paths and no witness_note")
        if "--strategy" in argv and not p.get("strategy") and not p.get("turns"):
            answer.notes.append(f"--strategy: {p['name']} has no strategy and no turns")
    return answer, data


def verify_junit(argv: Sequence[str], tmp: Path) -> Answer:
    """`afsmc verify --junit FILE`: one testcase per requirement, its outcome the verdict
    (`failure`/`error` name it in `type`; a pass is `holds`), its message ending in the
    values (`; min 0.81, max 0.83 (each within 1e-06)`, 6 digits)."""
    out = tmp / "junit.xml"
    r = run_cli("verify", *argv, "--junit", str(out))
    crashed(r, "verify --junit")
    refused = refusal(r.err + r.out)
    if refused:
        return Answer(code=refused[0], message=refused[1])
    answer = Answer()
    for case in ET.parse(out).getroot().iter("testcase"):
        name = case.get("name", "").split(":")[0]
        bad = case.find("failure")
        if bad is None:
            bad = case.find("error")
        verdict = bad.get("type") if bad is not None else "holds"
        text = (bad.text if bad is not None else case.findtext("system-out")) or ""
        values = dict(re.findall(r"\b(min|max|value) ([-+0-9.e]+|inf)", text.rsplit("; ", 1)[-1]))
        value = number(values.get("value", "-"))
        lo = number(values["min"]) if "min" in values else value
        hi = number(values["max"]) if "max" in values else value
        answer.shown[name] = Shown(lo, hi, verdict, digits=6)
    return answer


# -- sweep and regions ---------------------------------------------------------------

def sweep_csv(argv: Sequence[str]) -> Answer:
    """`afsmc sweep` of one point, as CSV: a row per property, full floats."""
    r = run_cli("sweep", *argv, "-j", "1")
    crashed(r, "sweep")
    refused = refusal(r.err + r.out)
    if refused:
        return Answer(code=refused[0], message=refused[1])
    answer = Answer()
    for row in csv.DictReader(io.StringIO(r.out)):
        value = number(row["value"])
        lo = number(row["min"]) if row["min"] else value
        hi = number(row["max"]) if row["max"] else value
        answer.shown[row["property"]] = Shown(lo, hi, row.get("verdict") or None)
    return answer


def sweep_json(argv: Sequence[str]) -> Answer:
    """`afsmc sweep --json` of one point: its point's properties, full floats."""
    r = run_cli("sweep", *argv, "-j", "1", "--json")
    crashed(r, "sweep --json")
    data = json.loads(r.out)
    refused = json_refusal(data)
    if refused:
        return Answer(code=refused[0], message=refused[1])
    answer = Answer()
    (point,) = data["points"]
    for p in point["properties"]:
        lo = p["min"] if p["min"] is not None else p["value"]
        hi = p["max"] if p["max"] is not None else p["value"]
        answer.shown[p["name"]] = Shown(lo, hi, p.get("verdict"))
    return answer


def regions_verdict(holds: float, fails: float, unknown: float) -> str:
    """What the regions of the whole box say of the requirement: `holds` if no region
    fails and none is unknown, `fails` if none holds and none is unknown, `depends` if
    some hold and some fail, else `undecided`."""
    if fails == 0 and unknown == 0:
        return "holds"
    if holds == 0 and unknown == 0:
        return "fails"
    if holds > 0 and fails > 0:
        return "depends"
    return "undecided"


def regions(argv: Sequence[str], name: str) -> Answer:
    """`afsmc regions --json` over the mission's own box: no bounds, a verdict (see
    `regions_verdict`), shown as property `name`."""
    r = run_cli("regions", *argv, "--json", "-j", "1")
    crashed(r, "regions")
    data = json.loads(r.out)
    refused = json_refusal(data)
    if refused:
        return Answer(code=refused[0], message=refused[1])
    verdict = regions_verdict(data["holds"], data["fails"], data["unknown"])
    return Answer(shown={name: Shown(None, None, verdict)})


# -- the Python API ------------------------------------------------------------------

def api(path: str, properties: Sequence[str], options: Mapping[str, Any]) -> Any:
    """`afsmc.load(path).verify(...)`: the `Results`, or the AfsmError it raised."""
    import afsmc

    try:
        return afsmc.load(path).verify(list(properties), **options)
    except afsmc.AfsmError as exc:
        return exc


def api_refusal(res: Any) -> Answer | None:
    import afsmc

    if isinstance(res, afsmc.AfsmError):
        code = next((d.code for d in res.diagnostics if d.severity.name == "ERROR"), None)
        return Answer(code=str(code), message=str(res).splitlines()[0])
    return None


def api_results(res: Any, options: Mapping[str, Any]) -> Answer:
    """`Results[name]`: each `PropertyResult`'s min/max/value and verdict, and its paths
    (or why there are none) when `witness` was asked."""
    answer = api_refusal(res) or Answer()
    if answer.code is None:
        for p in res.properties:
            lo = p.min if p.min is not None else p.value
            hi = p.max if p.max is not None else p.value
            verdict = p.verdict.kind if p.verdict is not None else None
            answer.shown[p.name] = Shown(lo, hi, verdict)
            if options.get("witness") and not p.witnesses and not p.witness_note:
                answer.notes.append(f"witness=2: {p.name} has no paths and no witness_note")
            if options.get("strategy") and p.strategy is None and p.turns is None:
                answer.notes.append(f"strategy=True: {p.name} has no strategy and no turns")
    return answer


def api_pandas(res: Any) -> Answer:
    """`Results.to_pandas()`: a row per property, columns min/max/value/verdict."""
    answer = api_refusal(res) or Answer()
    if answer.code is None:
        df = res.to_pandas()

        def cell(name: str, column: str) -> Any:
            if column not in df.columns:
                return None
            v = df.loc[name, column]
            return None if isinstance(v, float) and math.isnan(v) else v

        for name in df.index:
            value = cell(name, "value")
            lo = cell(name, "min") if cell(name, "min") is not None else value
            hi = cell(name, "max") if cell(name, "max") is not None else value
            answer.shown[str(name)] = Shown(lo, hi, cell(name, "verdict"))
    return answer


def api_html(res: Any) -> Answer:
    """`Results._repr_html_()`: the table Jupyter shows, 6 digits."""
    answer = api_refusal(res) or Answer()
    if answer.code is None:
        page = res._repr_html_()
        heads = [html.unescape(h) for h in re.findall(r"<th>(.*?)</th>", page)]
        for row in re.findall(r"<tr>((?:<td>.*?</td>)+)</tr>", page):
            cells = dict(zip(heads, (html.unescape(c)
                                     for c in re.findall(r"<td>(.*?)</td>", row)),
                             strict=True))
            value = number(cells.get("value", ""))
            lo = number(cells["min"]) if cells.get("min") else value
            hi = number(cells["max"]) if cells.get("max") else value
            answer.shown[cells["property"]] = Shown(lo, hi, cells.get("verdict") or None,
                                                    digits=6)
    return answer


def api_sweep(path: str, point: str, properties: Sequence[str],
              options: Mapping[str, Any]) -> Answer:
    """`afsmc.load(path).sweep(NAME, "v:v").to_pandas()` of one point: a row per property,
    columns min/max/value and (a requirement's) verdict, as the CLI's CSV."""
    import afsmc

    name, values = point.split("=")
    try:
        sw = afsmc.load(path).sweep(name, values, properties=list(properties) or None,
                                    jobs=1, **options)
    except afsmc.AfsmError as exc:
        return api_refusal(exc) or Answer()
    answer = Answer()
    for row in sw.to_pandas().to_dict("records"):
        cell = {k: None if isinstance(v, float) and math.isnan(v) else v
                for k, v in row.items()}
        lo = cell["min"] if cell["min"] is not None else cell["value"]
        hi = cell["max"] if cell["max"] is not None else cell["value"]
        answer.shown[str(cell["property"])] = Shown(lo, hi, cell.get("verdict") or None)
    return answer


# -- diagram and simulate ------------------------------------------------------------

def svg_texts(path: Path) -> list[list[str]]:
    """The texts of each node (`<g class="node">`) of a Graphviz SVG, in order."""
    page = path.read_text(encoding="utf-8")
    groups = re.findall(r'<g id="[^"]*" class="node">(.*?)</g>', page, re.S)
    return [[html.unescape(t) for t in re.findall(r"<text[^>]*>(.*?)</text>", g, re.S)]
            for g in groups]


def diagram(argv: Sequence[str], tmp: Path) -> tuple[Answer, list[list[str]]]:
    """`afsmc diagram ... -o FILE.svg`: the refusal, or the texts of its nodes."""
    out = tmp / "diagram.svg"
    r = run_cli("diagram", *argv, "-o", str(out))
    crashed(r, "diagram")
    refused = refusal(r.err + r.out)
    if refused:
        return Answer(code=refused[0], message=refused[1]), []
    assert r.code == 0, r.err
    return Answer(), svg_texts(out)


RANGE = r"([-+0-9.e]+|n/a|inf)(?: – ([-+0-9.e]+|n/a|inf))?"


def diagram_results(argv: Sequence[str], results: Path, names: Sequence[str],
                    tmp: Path) -> Answer:
    """`afsmc diagram --results verify.json`: the note `name: lo – hi (uniform u)` of
    each property (4 digits) and a verdict word in it, if any."""
    answer, nodes = diagram([*argv, "--results", str(results)], tmp)
    if answer.code is None:
        lines = [t for node in nodes for t in node]
        for name in names:
            line = next((t for t in lines if t.startswith(f"{name}: ")), None)
            if line is None:
                answer.notes.append(f"--results: no note for {name}")
                continue
            m = re.match(rf"{re.escape(name)}: {RANGE}", line)
            assert m, line
            lo = number(m.group(1))
            hi = number(m.group(2)) if m.group(2) else lo
            verdict = next((v for v in VERDICTS if re.search(rf"\b{v}\b", line)), None)
            answer.shown[name] = Shown(lo, hi, verdict, digits=4)
    return answer


def diagram_strategy(argv: Sequence[str], name: str, tmp: Path,
                     midpoint: bool = False) -> Answer:
    """`afsmc diagram --strategy min:NAME`: the note `min strategy of NAME: v` (6 digits;
    `... of NAME at the midpoint: v` with interval probabilities), shown as the property's
    lower bound."""
    answer, nodes = diagram([*argv, "--strategy", f"min:{name}"], tmp)
    if answer.code is None:
        texts = [t for node in nodes for t in node]
        head = f"min strategy of {name}" + (" at the midpoint" if midpoint else "") + ": "
        line = next((t for t in texts if t.startswith(head)), None)
        if line is None:
            answer.notes.append(f"--strategy: no note '{head}...'")
        else:
            answer.shown[name] = Shown(number(line.rsplit(": ", 1)[1]), None, digits=6)
    return answer


def diagram_witness(argv: Sequence[str], name: str, tmp: Path) -> tuple[Answer, float | None]:
    """`afsmc diagram --witness NAME`: the note `most probable path of NAME: p, n steps`
    (`way to miss` for a requirement's violations); returns the path's probability (no
    bound of the property is shown)."""
    answer, nodes = diagram([*argv, "--witness", name], tmp)
    if answer.code is not None:
        return answer, None
    texts = [t for node in nodes for t in node]
    line = next((t for t in texts if t.startswith((f"most probable path of {name}: ",
                                                   f"most probable way to miss {name}: "))),
                None)
    if line is None:
        answer.notes.append(f"--witness: no note 'most probable path of {name}: ...'")
        return answer, None
    return answer, float(line.split(": ", 1)[1].split(",")[0])


def diagram_reach(argv: Sequence[str], mode: str, name: str, tmp: Path) -> Answer:
    """`afsmc diagram --reach`: the `P(reach) lo – hi` in the box of `mode` (4 digits),
    shown as property `name` (whose target is that mode)."""
    answer, nodes = diagram([*argv, "--reach"], tmp)
    if answer.code is None:
        box = next((node for node in nodes if mode in node
                    and any(t.startswith("P(reach)") for t in node)), None)
        if box is None:
            answer.notes.append(f"--reach: no P(reach) in the box of {mode}")
            return answer
        text = next(t for t in box if t.startswith("P(reach)"))
        m = re.match(rf"P\(reach\) {RANGE}", text)
        assert m, text
        lo = number(m.group(1))
        answer.shown[name] = Shown(lo, number(m.group(2)) if m.group(2) else lo, digits=4)
    return answer


def simulate_strategy(argv: Sequence[str], name: str) -> tuple[Answer, tuple[float, float]]:
    """`afsmc simulate --strategy min:NAME --json`: Storm's min it names (full float), and
    the estimate's confidence interval."""
    r = run_cli("simulate", *argv, "--strategy", f"min:{name}", "--runs", "2000", "--json")
    crashed(r, "simulate")
    data = json.loads(r.out)
    refused = json_refusal(data)
    if refused:
        return Answer(code=refused[0], message=refused[1]), (math.nan, math.nan)
    est = next(p for p in data["properties"] if p["name"] == name)
    shown = Shown(data["strategy"]["value"], None)
    return Answer(shown={name: shown}), (est["low"], est["high"])
