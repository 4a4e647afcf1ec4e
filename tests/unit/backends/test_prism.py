"""The PRISM backend: Storm builds every example and reads what afsmc writes; values agree
with closed forms."""

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
from tests.conftest import EXAMPLES, run_cli
from tests.storm_util import storm_prism

pytestmark = pytest.mark.storm

# Small instances for the test suite; the defaults are for people (two_uav: 950 k
# states at its defaults, 74 k here).
SMALL = {"uav": {"WIDTH": "2", "HEIGHT": "2", "T_LIMIT": "100"},
         "two_uav": {"OBJECTS": "1", "T_LIMIT": "60"}}


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
    comp = model.composition  # type: ignore[attr-defined]
    # an interleaving leaves who moves next to the scheduler, whatever the resolution
    interleaved = comp is not None and comp.kind == "interleaving" and \
        comp.ties != "uniform" and len(comp.agents) > 1
    expect = "MDP" if interleaved or (resolution == "nondet"
                                      and model.is_nondeterministic) else "DTMC"  # type: ignore[attr-defined]
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
        if name.endswith(("_min", "_max")):  # an interleaving: min and max over who moves
            base, end = name[:-4], name[-3:]
            lo = bounds[f"{base}_min"] if end == "min" else -math.inf
            hi = bounds[f"{base}_max"] if end == "max" else math.inf
        else:
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


def _model(tmp: Path, text: str) -> object:
    path = tmp / "spec.afsm"
    path.write_text(text)
    return load(str(path)).model


def test_nested_implication_means_the_same_to_storm(tmp_path: Path) -> None:
    """afsm reads `a => b => c` as `a => (b => c)`; Storm's PRISM parser groups to the
    left, so the output must carry parentheses. With a, b, c false it is true."""
    model = _model(tmp_path, """
machine imp;
var a : bool init false;
var b : bool init false;
var c : bool init false;
mode A = 0 initial;
mode B = 1 final;
action Go in A { goto B; }
label L = a => b => c;
property p = P=? [ F<=0 "L" ];
""")
    _, values = storm_prism(lower(model), tmp_path)  # type: ignore[arg-type]
    assert values["p"] == 1.0
