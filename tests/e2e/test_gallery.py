"""The gallery: every mission in examples/ is a clean, formatted and complete example, and
docs/gallery.md (with its diagrams) is what scripts/gen_gallery.py writes from them now.

That the PRISM and JANI routes agree on every example (states, transitions and every
property's value) is tests/unit/backends/test_jani.py's `test_examples_agree_with_prism`,
which takes every examples/*.afsm; `test_the_backend_tests_take_every_example` keeps it so.
"""

from __future__ import annotations

import shutil
from pathlib import Path

import pytest

import afsmc
from tests.conftest import EXAMPLES, ROOT, run_cli, script_module

gen = script_module("gen_gallery")
FILES = sorted(EXAMPLES.glob("*.afsm"))
IDS = [p.stem for p in FILES]
GALLERY = {ex.stem: ex for ex in gen.examples(ROOT)}


@pytest.mark.parametrize("path", FILES, ids=IDS)
def test_every_example_checks_without_a_warning(path: Path) -> None:
    diagnostics = afsmc.load(str(path), consts=GALLERY[path.stem].consts).check()
    assert not diagnostics, [f"{d.code}: {d.message}" for d in diagnostics]


def test_every_example_is_formatted() -> None:
    r = run_cli("fmt", "--check", *map(str, FILES))
    assert r.code == 0, r.err


@pytest.mark.parametrize("path", FILES, ids=IDS)
def test_every_example_is_a_complete_mission(path: Path) -> None:
    model = afsmc.load(str(path), consts=GALLERY[path.stem].consts).model
    assert gen.leading_comment(path.read_text(encoding="utf-8")), "no leading comment"
    assert model.labels and model.rewards and model.properties
    assert any(c.is_interval for c in model.constants), "no interval constant"
    if path.stem not in ("patrol", "uav"):  # the language's first two examples predate them
        assert any(p.threshold is not None for p in model.properties), "no requirement"


def test_the_backend_tests_take_every_example() -> None:
    from tests.unit.backends.test_jani import EXAMPLE_FILES

    assert EXAMPLE_FILES == FILES


def test_the_page_has_every_example_and_its_diagram() -> None:
    page = (ROOT / gen.PAGE).read_text(encoding="utf-8")
    for path in FILES:
        assert f"\n## {path.stem}\n" in page and f"](#{path.stem}): " in page
        svg = ROOT / gen.PICTURES / f"{path.stem}.svg"
        assert svg.read_bytes().lstrip().startswith(b"<?xml"), svg
    drawn = sorted(p.stem for p in (ROOT / gen.PICTURES).glob("*.svg"))
    assert drawn == IDS


@pytest.mark.storm
@pytest.mark.slow  # verifies every example (the UAV's default instance: ~6 s) and draws it
def test_the_page_is_current() -> None:
    files = gen.build(ROOT)
    assert sorted(files) == sorted([gen.PAGE, *(f"{gen.PICTURES}/{s}.svg" for s in IDS)])
    assert gen.stale(ROOT, files) == [], f"run `{gen.REGENERATE}`"


def test_the_leading_comment_is_the_paragraphs_before_the_code() -> None:
    text = "// One\n// two.\n//\n// Three.\nmachine m;\n// not this\n"
    assert gen.leading_comment(text) == ["One two.", "Three."]
    assert gen.leading_comment("machine m;\n") == []


def test_an_args_file_sets_the_instance(tmp_path: Path) -> None:
    (tmp_path / "examples").mkdir()
    shutil.copy(EXAMPLES / "patrol.afsm", tmp_path / "examples" / "patrol.afsm")
    (tmp_path / "examples" / "patrol.gallery.args").write_text(
        "# A shorter corridor.\n--const CELLS=2\n--const ROUNDS=1  # one round\n")
    [ex] = gen.examples(tmp_path)
    assert ex.consts == {"CELLS": "2", "ROUNDS": "1"} and ex.why == "A shorter corridor."
    line = gen.instance_line(ex, afsmc.load(str(ex.path), consts=ex.consts))
    assert line == ("Instance: `CELLS=2`, `ROUNDS=1`, from `examples/patrol.gallery.args`. "
                    "A shorter corridor.")


@pytest.mark.parametrize("text", ["--const\n", "--engine sparse\n", "--const CELLS\n"])
def test_an_args_file_holds_only_constants(text: str, tmp_path: Path) -> None:
    path = tmp_path / "m.gallery.args"
    path.write_text(text)
    with pytest.raises(SystemExit, match="expected `--const NAME=VALUE` pairs"):
        gen.read_args(path)


@pytest.mark.storm
def test_an_example_at_its_args_is_verified_at_them(tmp_path: Path) -> None:
    (tmp_path / "examples").mkdir()
    shutil.copy(EXAMPLES / "patrol.afsm", tmp_path / "examples" / "patrol.afsm")
    (tmp_path / "examples" / "patrol.gallery.args").write_text("--const CELLS=2\n")
    [ex] = gen.examples(tmp_path)
    lines, svg = gen.section(ex)
    small = afsmc.load(str(ex.path), consts={"CELLS": 2}).verify()
    text = "\n".join(lines)
    assert f"builds {small.raw.model.states:,} states" in text
    assert "`afsmc verify examples/patrol.afsm @examples/patrol.gallery.args`" in text
    finish = small["finish"]
    assert f"| finish | `P=? [ F \"done\" ]` | {gen.short(finish.min, gen.DIGITS)} | " \
           f"{gen.short(finish.max, gen.DIGITS)} | – |" in text
    assert svg.lstrip().startswith(b"<?xml")


def test_an_args_file_may_ask_for_symmetry(tmp_path: Path) -> None:
    path = tmp_path / "m.gallery.args"
    path.write_text("# Six.\n--const N=6\n--symmetry\n")
    assert gen.read_args(path) == ({"N": "6"}, "Six.")
    assert gen._symmetric(path)
    assert not gen._symmetric(tmp_path / "none.gallery.args")
