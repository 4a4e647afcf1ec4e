"""JANI text grows with the expression, not with the square of its nesting: JANI's
operators are binary, so a 4,000-term sum in a guard nests 4,000 levels, and written
indented all the way each level carried the indentation of those above it (the issue's
2.3 GB file). Past INDENTED_LEVELS a value is written on one line; the JSON is the same."""

from __future__ import annotations

import json

from afsmc.backends import jani
from afsmc.compiler import load
from afsmc.lower.lowering import lower
from afsmc.stack import run_deep
from tests.conftest import ROOT


def _guarded(n: int) -> str:
    src = (ROOT / "examples" / "overtake.afsm").read_text(encoding="utf-8")
    key = "action Continue in Pass when "
    terms = " + ".join("left" if k % 2 else "clear" for k in range(n))
    return src.replace(key, f"{key}({terms}) >= 0 && ")


def _size(n: int) -> int:
    """The bytes of the JANI of an n-term guard, checked to be the emitted JSON."""
    model = jani.emit(lower(load("overtake.afsm", text=_guarded(n)).model))
    out = jani.dumps(model)
    assert json.loads(out) == model
    return len(out.encode())


def test_a_4000_term_guard_is_under_a_megabyte_of_the_same_json() -> None:
    sizes = [run_deep(lambda: _size(1000)), run_deep(lambda: _size(4000))]
    assert sizes[1] < 1_000_000, sizes
    assert sizes[1] < 5 * sizes[0], sizes  # 4x the terms, about 4x the text


def test_shallow_values_are_written_as_json_dumps_indents_them() -> None:
    model = {"a": [1, {"b": [], "c": {}}, "x\\u00e9"], "op": "≤", "d": {"e": None}}
    assert jani.dumps(model) == json.dumps(model, indent=2, ensure_ascii=False) + "\n"
