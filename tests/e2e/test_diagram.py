"""Mission diagrams (afsmc compile -t dot, afsmc diagram) and the mode-graph checks.

Expected nodes and edges are read from the spec text with regular expressions here, not
from afsmc's own mode graph, so the diagram is checked against an independent reading.
"""

from __future__ import annotations

import json
import re
import xml.etree.ElementTree as ET
from pathlib import Path

import pytest

from tests.conftest import CASES, EXAMPLES, run_cli

MISSION = CASES / "dot_mission17" / "mission17.afsm"


SVG = "{http://www.w3.org/2000/svg}"


def _mode_set(text: str, modes: dict[str, int]) -> list[int]:
    text = text.strip()
    if text == "*":
        return sorted(modes.values())
    out: list[int] = []
    for item in text.strip("{}").split(","):
        item = item.strip()
        if ".." in item:
            lo, hi = item.split("..")
            out += range(int(lo), int(hi) + 1)
        elif item.isdigit():
            out.append(int(item))
        else:
            out.append(modes[item])
    return sorted(out)


def read_spec(text: str) -> tuple[dict[str, int], set[tuple[int, int]],
                                   dict[str, tuple[list[int], set[int]]]]:
    """Modes, edges of single-mode actions, and hazards (sources, targets) of a spec.

    Final modes are absorbing, so a hazard never leaves them."""
    text = re.sub(r"//[^\n]*", "", text)
    modes = {m[0]: int(m[1]) for m in re.findall(r"\bmode\s+(\w+)\s*=\s*(\d+)", text)}
    finals = {modes[m] for m in re.findall(r"\bmode\s+(\w+)\s*=\s*\d+[^;]*\bfinal\b", text)}
    edges: set[tuple[int, int]] = set()
    for where, body in re.findall(r"\baction\s+\w+\s+in\s+(\w+)[^{]*\{(.*?)\}", text, re.S):
        src = modes[where]
        for outcome in [o for o in body.split(";") if o.strip()]:
            goto = re.search(r"goto\s+(\w+)", outcome)
            edges.add((src, modes[goto.group(1)] if goto else src))
    hazards: dict[str, tuple[list[int], set[int]]] = {}
    for name, where, body in re.findall(r"\bhazard\s+(\w+)\s+from\s+(\{[^}]*\}|\*)[^{]*\{(.*?)\}",
                                        text, re.S):
        targets = {modes[g] for g in re.findall(r"goto\s+(\w+)", body)}
        hazards[name] = ([n for n in _mode_set(where, modes) if n not in finals], targets)
    return modes, edges, hazards


def paper_set(numbers: list[int]) -> str:
    """The paper's notation, written out independently: {0..15}, {1..11, 14, 15}."""
    parts, i = [], 0
    while i < len(numbers):
        j = i
        while j + 1 < len(numbers) and numbers[j + 1] == numbers[j] + 1:
            j += 1
        if j - i >= 2:
            parts.append(f"{numbers[i]}..{numbers[j]}")
        else:
            parts += [str(n) for n in numbers[i:j + 1]]
        i = j + 1
    return "{" + ", ".join(parts) + "}"


def svg_graph(path: Path) -> tuple[dict[str, str], set[tuple[str, str]], dict[tuple[str, str], str]]:
    """Node id -> label text, the edges, and edge -> label text of a rendered SVG."""
    root = ET.parse(path).getroot()
    nodes: dict[str, str] = {}
    edges: set[tuple[str, str]] = set()
    labels: dict[tuple[str, str], str] = {}
    for g in root.iter(f"{SVG}g"):
        title = g.find(f"{SVG}title")
        if title is None or title.text is None:
            continue
        texts = " | ".join(t.text or "" for t in g.iter(f"{SVG}text"))
        if g.get("class") == "node":
            nodes[title.text] = texts
        elif g.get("class") == "edge":
            a, b = title.text.split("->")
            edges.add((a, b))
            labels[(a, b)] = texts
    return nodes, edges, labels


def test_diagram_of_a_figure1_mission_matches_the_spec(tmp_path: Path) -> None:
    out = tmp_path / "m.svg"
    r = run_cli("diagram", str(MISSION), "-o", str(out))
    assert r.code == 0, r.err
    nodes, edges, labels = svg_graph(out)
    modes, spec_edges, hazards = read_spec(MISSION.read_text())
    assert len(modes) == 17
    # one node per mode, labelled with its name and number
    for name, n in modes.items():
        assert nodes[f"m{n}"].split(" | ")[:2] == [name, str(n)]
    mode_edges = {(a, b) for a, b in edges if a.startswith("m") and b.startswith("m")}
    assert mode_edges == {(f"m{a}", f"m{b}") for a, b in spec_edges}
    # each hazard drawn once: an ellipse listing its modes in the paper's notation
    group_nodes = {k: v for k, v in nodes.items() if k not in {f"m{n}" for n in modes.values()}
                   and k != "start"}
    assert sorted(group_nodes.values()) == sorted(paper_set(s) for s, _ in hazards.values())
    assert "{0..15}" in group_nodes.values() and "{1..11, 14, 15}" in group_nodes.values()
    group_edges = {(nodes[a], b) for a, b in edges if a in group_nodes}
    assert group_edges == {(paper_set(s), f"m{t}") for s, ts in hazards.values() for t in ts}
    assert ("start", f"m{modes['Idle']}") in edges
    # labels: action names, and the probability of an outcome that is not certain
    assert labels[(f"m{modes['Initialise']}", f"m{modes['GoToSearch']}")] == "Check (0.95)"
    assert labels[(f"m{modes['Search']}", f"m{modes['Search']}")] == "Search (0.7)"
    assert labels[(f"m{modes['Idle']}", f"m{modes['TakeOff']}")] == "Launch"


def test_diagram_default_output_and_formats(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.chdir(tmp_path)
    r = run_cli("diagram", str(EXAMPLES / "patrol.afsm"))
    assert r.code == 0, r.err
    svg = (tmp_path / "patrol.svg").read_text()
    assert svg.lstrip().startswith("<?xml") and "<svg" in svg
    nodes, _, _ = svg_graph(tmp_path / "patrol.svg")
    modes, _, hazards = read_spec((EXAMPLES / "patrol.afsm").read_text())
    assert {f"m{n}" for n in modes.values()} <= set(nodes)
    assert {paper_set(s) for s, _ in hazards.values()} <= set(nodes.values())
    assert run_cli("diagram", str(EXAMPLES / "patrol.afsm"), "-o", "p.png").code == 0
    assert (tmp_path / "p.png").read_bytes().startswith(b"\x89PNG")
    assert run_cli("diagram", str(EXAMPLES / "patrol.afsm"), "-o", "p.pdf").code == 0
    assert (tmp_path / "p.pdf").read_bytes().startswith(b"%PDF")
    r = run_cli("diagram", str(EXAMPLES / "patrol.afsm"), "-o", "p.gif")
    assert r.code == 2 and ".svg, .png or .pdf" in r.err


def test_missing_dot_program_is_a_diagnostic(tmp_path: Path,
                                             monkeypatch: pytest.MonkeyPatch) -> None:
    empty = tmp_path / "bin"
    empty.mkdir()
    monkeypatch.setenv("PATH", str(empty))
    r = run_cli("diagram", str(EXAMPLES / "patrol.afsm"), "-o", str(tmp_path / "x.svg"))
    assert r.code == 1
    assert "error[E610]" in r.err and "dot" in r.err and "Traceback" not in r.err
    assert not (tmp_path / "x.svg").exists()


BROKEN = """\
machine broken;
var x : [0..3] init 0;
mode A = 0 initial;
mode B = 1;
mode C = 2;
mode D = 3 final;
mode E = 4;
action Step in A weight 0.5 { 0.5: goto B; 0.5: x := min(x + 1, 3); }
action Never in A when x > 5 { goto C; }
action Loser in A weight 0.2 { goto C; }
action Ping in B { goto E; }
action Pong in E { goto B; }
action Fin in C { goto D; }
"""


def _pos(text: str, needle: str, offset: int = 0) -> str:
    i = text.index(needle) + offset
    line = text.count("\n", 0, i) + 1
    col = i - (text.rfind("\n", 0, i) + 1) + 1
    return f"{line}:{col}"


def test_mode_graph_warnings_name_modes_and_actions(tmp_path: Path) -> None:
    spec = tmp_path / "broken.afsm"
    spec.write_text(BROKEN)
    r = run_cli("check", str(spec))
    assert r.code == 0, r.err
    # C is only entered by actions that never fire, so C and D are unreachable
    assert f"broken.afsm:{_pos(BROKEN, 'mode C')}: warning[W601]: mode C (2)" in r.err
    assert f"broken.afsm:{_pos(BROKEN, 'mode D')}: warning[W601]: mode D (3)" in r.err
    assert (f"broken.afsm:{_pos(BROKEN, 'Never in')}: warning[W603]: action Never can never "
            "fire: its guard never holds") in r.err
    assert (f"broken.afsm:{_pos(BROKEN, 'Loser in')}: warning[W603]: action Loser can never "
            "fire: an enabled competitor always has a larger weight (Step)") in r.err
    # B and E ping-pong forever: once there, the mission cannot end
    assert f"broken.afsm:{_pos(BROKEN, 'mode B')}: warning[W602]" in r.err
    assert f"broken.afsm:{_pos(BROKEN, 'mode E')}: warning[W602]" in r.err
    assert f"broken.afsm:{_pos(BROKEN, 'mode A')}: warning[W602]" in r.err  # A only leads there
    js = json.loads(run_cli("check", str(spec), "--json").out)
    assert sorted({d["code"] for d in js}) == ["W601", "W602", "W603"]
    # the picture shows them: grey dashed modes, dashed "(never)" edges
    dot = run_cli("compile", str(spec), "-t", "dot", "-o", "-").out
    assert re.search(r'm2 \[label="C\\n2\\n\(unreachable\)"[^\]]*style="rounded,filled,dashed"',
                     dot)
    assert re.search(r'm0 -> m2 \[label="Loser \(never\)\\nNever \(never\)"[^\]]*style=dashed',
                     dot)
    assert 'm1 [label="B\\n1\\n(cannot end)"' in dot


def test_no_mode_graph_warnings_for_the_examples() -> None:
    for spec in (EXAMPLES / "patrol.afsm", MISSION):
        r = run_cli("check", str(spec))
        assert r.code == 0 and not re.search(r"W60\d", r.err), r.err


CHAIN = """\
machine chain;
const prob P_B = 0.3;
const prob Q_A = 0.5;
var k : [0..2] init 0;
mode A = 0 initial;
mode B = 1 final;
mode C = 2;
mode D = 3 final;
action Go in A { P_B: goto B; 1 - P_B: goto C; }
action Back in C { Q_A: goto A; 1 - Q_A: goto D, k := 1; }
"""


CHOICE = """\
machine choice;
const int K = [1, 2];
var x : [0..2] init 0;
mode A = 0 initial;
mode B = 1;
mode E = 2 final;
mode F = 3 final;
action Set in A { goto B, x := K; }
action ToE in B when x == 2 { goto E; }
action ToF in B when x != 2 { goto F; }
"""


def _reach(svg: Path) -> dict[str, str]:
    nodes, _, _ = svg_graph(svg)
    return {v.split(" | ")[0]: v.split(" | ")[2] for k, v in nodes.items()
            if k.startswith("m") and v.count(" | ") >= 2}


@pytest.mark.storm
def test_reach_overlay_dtmc_matches_hand_computation(tmp_path: Path) -> None:
    spec = tmp_path / "chain.afsm"
    spec.write_text(CHAIN)
    r = run_cli("diagram", str(spec), "--reach", "-o", str(tmp_path / "c.svg"))
    assert r.code == 0, r.err
    p, q = 0.3, 0.5
    # From A: B with p, else C; from C: back to A with q, else D. Solve x = p + (1-p) q x.
    reach_b = p / (1 - (1 - p) * q)
    reach_d = (1 - p) * (1 - q) / (1 - (1 - p) * q)
    got = _reach(tmp_path / "c.svg")
    assert got["A"] == "P(reach) 1"
    assert got["B"] == f"P(reach) {reach_b:.4g}"
    assert got["C"] == f"P(reach) {1 - p:.4g}"
    assert got["D"] == f"P(reach) {reach_d:.4g}"


@pytest.mark.storm
def test_reach_overlay_mdp_gives_min_and_max(tmp_path: Path) -> None:
    spec = tmp_path / "choice.afsm"
    spec.write_text(CHOICE)
    r = run_cli("diagram", str(spec), "--reach", "-o", str(tmp_path / "c.svg"))
    assert r.code == 0, r.err
    got = _reach(tmp_path / "c.svg")
    # K in [1, 2] chosen by an adversary: E is reached iff it picks 2, F iff it picks 1.
    assert got["E"] == "P(reach) 0 – 1" and got["F"] == "P(reach) 0 – 1"
    assert got["B"] == "P(reach) 1"
    # resolved uniformly, each is reached with probability 1/2
    r = run_cli("diagram", str(spec), "--reach", "--resolve", "uniform", "-o",
                str(tmp_path / "u.svg"))
    assert r.code == 0, r.err
    assert _reach(tmp_path / "u.svg")["E"] == f"P(reach) {1 / 2:.4g}"


@pytest.mark.slow
@pytest.mark.storm
def test_reach_on_the_reduced_model_equals_storm_on_the_unreduced_one(tmp_path: Path) -> None:
    # --reach checks the reduced model in verify's guard; the oracle is Storm itself on
    # afsmc's unreduced PRISM (compile --no-reduce), one Pmin/Pmax per mode.
    import stormpy

    from afsmc.commands.diagram import mode_reachability
    from afsmc.compiler import load

    consts = {"WIDTH": "2", "HEIGHT": "2", "T_LIMIT": "100", "DEADLINE": "100"}
    model = load(str(EXAMPLES / "uav.afsm"), consts).model
    got, mdp = mode_reachability(model, "nondet")
    assert mdp
    r = run_cli("compile", str(EXAMPLES / "uav.afsm"), "--no-reduce", "-o",
                str(tmp_path / "u.prism"), *[a for k, v in consts.items()
                                             for a in ("--const", f"{k}={v}")])
    assert r.code == 0, r.err
    prog = stormpy.parse_prism_program(str(tmp_path / "u.prism"))
    numbers = sorted(m.number for m in model.modes)
    props = stormpy.parse_properties(
        "; ".join(f"P{op}=? [ F mode={n} ]" for n in numbers for op in ("min", "max")), prog)
    built = stormpy.build_model(prog, props)
    init = built.initial_states[0]
    want = [stormpy.model_checking(built, p).get_value(init) for p in props]
    assert sorted(got) == numbers
    for i, n in enumerate(numbers):
        assert got[n] == pytest.approx((want[2 * i], want[2 * i + 1]), abs=1e-9), n
    assert any(lo < hi for lo, hi in got.values())  # the intervals matter here


@pytest.mark.slow
@pytest.mark.storm
def test_reach_stops_at_max_states_with_e405(tmp_path: Path) -> None:
    out = tmp_path / "u.svg"
    r = run_cli("diagram", str(EXAMPLES / "uav.afsm"), "--reach", "--max-states", "100",
                "-o", str(out))
    assert r.code == 1 and "error[E405]" in r.err and "--max-states 100" in r.err, r.err
    assert "Traceback" not in r.err and not out.exists()


def test_results_json_overlay(tmp_path: Path) -> None:
    # the shape `afsmc verify --json` writes: null for what was not asked
    results = {"machine": "patrol", "properties": [
        {"name": "finish", "formula": 'P=? [ F "done" ]', "min": 0.25, "max": 0.5,
         "uniform": 0.375, "value": None},
        {"name": "fault", "formula": 'P=? [ F "halted" ]', "min": None, "max": None,
         "uniform": None, "value": 0.125},
        {"name": "steps", "formula": 'R{"steps"}=? [ F "done" ]', "min": 3, "max": None,
         "uniform": None, "value": None, "infinite": ["max"]}],
        "modes": [{"mode": "Dock", "min": 0.75, "max": 0.75}]}
    rj = tmp_path / "r.json"
    rj.write_text(json.dumps(results))
    out = tmp_path / "p.svg"
    r = run_cli("diagram", str(EXAMPLES / "patrol.afsm"), "--results", str(rj), "-o", str(out))
    assert r.code == 0, r.err
    nodes, _, _ = svg_graph(out)
    assert nodes["results"] == "finish: 0.25 – 0.5 (uniform 0.375) | fault: 0.125 | steps: 3 – inf"
    assert nodes["m1"] == "Dock | 1 | P(reach) 0.75"
    rj.write_text(json.dumps({**results, "constants": {"CELLS": 4, "ROUNDS": 3}}))
    r = run_cli("diagram", str(EXAMPLES / "patrol.afsm"), "--results", str(rj), "-o", str(out))
    assert r.code == 0, r.err  # the constants drawn
    for bad, said in (("{not json", "is not JSON"), ('{"x": 1}', '"properties" list'),
                      ('{"properties": [1]}', '"properties" list'),
                      (json.dumps({**results, "machine": "uav"}), "results of machine uav"),
                      (json.dumps({**results, "modes": [{"mode": "Nowhere", "value": 1}]}),
                       "machine patrol has no mode 'Nowhere'"),
                      (json.dumps({**results, "modes": [{"mode": "Dock", "min": "abc"}]}),
                       "mode Dock has min 'abc', not a number"),
                      (json.dumps({**results, "modes": [{"number": 1, "value": 1.5}]}),
                       "mode Dock has value 1.5, not a probability"),
                      (json.dumps({"properties": [{"name": "p", "max": True}]}),
                       "property p has max True, not a number"),
                      (json.dumps({"properties": [{"name": "p", "min": 0.6, "max": 0.4}]}),
                       "property p has min 0.6 above its max 0.4"),
                      (json.dumps({**results, "constants": {"CELLS": 6, "ROUNDS": 3}}),
                       "holds results for CELLS=6; the diagram is of CELLS=4"),
                      (json.dumps({"file": "p.afsm", "variable": "CELLS", "points": [],
                                   "properties": [{"name": "finish"}]}),
                       "is the output of `afsmc sweep`"),
                      (json.dumps({**results, "modes": [{"mode": "Dock", "value": 0.5},
                                                        {"number": 1, "value": 0.25}]}),
                       "mode Dock is listed twice"),
                      ('{"properties": [{"name": "p", "min": NaN}]}',
                       "property p has min nan, not a finite number"),
                      ('{"properties": [{"name": "p", "value": Infinity}]}',
                       "property p has value inf, not a finite number"),
                      (json.dumps({**results, "modes": [{"mode": "Dock"}]}),
                       "mode Dock has no value"),
                      (json.dumps({**results, "modes": [{"mode": "Dock", "number": 0,
                                                         "value": 0.5}]}),
                       "names mode Dock (number 1) and number 0 (Patrol)"),
                      (json.dumps({**results, "constants": []}), '"constants" is not an object'),
                      (json.dumps({"properties": [{"name": "p", "value": 1},
                                                  {"name": "p", "value": 2}]}),
                       "property p is listed twice"),
                      # `afsmc simulate --json`: its estimates showed as n/a
                      (json.dumps({"runs": 100, "properties": [
                          {"name": "finish", "estimate": 0.8, "low": 0.7, "high": 0.9}]}),
                       "is the output of `afsmc simulate`"),
                      (json.dumps({"properties": [{"name": "finish", "p": 0.8}]}),
                       "no property has a min, max, uniform or value")):
        rj.write_text(bad)
        r = run_cli("diagram", str(EXAMPLES / "patrol.afsm"), "--results", str(rj), "-o",
                    str(out))
        assert r.code == 1 and "error[E611]" in r.err and said in r.err, (bad, r.err)


@pytest.mark.storm
@pytest.mark.parametrize("option", [["--resolve", "uniform"], ["--max-states", "1000"]])
def test_reach_options_without_reach_are_usage_errors(tmp_path: Path, option: list[str]) -> None:
    """--resolve and --max-states only change what --reach computes: given alone they would
    be ignored, so the command line is refused (exit 2) and nothing is drawn."""
    out = tmp_path / "p.svg"
    r = run_cli("diagram", str(EXAMPLES / "patrol.afsm"), *option, "-o", str(out))
    assert r.code == 2 and f"{option[0]} only applies to --reach" in r.err, r.err
    assert not out.exists()
    r = run_cli("diagram", str(EXAMPLES / "patrol.afsm"), *option, "--reach", "-o", str(out))
    assert r.code == 0 and out.exists(), r.err


# The arrows of the paper's Figure 1 (the tikz \path list), by mode number.
FIGURE1 = {(0, 1), (1, 2), (2, 13), (2, 14), (3, 3), (3, 4), (3, 12), (4, 5), (5, 6), (6, 7),
           (7, 8), (7, 15), (8, 8), (8, 9), (8, 15), (8, 12), (9, 10), (10, 11), (11, 12),
           (11, 14), (12, 13), (13, 0), (14, 3), (15, 4), (15, 14)}


FIGURE1_GROUPS = {("{1..11, 14, 15}", 12), ("{0..15}", 16)}


def test_uav_diagram_has_every_arrow_of_figure1(tmp_path: Path) -> None:
    spec = EXAMPLES / "uav.afsm"
    out = tmp_path / "uav.svg"
    r = run_cli("diagram", str(spec), "-o", str(out))
    assert r.code == 0, r.err
    nodes, edges, _ = svg_graph(out)
    modes, spec_edges, hazards = read_spec(spec.read_text())
    assert set(range(17)) <= set(modes.values())
    assert {f"m{n}" for n in modes.values()} <= set(nodes)
    mode_edges = {(int(a[1:]), int(b[1:])) for a, b in edges
                  if a.startswith("m") and b.startswith("m")}
    assert mode_edges == spec_edges
    assert mode_edges >= FIGURE1
    group_edges = {(nodes[a], int(b[1:])) for a, b in edges if nodes.get(a, "").startswith("{")}
    assert group_edges == {(paper_set(s), t) for s, ts in hazards.values() for t in ts}
    assert group_edges >= FIGURE1_GROUPS


def test_a_failing_dot_program_is_e613_and_writes_nothing(tmp_path: Path,
                                                          monkeypatch: pytest.MonkeyPatch) -> None:
    broken = tmp_path / "bin"
    broken.mkdir()
    dot = broken / "dot"
    dot.write_text("#!/bin/sh\necho 'dot: cannot load plugins' >&2\nexit 1\n")
    dot.chmod(0o755)
    monkeypatch.setenv("PATH", f"{broken}:/usr/bin:/bin")
    r = run_cli("diagram", str(EXAMPLES / "patrol.afsm"), "-o", str(tmp_path / "x.svg"))
    assert r.code == 1
    assert "error[E613]" in r.err and "cannot load plugins" in r.err
    assert not (tmp_path / "x.svg").exists()


def test_a_storm_failure_at_reach_other_than_size_is_e612() -> None:
    from afsmc.commands.diagram import _reach_error
    from afsmc.verify.engines.storm import StormFailure

    err = _reach_error(StormFailure("check", "Storm  could not\n solve it"))
    (d,) = err.diagnostics
    assert d.code == "E612"
    assert d.message == ("Storm could not compute the reachability of the modes: "
                         "Storm could not solve it")
    assert [x.code for x in _reach_error(StormFailure("too-big", "big")).diagnostics] == ["E405"]


def test_a_witness_named_as_its_query_is_e407_that_says_how_to_write_it(tmp_path: Path) -> None:
    r = run_cli("diagram", str(EXAMPLES / "two_uav.afsm"), "--witness", "success_max",
                "-o", str(tmp_path / "w.svg"))
    assert r.code == 1 and "E407" in r.err and "--witness success_max" in r.err
    assert "write max:success" in r.err and not (tmp_path / "w.svg").exists()
