"""Every `--json` output of `verify`, `sweep`, `regions` and `simulate` is valid under its
published JSON Schema (docs/schemas/NAME.schema.json, checked with `jsonschema`) and is
taken by its pydantic model (`afsmc.answer`, strict): the real commands on small missions
of each kind (an MDP, a DTMC, interval probabilities, composed missions timed and
interleaving), with a requirement, `--strategy`, `--witness`, `--exact`, failures and
interrupts. Each case also checks that the output has the keys it is meant to cover."""

from __future__ import annotations

import json
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import jsonschema
import pytest

from afsmc.answer.schema import MODELS, schema
from tests.conftest import EXAMPLES, run_cli
from tests.specs import BOOL_PARAM

pytestmark = pytest.mark.storm

PATROL = str(EXAMPLES / "patrol.afsm")
TWO_UAV = str(EXAMPLES / "two_uav.afsm")
SMALL = "CELLS=2,ROUNDS=1"
SMALL_UAV = "OBJECTS=1,T_LIMIT=25"
DONE = 'P>=0.6 [ F "done" ]'
# a DTMC with warnings (W302, W304), one path into "done" and none into "nowhere"
FEW_PATHS = """machine few;
var x : [0..3] init 0;
mode A = 0 initial;
mode B = 1 final;
mode C = 2 final;
action Go in A when x < 2 { 0.5: x := x + 1; 0.5: goto C; }
action Fin in A when x == 2 { goto B; }
const int UNUSED = 3;
label done = mode == B;
label nowhere = false;
property p = P=? [ F "done" ];
property q = P=? [ F "nowhere" ];
"""
# a name declared twice: a diagnostic with a related place
TWICE = """machine twice;
const int K = 1;
const int K = 2;
mode A = 0 initial;
mode B = 1 final;
action Go in A { goto B; }
"""


@pytest.fixture(scope="module")
def files(tmp_path_factory: pytest.TempPathFactory) -> dict[str, str]:
    """The missions of the cases: the examples, and variants of them written here."""
    tmp = tmp_path_factory.mktemp("missions")
    patrol = Path(PATROL).read_text(encoding="utf-8")
    uav = Path(TWO_UAV).read_text(encoding="utf-8")
    variants = {
        # a DTMC: no interval constant left
        "dtmc": patrol.replace("const int MOVE_COST = [1, 2];", "const int MOVE_COST = 1;"),
        # interval probabilities
        "iv": patrol.replace("const prob P_FAULT  = 0.01;", "const prob P_FAULT = [0.005, 0.03];"),
        # agents that interleave: the strategies choose who moves (turns)
        "interleaving": uav.replace("compose timed ties order;", "compose interleaving;"),
        "nondet": uav.replace("compose timed ties order;", "compose timed ties nondet;"),
        # an expected reward that is infinite where "done" is missed
        "forever": patrol + 'property forever = R{"steps"}=? [ F "done" ];\n',
    }
    variants["iv_forever"] = variants["iv"] + 'property forever = R{"steps"}=? [ F "done" ];\n'
    out = {"patrol": PATROL, "two_uav": TWO_UAV}
    for name, text in (("few", FEW_PATHS), ("twice", TWICE), ("windy", BOOL_PARAM)):
        (tmp / f"{name}.afsm").write_text(text, encoding="utf-8")
        out[name] = str(tmp / f"{name}.afsm")
    for name, text in variants.items():
        assert text not in (patrol, uav), name  # the replacement took
        path = tmp / f"{name}.afsm"
        path.write_text(text, encoding="utf-8")
        out[name] = str(path)
    return out


def _no_constant(name: str) -> Any:
    raise ValueError(f"{name} is not JSON")


def validate(command: str, text: str) -> Any:
    """The object `text` holds, after both validators took it; JSON's own grammar only (no
    NaN or Infinity, which Python's json module would read). The model dumps it back as
    it was, keys in the same order: the models describe the output exactly."""
    obj = json.loads(text, parse_constant=_no_constant)
    jsonschema.Draft202012Validator(schema(command)).validate(obj)
    answer = MODELS[command].model_validate_json(text, strict=True)
    back = answer.model_dump(mode="json", by_alias=True)
    assert back == obj
    assert _keys(back) == _keys(obj)
    return obj


def _keys(obj: Any) -> Any:
    """The object's keys, in order, at every level."""
    if isinstance(obj, dict):
        return [(k, _keys(v)) for k, v in obj.items()]
    if isinstance(obj, list):
        return [_keys(v) for v in obj]
    return None


def argv_of(argv: list[str], files: dict[str, str]) -> list[str]:
    """The case's arguments with each {mission} replaced by its file."""
    out = []
    for a in argv:
        for name, path in files.items():
            a = a.replace("{" + name + "}", path)
        out.append(a)
    return out


def has(obj: Any, path: str) -> bool:
    """Whether `obj` has the key path `a.0.b` (list indexes as numbers)."""
    for part in path.split("."):
        if isinstance(obj, list) and part.isdigit() and int(part) < len(obj):
            obj = obj[int(part)]
        elif isinstance(obj, dict) and part in obj:
            obj = obj[part]
        else:
            return False
    return True


# (id, argv with {mission} placeholders, exit codes allowed, key paths the output must have)
CASES: list[tuple[str, list[str], tuple[int, ...], tuple[str, ...]]] = [
    ("verify-mdp", ["verify", "{patrol}", "-c", SMALL], (0,),
     ("uniform_model.states", "properties.5.uniform")),
    ("verify-dtmc", ["verify", "{dtmc}", "-c", SMALL], (0,), ("properties.0.value",)),
    ("verify-interval-probabilities", ["verify", "{iv}", "-c", SMALL, "-f", DONE], (0, 1),
     ("probability_intervals.properties.0.min_at", "properties.0.reason")),
    ("verify-strategy", ["verify", "{patrol}", "-c", SMALL, "-p", "finish", "--strategy"], (0,),
     ("properties.0.strategy.min.0.indifferent",)),
    ("verify-witness", ["verify", "{patrol}", "-c", SMALL, "-p", "finish", "--witness", "2"],
     (0,), ("properties.0.witnesses.1.steps.0.choice", "properties.0.witness_strategy")),
    ("verify-requirement-exact", ["verify", "{patrol}", "-c", SMALL, "-f", DONE, "--exact"],
     (0,), ("properties.0.exact.min", "properties.0.threshold.op")),
    ("verify-requirement-fails-witness", ["verify", "{patrol}", "-c", SMALL, "-f",
                                          'P<=0.01 [ F "done" ]', "--witness", "1"], (1,),
     ("properties.0.witnesses.0", "properties.0.witness_violates")),
    ("verify-warnings-fewer-paths", ["verify", "{few}", "-p", "p", "--witness", "5"], (0,),
     ("warnings.1.line", "properties.0.witness_note", "properties.0.witnesses.0")),
    ("verify-no-path", ["verify", "{few}", "-p", "q", "--witness", "2"], (0,),
     ("properties.0.witness_note",)),
    ("verify-jani", ["verify", "{patrol}", "-c", SMALL, "-p", "finish", "--via", "jani"], (0,),
     ("via",)),
    ("verify-related-place", ["verify", "{twice}"], (1,), ("diagnostics.0.related.0.line",)),
    ("verify-infinite-reward", ["verify", "{patrol}", "-c", SMALL, "-f",
                                'R{"steps"}=? [ F "done" ]'], (0,), ("properties.0.infinite",)),
    ("verify-bisim", ["verify", "{patrol}", "-c", SMALL, "-p", "finish", "--bisim"], (0,),
     ("model.quotient_states",)),
    ("verify-dd", ["verify", "{patrol}", "-c", SMALL, "-p", "finish", "--engine", "dd"], (0,),
     ("model.engine",)),
    ("verify-timed-agents", ["verify", "{two_uav}", "-c", SMALL_UAV, "-p", "success",
                             "--strategy", "--witness", "1"], (0,),
     ("properties.0.strategy.max", "properties.0.witnesses.0.steps.0.changes")),
    ("verify-interleaving", ["verify", "{interleaving}", "-c", SMALL_UAV, "-p", "success",
                             "--strategy"], (0,), ("properties.0.turns.min",)),
    ("verify-ties-nondet", ["verify", "{nondet}", "-c", SMALL_UAV, "-p", "success",
                            "--witness", "1"], (0,), ("properties.0.witnesses",)),
    # a query Storm fails on: the diagnostics, and the values it had (issue 44 lists it)
    ("verify-failed-query", ["verify", "{patrol}", "-c", SMALL, "-f",
                             'P>=0.5 ["halted" U "done"]', "--witness", "2"], (0, 1),
     ("properties.0.uniform",)),
    ("verify-max-states", ["verify", "{patrol}", "-c", SMALL, "--max-states", "5"], (1,),
     ("diagnostics.0.hint",)),
    ("verify-unknown-constant", ["verify", "{patrol}", "-c", "NOPE=1"], (1,), ("diagnostics.0",)),
    ("sweep-const", ["sweep", "{patrol}", "-c", "CELLS=2:3,ROUNDS=1", "-p", "finish", "-f",
                     DONE, "-j", "1"], (0,), ("requirements.0.ranges.0.from",
                                             "properties.1.formula")),
    ("sweep-bound", ["sweep", "{patrol}", "-c", SMALL, "--bound", "5:10:5", "-p",
                     "finish_soon", "-j", "1"], (0,), ("points.1.properties.0.formula",)),
    ("sweep-grid", ["sweep", "{patrol}", "-c", "CELLS=2:3", "-c", "ROUNDS=1:2", "-p", "finish",
                    "-f", 'P>=0.93 [ F "done" ]', "-j", "1"], (0,),
     ("rows.3.point.ROUNDS", "requirements.0.points")),
    ("sweep-dtmc", ["sweep", "{dtmc}", "-c", "CELLS=2:3,ROUNDS=1", "-p", "finish", "-j", "1"],
     (0,), ("points.0.properties.0.value",)),
    ("sweep-bool", ["sweep", "{windy}", "-c", "WINDY=false,true", "-j", "1"], (0,),
     ("points.1.x",)),
    ("sweep-interval-probabilities", ["sweep", "{iv}", "-c", "CELLS=2:3,ROUNDS=1", "-f", DONE,
                                      "-j", "1"], (0,), ("requirements",)),
    ("sweep-infinite-reward", ["sweep", "{forever}", "-c", "CELLS=2:3,ROUNDS=1", "-p",
                               "forever", "-j", "1"], (0,), ("points.0.properties.0.infinite",)),
    ("sweep-some-points-fail", ["sweep", "{patrol}", "-c", "CELLS=2:3,ROUNDS=1", "-p", "finish",
                                "--max-states", "90", "-j", "1"], (1,),
     ("diagnostics.0", "points.0.properties")),
    ("sweep-grid-some-points-fail", ["sweep", "{patrol}", "-c", "CELLS=2:3", "-c",
                                     "ROUNDS=1:2", "-p", "finish", "--max-states", "150",
                                     "-j", "1"], (1,), ("diagnostics.0", "rows.0.point")),
    ("sweep-no-such-property", ["sweep", "{patrol}", "-c", "CELLS=2:3", "-p", "nope"], (1,),
     ("diagnostics.0.hint",)),
    ("regions-interval-probability", ["regions", "{iv}", "-c", SMALL, "--require",
                                      'P>=0.9 [ F "done" ]', "--feasible"], (0,),
     ("feasible.P_FAULT", "regions.0.bounds.P_FAULT")),
    ("regions-infeasible", ["regions", "{iv}", "-c", SMALL, "--require",
                            'P>=0.999 [ F "done" ]', "--feasible", "--max-rounds", "2"], (0,),
     ("feasible", "feasible_method")),
    ("regions-two-parameters", ["regions", "{two_uav}", "-c", SMALL_UAV, "--param",
                                "ALPHA=0.1:0.3", "--param", "P_SLIP=0.01:0.1", "--require",
                                'P>=0.5 [ F "success" ]', "--max-rounds", "3"], (0,),
     ("box.ALPHA", "regions.0.bounds.P_SLIP")),
    ("regions-not-a-parameter", ["regions", "{iv}", "--param", "CELLS=1:2", "--require", DONE],
     (1,), ("diagnostics.0.line",)),
    ("simulate-traces", ["simulate", "{patrol}", "-c", SMALL, "--runs", "300", "--traces", "2"],
     (0,), ("traces.1.1.action", "properties.0.estimate")),
    ("simulate-strategy", ["simulate", "{patrol}", "-c", SMALL, "--runs", "300", "--strategy",
                           "min:finish"], (0,), ("strategy.value",)),
    ("simulate-interleaving", ["simulate", "{interleaving}", "-c", SMALL_UAV, "--runs", "300",
                               "--traces", "1"], (0,), ("scheduler", "traces.0.0.vars")),
    ("simulate-interval-probabilities-undecided", ["simulate", "{iv}", "-c", SMALL, "--runs",
                                                   "300", "--at", "max", "--max-steps", "3"],
     (0,), ("properties.5.high",)),
    ("simulate-dtmc-floor", ["simulate", "{dtmc}", "-c", SMALL, "--runs", "300", "--resolve",
                             "floor"], (0,), ("resolve",)),
    ("simulate-warnings", ["simulate", "{few}", "--runs", "100"], (0,), ("warnings.0.code",)),
    ("simulate-no-such-strategy", ["simulate", "{patrol}", "--runs", "10", "--strategy",
                                   "min:nope"], (1,), ("diagnostics.0",)),
]


# the cases of more than about 2 s (Storm's symbolic engine, the composed missions)
SLOW = {"verify-dd", "verify-timed-agents", "verify-interleaving", "verify-ties-nondet"}


@pytest.mark.parametrize(("argv", "codes", "keys"), [
    pytest.param(*c[1:], id=c[0], marks=[pytest.mark.slow] if c[0] in SLOW else [])
    for c in CASES])
def test_the_json_of_each_case_is_valid(files: dict[str, str], argv: list[str],
                                        codes: tuple[int, ...], keys: tuple[str, ...]) -> None:
    r = run_cli(*argv_of(argv, files), "--json")
    assert r.code in codes, (r.code, r.err, r.out)
    obj = validate(argv[0], r.out)
    missing = [k for k in keys if not has(obj, k)]
    assert not missing, (missing, obj)


def test_a_key_the_schema_does_not_declare_is_refused(files: dict[str, str]) -> None:
    # Both validators are strict: an unknown key, a null where a key is absent instead,
    # and a number where a string is due fail.
    r = run_cli("verify", files["patrol"], "-c", SMALL, "-p", "finish", "--json")
    good = json.loads(r.out)
    for change in ({"extra": 1}, {"infinite": None}, {"formula": 1}):
        obj = json.loads(r.out)
        obj["properties"][0] |= change
        with pytest.raises(jsonschema.ValidationError):
            jsonschema.Draft202012Validator(schema("verify")).validate(obj)
        with pytest.raises(ValueError):
            MODELS["verify"].model_validate_json(json.dumps(obj), strict=True)
    validate("verify", json.dumps(good))


@pytest.fixture
def stop_second(monkeypatch: pytest.MonkeyPatch) -> Iterator[Any]:
    """`stop_second(module, name)`: the function runs once for real; its second call is a
    Ctrl-C (a KeyboardInterrupt where the user's would arrive)."""

    def patch(module: Any, name: str) -> None:
        real = getattr(module, name)
        calls: list[int] = []

        def once(*args: Any, **kwargs: Any) -> Any:
            calls.append(1)
            if len(calls) > 1:
                raise KeyboardInterrupt
            return real(*args, **kwargs)

        monkeypatch.setattr(module, name, once)

    yield patch


def test_an_interrupted_sweep_is_valid(files: dict[str, str], stop_second: Any) -> None:
    import importlib

    stop_second(importlib.import_module("afsmc.verify.reports.sweep"), "evaluate")
    r = run_cli("sweep", files["patrol"], "-c", "CELLS=2:3,ROUNDS=1", "-p", "finish", "-j", "1",
                "--json")
    assert r.code == 130, r.err
    obj = validate("sweep", r.out)
    assert obj["interrupted"] is True and len(obj["points"]) == 1


def test_an_interrupted_simulation_is_valid(files: dict[str, str], stop_second: Any) -> None:
    from afsmc.sim import run

    stop_second(run, "simulate_batch")
    r = run_cli("simulate", files["patrol"], "-c", SMALL, "--runs", "400", "--batch-size", "100",
                "--json")
    assert r.code == 130, r.err
    obj = validate("simulate", r.out)
    assert obj["interrupted"] is True and obj["runs"] == 100


def test_an_interrupted_verify_is_valid(files: dict[str, str],
                                        monkeypatch: pytest.MonkeyPatch) -> None:
    from afsmc.verify.engines.guard import Interrupted
    from tests.unit.verify.test_verify_partial_results import _stop_after_first_answer

    _stop_after_first_answer(monkeypatch, lambda v: Interrupted(dict(v)))
    r = run_cli("verify", files["patrol"], "-c", SMALL, "-p", "finish", "--no-uniform",
                "--engine", "sparse", "--json")
    assert r.code == 130, r.err
    obj = validate("verify", r.out)
    assert obj["interrupted"] is True and obj["properties"][0]["max"] is None


def test_an_interrupted_region_check_is_valid(files: dict[str, str],
                                              stop_second: Any) -> None:
    from afsmc.verify.reports import regions

    stop_second(regions, "_round")
    r = run_cli("regions", files["iv"], "-c", SMALL, "--require", 'P>=0.9 [ F "done" ]',
                "--json")
    assert r.code == 130, r.err
    assert validate("regions", r.out) == {"interrupted": True, "diagnostics": []}


@pytest.mark.parametrize("command", list(MODELS))
def test_an_internal_error_is_valid(command: str, capsys: pytest.CaptureFixture[str]) -> None:
    # the report of a bug in afsmc, as the CLI prints it under --json
    from afsmc.cli import _internal_error

    assert _internal_error(RuntimeError("a bug"), as_json=True) == 3
    out, err = capsys.readouterr()
    Path(err.split("the traceback is in ", 1)[1].split(";", 1)[0]).unlink()
    assert validate(command, out)["diagnostics"][0]["code"] == "E009"


# Outputs that are not what the schemas publish today: each is a bug to fix in the command
# (strict: the test fails once it is fixed, and the mark should go).

def test_an_infinite_bound_over_interval_probabilities_is_json(files: dict[str, str]) -> None:
    r = run_cli("verify", files["iv_forever"], "-c", SMALL, "-p", "forever", "--json")
    assert r.code == 0, r.err
    validate("verify", r.out)


def test_the_strategy_of_an_infinite_reward_is_json(files: dict[str, str]) -> None:
    r = run_cli("simulate", files["forever"], "-c", SMALL, "--runs", "100", "--strategy",
                "max:forever", "--json")
    assert r.code == 0, r.err
    validate("simulate", r.out)


@pytest.mark.slow
def test_an_unreachable_dask_scheduler_is_one_json_object(files: dict[str, str]) -> None:
    import dask
    import distributed  # noqa: F401  (its defaults first: leaving set() would drop them)

    with dask.config.set({"distributed.comm.timeouts.connect": "1s"}):
        r = run_cli("sweep", files["patrol"], "-c", "CELLS=2:3,ROUNDS=1", "-p", "finish",
                    "--dask", "tcp://127.0.0.1:1", "--json")
    assert r.code == 1, r.err
    validate("sweep", r.out)
