"""Tuple variables: a one-field tuple takes a plain value, with the answer of a plain
variable."""

from __future__ import annotations

from pathlib import Path

import pytest

pytestmark = pytest.mark.storm


def test_a_one_field_tuple_takes_a_plain_value(tmp_path: Path) -> None:
    """`var p : (x: [0..2]) init 1` and `p := (2)`: one field takes a plain value (`(2)` is
    the number 2), neither is E217/E237. The answer equals a plain variable's."""
    import json

    from tests.conftest import run_cli

    def value(text: str) -> float:
        path = tmp_path / "t.afsm"
        path.write_text(text)
        r = run_cli("verify", str(path), "--json")
        assert r.code == 0, r.err
        return float(json.loads(r.out)["properties"][0]["value"])

    head = "mode A initial;\nmode B final;\n"
    tup = value(head + "var p : (x: [0..2]) init 1;\n"
                "action a in A { 0.5: goto B, p := (2); 0.5: goto B, p := p.x; }\n"
                "property q = P=? [ F p.x == 2 ];\n")
    plain = value(head + "var x : [0..2] init 1;\n"
                  "action a in A { 0.5: goto B, x := 2; 0.5: goto B, x := x; }\n"
                  "property q = P=? [ F x == 2 ];\n")
    assert tup == plain == 0.5
