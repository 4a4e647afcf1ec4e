"""Inputs at the edges of what afsmc accepts: byte-order marks, argument files, repeated
or non-finite constants, numbers beyond 64 bits, names PRISM or Storm reserve."""

from __future__ import annotations

from pathlib import Path

from afsmc.syntax.fmt import format_text
from tests.conftest import run_cli

BOM = "\ufeff"

SMALL = """machine small;
var x : [0..3] init 0;
mode A = 0 initial;
mode B = 1 final;
action Up in A when x < 3 { x += 1; }
action Done in A when x == 3 { goto B; }
label done = mode == B;
property reach = P=? [ F "done" ];
"""


def test_a_leading_byte_order_mark_is_skipped(tmp_path: Path) -> None:
    path = tmp_path / "bom.afsm"
    path.write_text(BOM + SMALL, encoding="utf-8")
    assert run_cli("check", str(path)).code == 0
    bad = tmp_path / "bad.afsm"
    bad.write_text(BOM + "const int 5;\n", encoding="utf-8")
    r = run_cli("check", str(bad))
    assert r.code == 1 and f"{bad}:1:11: error[E101]: unexpected '5'" in r.err
    assert "\n 1 | const int 5;\n   |           ^\n" in r.err


def test_fmt_keeps_a_byte_order_mark() -> None:
    out = format_text(BOM + "machine  small ;\n" + SMALL.split("\n", 1)[1])
    assert out.startswith(BOM + "machine small;\n") and out.count(BOM) == 1
    assert format_text(out) == out
