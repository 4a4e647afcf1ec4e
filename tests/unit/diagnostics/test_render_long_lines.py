"""A source line longer than render.LONG_LINE is quoted in part, around the place: the
excerpt of each diagnostic is bounded, however long the line, and a short line is quoted
whole as before."""

from __future__ import annotations

import time

from afsmc.diagnostics import BOM, Diagnostic, Severity, Source, Span
from afsmc.diagnostics.render import LONG_LINE, render, render_all


def _diag(source: Source, start: int, end: int) -> Diagnostic:
    return Diagnostic("W304", Severity.WARNING, "constant is never used",
                      Span.at_offset(source, start, end))


def test_a_short_line_is_quoted_whole() -> None:
    source = Source("m.afsm", "machine m;\nconst int x = 1;\n")
    out = render(_diag(source, 21, 22))
    assert " 2 | const int x = 1;\n   |           ^" in out


def test_a_long_line_is_quoted_around_the_place_with_the_caret_under_it() -> None:
    decl = "const int x = 1; "
    text = BOM + decl * 10_000 + "const int target = 2;\r\n"
    source = Source("m.afsm", text)
    at = text.index("target")
    line = render(_diag(source, at, at + len("target"))).splitlines()
    quoted, caret = line[2], line[3]
    assert quoted.startswith(" 1 | ...") and len(quoted) < LONG_LINE + 20
    assert quoted[caret.index("^"):].startswith("target")
    assert caret.count("^") == len("target")
    assert not quoted.endswith("\r")


def test_many_diagnostics_on_one_long_line_cost_each_a_bounded_excerpt() -> None:
    def seconds(n: int) -> float:
        text = "const int x = 1; " * n
        source = Source("m.afsm", text)
        diags = [_diag(source, 17 * i, 17 * i + 5) for i in range(n)]
        t0 = time.process_time()
        out = render_all(diags)
        assert len(out) < n * (LONG_LINE + 200)
        return time.process_time() - t0

    small, large = seconds(2000), seconds(20_000)
    assert large < 1.0 or large < 30 * max(small, 0.01), (small, large)
