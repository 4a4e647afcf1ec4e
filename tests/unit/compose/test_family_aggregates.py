"""`count(e)`, `all(e)` and `any(e)` over a family's members (afsmc.resolve.templates):
`e` once per member with the family's name replaced by the member's. The oracles: the
same labels written out over the members (the same compiled PRISM, the same values), and
examples/fleet.afsm's own counters (`finished == N` is `all(r.mode == Finished)`,
`lost > 0` is `any(r.mode == Stranded)`) at two sizes of the family."""

from __future__ import annotations

from pathlib import Path

import pytest

from afsmc.backends.prism import emit
from afsmc.compiler import load, lowered
from afsmc.diagnostics import CompileError
from afsmc.verify.core.api import run
from tests.conftest import EXAMPLES

FLEET = (EXAMPLES / "fleet.afsm").read_text(encoding="utf-8")
COUNTS = """
label two   = count(r.mode == Finished) >= 2;
label every = all(r.mode == Finished);
label some  = any(r.mode in {Stranded});
property two   = P=? [ F "two" ];
property every = P=? [ F "every" ];
property some  = P=? [ F "some" ];
"""
# the same, written out over three robots
WRITTEN = """
label two   = (r1.mode == Finished ? 1 : 0) + (r2.mode == Finished ? 1 : 0) + (r3.mode == Finished ? 1 : 0) >= 2;
label every = r1.mode == Finished && r2.mode == Finished && r3.mode == Finished;
label some  = r1.mode in {Stranded} || r2.mode in {Stranded} || r3.mode in {Stranded};
property two   = P=? [ F "two" ];
property every = P=? [ F "every" ];
property some  = P=? [ F "some" ];
"""


def _file(tmp_path: Path, name: str, text: str) -> str:
    path = tmp_path / name
    path.write_text(text, encoding="utf-8")
    return str(path)


def _prism(path: str) -> str:
    out = emit(lowered(load(path).model)).model
    return "\n".join(line for line in out.splitlines() if not line.startswith("//"))


def test_counts_compile_to_the_labels_written_out(tmp_path: Path) -> None:
    counted = _file(tmp_path, "fleet.afsm", FLEET + COUNTS)
    (tmp_path / "w").mkdir()
    written = _file(tmp_path / "w", "fleet.afsm", FLEET + WRITTEN)
    assert _prism(counted) == _prism(written)


@pytest.mark.storm
@pytest.mark.parametrize("n", [2, 3])
def test_all_and_any_are_the_missions_counters(tmp_path: Path, n: int) -> None:
    path = _file(tmp_path, "fleet.afsm", FLEET + COUNTS + """
property every_f = P=? [ F finished == N ];
property some_f  = P=? [ F lost > 0 ];
""")
    res = run(path, isolate=False, consts={"N": n},
              properties=["every", "every_f", "some", "some_f", "two"])
    by = {p.name: p for p in res.properties}
    for mine, counter in (("every", "every_f"), ("some", "some_f")):
        assert by[mine].min is not None and by[mine].max is not None
        assert by[mine].min == pytest.approx(by[counter].min, abs=1e-9)
        assert by[mine].max == pytest.approx(by[counter].max, abs=1e-9)
    # at least two of two robots finish is every robot finishing
    if n == 2:
        assert by["two"].min == pytest.approx(by["every"].min, abs=1e-9)
    assert res.symmetry is not None and res.symmetry.reason is None  # alike still


@pytest.mark.parametrize(("label", "says"), [
    ("r.mode == Finished", "'r' is a family of agents (r1, r2, r3)"),
    ("count(r1.done == 2) > 0", "count(...) takes an expression that reads one family"),
    ("any(r.done == 2, r.b == 0)", "any(...) takes one expression"),
])
def test_a_family_read_outside_them_or_a_bad_count_is_e253(tmp_path: Path, label: str,
                                                           says: str) -> None:
    path = _file(tmp_path, "bad.afsm", FLEET + f"label bad = {label};\n")
    with pytest.raises(CompileError) as err:
        load(path)
    (d,) = [d for d in err.value.diagnostics if d.code == "E253"]
    assert d.message.startswith(says), d.message
    assert d.span is not None and d.span.line == FLEET.count("\n") + 1


def test_a_count_without_a_family_says_what_it_needs(tmp_path: Path) -> None:
    text = FLEET.replace("agent r[1..N] : Robot;", "agents r1 = Robot(), r2 = Robot();")
    path = _file(tmp_path, "pair.afsm", text + "label two = count(r1.mode == Finished) > 0;\n")
    with pytest.raises(CompileError) as err:
        load(path)
    (d,) = [d for d in err.value.diagnostics if d.code == "E233"]
    assert d.message == "unknown function 'count'"
    assert d.hint is not None and d.hint.startswith(
        "count(...) ranges over a family's members, and no family is declared")
