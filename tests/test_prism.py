"""The PRISM backend: Storm builds every example; values agree with closed forms; the
output is byte-deterministic and pinned by golden files."""

from __future__ import annotations

import json
import math
from functools import cache
from pathlib import Path

import pytest
import stormpy

from afsmc.backends.prism import emit
from afsmc.compiler import load
from afsmc.lower.lowering import RESOLUTIONS, lower
from tests.conftest import CASES, EXAMPLES, ROOT, run_cli
from tests.storm_util import storm_prism

# Small instances for the test suite; the defaults are for people.
SMALL = {"uav": {"WIDTH": "2", "HEIGHT": "2", "T_LIMIT": "100"}}


def _load_text(text: str, tmp: Path, name: str = "spec") -> object:
    path = tmp / f"{name}.afsm"
    path.write_text(text)
    return load(str(path)).model


GEOMETRIC = """
machine geo;
const prob P_WIN = 0.3;
const prob Q = 0.05;
mode Try = 0 initial;
mode Won = 1 final;
mode Lost = 2 final;
action Attempt in Try { P_WIN: goto Won; 1 - P_WIN: skip; }
hazard Fail from {Try} with probability Q { goto Lost; }
label won = mode == Won;
property win = P=? [ F "won" ];
property steps = R{"steps"}=? [ F mode != Try ];
rewards steps { mode == Try : 1; }
"""


def test_geometric_trials_with_a_hazard_match_the_closed_form(tmp_path: Path) -> None:
    model = _load_text(GEOMETRIC, tmp_path)
    _, values = storm_prism(lower(model), tmp_path)  # type: ignore[arg-type]
    p, q = 0.3, 0.05
    stay = (1 - q) * (1 - p)
    assert values["win"] == pytest.approx((1 - q) * p / (1 - stay), abs=1e-6)
    assert values["steps"] == pytest.approx(1 / (1 - stay), abs=1e-6)


CLIMB = """
machine climb;
param int K = 5;
const prob P_OK = 0.9;
const int STEP = [1, 2];
var x : [0..K] init 0 clamp;
mode Climb = 0 initial;
mode Top = 1 final;
mode Fell = 2 final;
// The weights pick Up below K and Stop at K: Definition 2's arg-max.
action Up in Climb weight (x < K ? 0.8 : 0.2) { P_OK: x += STEP; 1 - P_OK: goto Fell; }
action Stop in Climb weight 0.5 { goto Top; }
label top = mode == Top;
property top = P=? [ F "top" ];
"""


def _uniform_climb(k: int, s: float) -> float:
    # independent recurrence: f(x) = s * (f(x+1) + f(x+2)) / 2 below k, f(>=k) = 1
    f = [0.0] * (k + 3)
    for x in range(k + 2, -1, -1):
        f[x] = 1.0 if x >= k else s * (f[x + 1] + f[x + 2]) / 2
    return f[0]


def test_weights_and_interval_constants_give_the_expected_bounds(tmp_path: Path) -> None:
    model = _load_text(CLIMB, tmp_path)
    k, s = 5, 0.9
    _, nondet = storm_prism(lower(model, "nondet"), tmp_path, "n")  # type: ignore[arg-type]
    assert nondet["top_min"] == pytest.approx(s**k, abs=1e-6)
    assert nondet["top_max"] == pytest.approx(s ** math.ceil(k / 2), abs=1e-6)
    _, uniform = storm_prism(lower(model, "uniform"), tmp_path, "u")  # type: ignore[arg-type]
    assert uniform["top"] == pytest.approx(_uniform_climb(k, s), abs=1e-6)
    _, lo = storm_prism(lower(model, "lo"), tmp_path, "lo")  # type: ignore[arg-type]
    _, hi = storm_prism(lower(model, "hi"), tmp_path, "hi")  # type: ignore[arg-type]
    assert lo["top"] == pytest.approx(s**k, abs=1e-6)
    assert hi["top"] == pytest.approx(s ** math.ceil(k / 2), abs=1e-6)


EXAMPLE_FILES = sorted(EXAMPLES.glob("*.afsm"))


@cache
def _example(stem: str) -> object:
    path = EXAMPLES / f"{stem}.afsm"
    return load(str(path), SMALL.get(stem, {})).model


@pytest.mark.parametrize("path", EXAMPLE_FILES, ids=[p.stem for p in EXAMPLE_FILES])
@pytest.mark.parametrize("resolution", RESOLUTIONS)
def test_storm_builds_every_example(path: Path, resolution: str, tmp_path: Path) -> None:
    model = _example(path.stem)
    built, values = storm_prism(lower(model, resolution), tmp_path)  # type: ignore[arg-type]
    assert built.nr_states > 0
    expect = "MDP" if resolution == "nondet" and model.is_nondeterministic else "DTMC"  # type: ignore[attr-defined]
    assert built.model_type.name == expect
    for name, value in values.items():
        assert math.isfinite(value), name


@pytest.mark.parametrize("path", EXAMPLE_FILES, ids=[p.stem for p in EXAMPLE_FILES])
def test_uniform_lies_between_min_and_max(path: Path, tmp_path: Path) -> None:
    model = _example(path.stem)
    if not model.is_nondeterministic:  # type: ignore[attr-defined]
        pytest.skip("no interval constants")
    _, bounds = storm_prism(lower(model, "nondet"), tmp_path, "n")  # type: ignore[arg-type]
    _, uniform = storm_prism(lower(model, "uniform"), tmp_path, "u")  # type: ignore[arg-type]
    for name, value in uniform.items():
        lo, hi = bounds.get(f"{name}_min"), bounds.get(f"{name}_max")
        assert lo is not None and hi is not None
        assert lo - 1e-6 <= value <= hi + 1e-6, name


def test_uav_default_instance_reaches_every_mode_of_figure_1(tmp_path: Path) -> None:
    """All 17 modes of the paper (0..16) are reachable for the default constants."""
    model = load(str(EXAMPLES / "uav.afsm")).model
    out = emit(lower(model, "lo"))
    path = tmp_path / "uav.prism"
    path.write_text(out.model)
    prog = stormpy.parse_prism_program(str(path))
    opts = stormpy.BuilderOptions()
    opts.set_build_state_valuations()
    built = stormpy.build_model(prog, options=opts)
    seen = {json.loads(str(built.state_valuations.to_json(s)))["mode"]
            for s in range(built.nr_states)}
    assert set(range(17)) <= seen
    assert len(model.modes) == 18 and {m.number for m in model.modes} == set(range(18))


@pytest.mark.parametrize("stem", ["patrol", "uav"])
def test_prism_output_is_deterministic_and_golden(stem: str, update_golden: bool,
                                                  monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.chdir(ROOT)
    first = run_cli("compile", f"examples/{stem}.afsm", "-o", "-")
    second = run_cli("compile", f"examples/{stem}.afsm", "-o", "-")
    assert first.code == 0 and first.out == second.out
    golden = CASES / f"prism_{stem}" / "expected.prism"
    if update_golden or not golden.exists():
        golden.parent.mkdir(parents=True, exist_ok=True)
        golden.write_text(first.out)
    assert first.out == golden.read_text()


def test_compile_to_stdout_marks_where_the_properties_begin(tmp_path: Path) -> None:
    """`-o -` printed the model and its properties back to back (review 18): split at the
    marked line, each part is what Storm reads from the two files."""
    import stormpy

    r = run_cli("compile", str(EXAMPLES / "patrol.afsm"), "-o", "-")
    assert r.code == 0, r.err
    model, props = r.out.split("\n// ==== patrol.props\n")
    written = run_cli("compile", str(EXAMPLES / "patrol.afsm"), "-o", f"{tmp_path}/")
    assert written.code == 0, written.err
    assert model == (tmp_path / "patrol.prism").read_text()
    assert props == (tmp_path / "patrol.props").read_text()
    program = stormpy.parse_prism_program(str(tmp_path / "patrol.prism"))
    assert len(stormpy.parse_properties(props, program)) == props.count(";")


def test_compile_replaces_only_an_output_suffix(tmp_path: Path) -> None:
    """`-o out/patrol.cells-4` wrote out/patrol.prism: '.cells-4' was taken for a suffix."""
    src = str(EXAMPLES / "patrol.afsm")
    for given, written in (("patrol.cells-4", "patrol.cells-4"), ("m.prism", "m"),
                           ("n.props", "n"), ("plain", "plain")):
        r = run_cli("compile", src, "-o", str(tmp_path / given))
        assert r.code == 0, r.err
        assert (tmp_path / f"{written}.prism").exists() and \
            (tmp_path / f"{written}.props").exists(), (given, sorted(tmp_path.iterdir()))
    # a target of one file takes the name as given (review 19: x.json became x.json.jani)
    for target, given, written in (("jani", "x.json", "x.json"), ("jani", "y", "y.jani"),
                                   ("dot", "g.gv", "g.gv"), ("dot", "h.dot", "h.dot")):
        r = run_cli("compile", src, "-t", target, "-o", str(tmp_path / given))
        assert r.code == 0 and (tmp_path / written).exists(), (given, r.err)
    # but DOT text under a picture's name is a mistake (review 22): `diagram` draws one
    r = run_cli("compile", src, "-t", "dot", "-o", str(tmp_path / "h.svg"))
    assert r.code == 2 and not (tmp_path / "h.svg").exists(), r.err


def test_compile_writes_files_and_never_overwrites_its_input(tmp_path: Path) -> None:
    src = tmp_path / "patrol.afsm"
    src.write_text((EXAMPLES / "patrol.afsm").read_text())
    r = run_cli("compile", str(src), "-o", str(tmp_path / "out") + "/")
    assert r.code == 0, r.err
    assert (tmp_path / "out" / "patrol.prism").read_text().startswith("// Generated by afsmc")
    assert (tmp_path / "out" / "patrol.props").exists()
    before = src.read_text()
    r = run_cli("compile", str(src), "-o", str(tmp_path / "patrol.afsm"))
    assert r.code == 0  # the suffix is replaced: patrol.prism and patrol.props beside it
    assert src.read_text() == before
    assert not list(tmp_path.glob(".*.tmp*"))


def test_compile_refuses_to_overwrite_the_input(tmp_path: Path) -> None:
    src = tmp_path / "m.prism"  # an .afsm file unluckily named like the output
    src.write_text((EXAMPLES / "patrol.afsm").read_text())
    r = run_cli("compile", str(src), "-o", str(tmp_path))
    assert r.code == 1 and "refusing to overwrite the input" in r.err
    assert src.read_text() == (EXAMPLES / "patrol.afsm").read_text()


def test_compile_refusing_one_output_writes_none(tmp_path: Path) -> None:
    # The input is named like the second output (.props): the .prism must not be left behind.
    src = tmp_path / "z.props"
    src.write_text((EXAMPLES / "patrol.afsm").read_text())
    r = run_cli("compile", str(src), "-o", str(tmp_path))
    assert r.code == 1 and "refusing to overwrite the input" in r.err, r.err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["z.props"]
    assert "wrote" not in r.err


def test_compile_with_an_unwritable_second_output_writes_none(tmp_path: Path) -> None:
    # A directory where the .props would go: found before the .prism is written.
    (tmp_path / "patrol.props").mkdir()
    r = run_cli("compile", str(EXAMPLES / "patrol.afsm"), "-o", str(tmp_path))
    assert r.code == 1 and "error[E003]" in r.err and "it is a directory" in r.err, r.err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["patrol.props"]
    assert "wrote" not in r.err


EMPTY_REWARDS = """machine er;
mode S = 0 initial;
mode D = 1 final;
action Go in S { 0.5: goto D; 0.5: skip; }
rewards r { }
property q = R{"r"}=? [ F mode == D ];
property c = R{"r"}=? [ C<=3 ];
"""


@pytest.mark.parametrize(("via", "engine"), [("prism", "sparse"), ("prism", "hybrid"),
                                             ("jani", "sparse")])
def test_an_empty_reward_structure_is_zero(tmp_path: Path, via: str, engine: str) -> None:
    # Storm's PRISM parser refuses `rewards "r" endrewards`: the backend writes `true : 0`.
    from afsmc.verify import run

    path = tmp_path / "er.afsm"
    path.write_text(EMPTY_REWARDS)
    res = run(str(path), via=via, engine=engine)  # type: ignore[arg-type]
    assert {p.name: p.value for p in res.properties} == {"q": 0.0, "c": 0.0}


def test_the_smallest_64_bit_int_is_prism_that_storm_reads(tmp_path: Path) -> None:
    # Storm's PRISM parser reads -9223372036854775808 as minus an overflowing literal (E411);
    # afsmc writes it as (-9223372036854775807 - 1). Both routes agree, and x > K holds.
    path = tmp_path / "m.afsm"
    path.write_text("machine m;\nmode A = 0 initial final;\nconst int K = -9223372036854775808;\n"
                    "var x : [-5..1] init 0;\nlabel l = x > K;\n"
                    'property p = P=? [ F "l" ];\n', encoding="utf-8")
    for via in ("prism", "jani"):
        r = run_cli("verify", str(path), "--via", via, "--json")
        assert r.code == 0, r.err
        assert json.loads(r.out)["properties"][0]["value"] == 1.0
