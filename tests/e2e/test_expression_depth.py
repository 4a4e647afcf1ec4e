"""Deep and long expressions: a 2,000-term expression goes through every command and the
Python API, and expressions nested past the parser's or Storm's limit are diagnostics."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from afsmc.syntax.parser import MAX_DEPTH
from tests.conftest import run_cli


def _chain(terms: int, term: str = "x * 0.00005") -> str:
    return " +\n    ".join([term] * terms)


def _long(terms: int) -> str:
    return f"""machine long;
var x : [0..3] init 0;
mode S = 0 initial;
mode D = 1 final;
formula f = {_chain(terms)};
action Go in S weight ({_chain(terms)}) {{ 0.5: goto D; 0.5: x := min(x + 1, 3); }}
label done = mode == D && f >= 0;
property p = P=? [ F<=5 "done" ];
"""


@pytest.fixture(scope="module")
def long_file(tmp_path_factory: pytest.TempPathFactory) -> Path:
    path = tmp_path_factory.mktemp("long") / "long.afsm"
    path.write_text(_long(2000), encoding="utf-8")
    return path


@pytest.mark.slow
@pytest.mark.parametrize("argv", [
    ["check"], ["check", "--json"], ["compile", "-t", "prism"], ["compile", "-t", "jani"],
    ["compile", "-t", "dot"], ["simulate", "--runs", "50"], ["fmt", "--check"],
], ids=lambda a: " ".join(a))
def test_a_2000_term_expression_goes_through_every_command(long_file: Path, tmp_path: Path,
                                                           argv: list[str]) -> None:
    extra = ["-o", str(tmp_path / "out")] if argv[0] == "compile" else []
    r = run_cli(*argv, str(long_file), *extra)
    assert "Traceback" not in r.err and "RecursionError" not in r.err, r.err[-2000:]
    assert r.code == (1 if argv[0] == "fmt" else 0), r.err[-2000:]  # fmt: would reformat


@pytest.mark.slow
@pytest.mark.storm
def test_a_2000_term_expression_verifies(long_file: Path) -> None:
    r = run_cli("verify", str(long_file), "--via", "jani", "--json")
    assert r.code == 0, r.err[-2000:]
    values = {p["name"]: p for p in json.loads(r.out)["properties"]}
    assert values["p"]["value"] == pytest.approx(1 - 0.5 ** 5)


@pytest.mark.slow
@pytest.mark.storm
def test_a_2000_term_expression_sweeps_in_worker_processes(long_file: Path) -> None:
    # Each worker process gives deep expressions the room one process has (no E114).
    r = run_cli("sweep", str(long_file), "--bound", "1:2:1", "-p", "p", "--jobs", "2",
                "--json")
    assert r.code == 0, r.err[-2000:]
    points = json.loads(r.out)["points"]
    assert [pt["properties"][0]["value"] for pt in points] == pytest.approx([0.5, 0.75])


@pytest.mark.slow
@pytest.mark.storm
def test_the_python_api_takes_deep_expressions_as_the_commands_do(long_file: Path) -> None:
    # load, run and sweep have the commands' room for deep expressions (without it, load
    # raises RecursionError on a case just below the depth limit).
    import sys
    import threading

    from afsmc.compiler import load
    from afsmc.verify import run, sweep

    limit = sys.getrecursionlimit()
    text = "machine m;\nmode S = 0 initial;\nmode D = 1 final;\naction Go in S weight (" \
        + "- " * (MAX_DEPTH - 10) + "1) { goto D; }\n"
    assert load("deep.afsm", text=text).model is not None
    res = run(str(long_file), via="jani")
    assert res.property("p").value == pytest.approx(1 - 0.5 ** 5)
    fig = sweep(str(long_file), "bound", [1, 2], kind="bound", properties=["p"], jobs=1)
    assert fig.curve("p", "value") == pytest.approx([0.5, 0.75])
    assert sys.getrecursionlimit() == limit  # given back afterwards

    # On another thread the limits stay as they are, since a thread's stack cannot grow:
    # the file may fail there with a RecursionError, but the process must not crash.
    seen: list[BaseException | None] = []

    def other() -> None:
        try:
            load("deep.afsm", text=text)
            seen.append(None)
        except RecursionError as exc:
            seen.append(exc)

    t = threading.Thread(target=other)
    t.start()
    t.join()
    assert len(seen) == 1


def test_an_expression_deeper_than_the_limit_is_a_diagnostic(tmp_path: Path) -> None:
    path = tmp_path / "deep.afsm"
    path.write_text(_long(MAX_DEPTH + 5), encoding="utf-8")
    r = run_cli("check", str(path))
    assert r.code == 1 and "Traceback" not in r.err
    assert f"{path}:5:13: error[E113]" in r.out + r.err
    minus = tmp_path / "minus.afsm"
    minus.write_text("machine m;\nmode S = 0 initial;\nmode D = 1 final;\n"
                     "action Go in S { " + "- " * (MAX_DEPTH + 600) + "0.5: goto D; 0.5: skip; }\n")
    r = run_cli("compile", "-t", "prism", str(minus), "-o", str(tmp_path / "m.prism"))
    assert r.code == 1 and "error[E113]" in r.out + r.err and "Traceback" not in r.err


def test_600_minus_signs_parse(tmp_path: Path) -> None:
    path = tmp_path / "minus.afsm"
    path.write_text("machine m;\nmode S = 0 initial;\nmode D = 1 final;\n"
                    "action Go in S { " + "- - " * 300 + "0.5: goto D; 0.5: skip; }\n")
    assert run_cli("check", str(path)).code == 0


@pytest.mark.slow
def test_formulas_nesting_too_deeply_once_inlined_are_a_diagnostic(tmp_path: Path) -> None:
    n = MAX_DEPTH - 10
    path = tmp_path / "chain.afsm"
    path.write_text(f"""machine fc;
var x : [0..3] init 0;
mode S = 0 initial;
mode D = 1 final;
formula f1 = {_chain(n, "x")};
formula f2 = f1 + {_chain(n, "x")};
formula f3 = f2 + {_chain(n, "x")};
action Go in S weight f3 / 100000 {{ 0.5: goto D; 0.5: x := min(x + 1, 3); }}
""", encoding="utf-8")
    r = run_cli("check", str(path))
    assert r.code == 1 and "Traceback" not in r.err
    assert "error[E246]: formula 'f3'" in r.out + r.err
    assert "'f2'" not in r.out + r.err


def _deep_label(depth: int) -> str:
    """A label and a guard that each nest `depth` levels deep, half of them in a formula."""
    half = depth // 2
    return f"""machine deep;
var x : [0..3] init 0;
mode S = 0 initial;
mode D = 1 final;
formula f = {" + ".join(["x"] * half)};
action Go in S when f + {" + ".join(["x"] * (depth - half - 1))} >= 0 {{
    0.5: goto D; 0.5: x := min(x + 1, 3);
}}
label l = f + {" + ".join(["x"] * (depth - half - 1))} > 100;
label done = mode == D;
property p = P=? [ F "done" ];
property q = P=? [ F "l" ];
"""


@pytest.mark.slow
@pytest.mark.storm
def test_expressions_storm_cannot_evaluate_are_e310_and_the_limit_builds(tmp_path: Path) -> None:
    """Storm's ExprTk stops at a stack depth of 10,000, below the parser's limit (E113 at
    5,000 levels) once formulas are inlined: `check` reports E310 past STORM_DEPTH, rather
    than letting verify fail with E403, and the limit itself builds through PRISM and JANI."""
    from afsmc.check.storm_depth import STORM_DEPTH

    path = tmp_path / "deep.afsm"
    path.write_text(_deep_label(STORM_DEPTH))
    assert run_cli("check", str(path)).code == 0
    for via in ("prism", "jani"):  # the oracle: Storm builds and checks the limit itself
        r = run_cli("verify", str(path), "--via", via, "--engine", "sparse", "--json")
        assert r.code == 0, r.err[-800:]
        values = {p["name"]: p["value"] for p in json.loads(r.out)["properties"]}
        assert values == {"p": pytest.approx(1.0), "q": pytest.approx(0.5)}  # x = 1 first
    path.write_text(_deep_label(STORM_DEPTH + 1))
    r = run_cli("check", str(path))
    assert r.code == 1 and "Traceback" not in r.err
    assert r.err.count("error[E310]") == 2, r.err[-2000:]
    assert f"label l nests {STORM_DEPTH + 1:,} levels deep once its formulas are inlined" in r.err
