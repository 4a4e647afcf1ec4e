"""afsmc.syntax.errors.before: the searches for what precedes a syntax error find what the
end-anchored patterns they replace found (those patterns are the oracle here, on random
texts), and take time linear in the text."""

from __future__ import annotations

import random
import re
import time

import pytest

from afsmc.diagnostics import CompileError
from afsmc.syntax.errors.before import (
    hazard_header,
    operand_before,
    weight_before_guard,
    word_before,
)
from afsmc.syntax.parser import parse

# The patterns as they were, searched from the start of the text (quadratic on long runs).
OPERAND = re.compile(r'([A-Za-z_][\w.]*|\d[\w.]*|"[^"]*"|\))\s*\Z')
WEIGHT_BEFORE_GUARD = re.compile(
    r"\b(?:action|hazard)\b(?:(?!\bwhen\b)[^{};])*\bweight\b[^{};]*$")
HAZARD_BOTH = re.compile(r"\bhazard\b(?:[^{};]|\{[^{}]*\})*$")
WORD = re.compile(r"([\w.]+)\s*$")

PIECES = ["a", "x1", "9", "1.5", ".", " ", "\n", '"', '"l"', "(", ")", "{", "}", ";", "+",
          "action", "hazard", "weight", "when", "with", "é", "_", "{A, B}", "{0..3}", "F"]


def _texts(n: int, seed: int) -> list[str]:
    rng = random.Random(seed)
    return ["".join(rng.choice(PIECES) + rng.choice(["", " "]) for _ in range(rng.randint(0, 14)))
            for _ in range(n)]


def _span(m: re.Match[str] | None) -> tuple[int, int, str] | None:
    return None if m is None else (m.start(), m.end(), m.group(1))


@pytest.mark.parametrize("seed", range(4))
def test_the_searches_agree_with_the_patterns_they_replace(seed: int) -> None:
    for text in _texts(2000, seed):
        for pos in {len(text), len(text) // 2, max(0, len(text) - 1)}:
            assert _span(operand_before(text, pos)) == _span(OPERAND.search(text, 0, pos)), \
                (text, pos)
            assert _span(word_before(text, pos)) == _span(WORD.search(text[:pos])), (text, pos)
            assert weight_before_guard(text, pos) == bool(
                WEIGHT_BEFORE_GUARD.search(text, 0, pos)), (text, pos)
            old = HAZARD_BOTH.search(text, 0, pos)
            assert hazard_header(text, pos) == (old.start() if old else None), (text, pos)


@pytest.mark.parametrize("text", [
    "machine m;\nconst int {A} = 1; }\n",
    "machine m;\nformula f = {A} 1;\n",
    "machine m;\nmode A initial;\naction b in A {{ x := {A} y := 1; }}\n",
    "machine m;\nformula f = {A} + b % 2;\n",
    "machine m;\nhazard h from {{A}} when {A} with probability 1 {{ goto A; }}\n",
    "machine m;\n// {A}\nconst int x = 1 1;\n",
])
def test_a_syntax_error_after_a_long_run_is_explained_in_linear_time(text: str) -> None:
    def seconds(n: int) -> float:
        source = text.replace("{A}", "a" * n).replace("{{", "{").replace("}}", "}")
        t0 = time.process_time()
        with pytest.raises(CompileError):
            parse(source, f"run{n}.afsm")
        return time.process_time() - t0

    seconds(1000)  # warm-up: the parser's tables, the examples' states
    small, large = seconds(4000), seconds(40_000)
    # 10x the text: linear is ~10x; the searches these replace took ~100x (seconds here)
    assert large < 1.0 or large < 30 * max(small, 0.01), (small, large)
