"""The sizes of input afsmc reads, stated once: past these it refuses with a diagnostic
rather than spend time and memory on an input no specification reaches.

Every stage's cost grows linearly with the size of its input (docs/benchmarks.md, "Input
size scaling"); the limits bound that cost. They are documented in docs/language.md
("Limits").
"""

from __future__ import annotations

# The characters of one source file or editor buffer (E004): 4 MiB, some 400 times the
# UAV mission of the paper, checked in well under a minute. Room above a 2 MB generated
# file for `afsmc fmt`'s layout of it (a few per cent longer: bodies on lines of their
# own), which must be read back.
MAX_SOURCE_CHARS = 4 * 1024 * 1024
# The characters of one name, number or quoted label name (E125). A 64-bit integer has at
# most 20 characters, a double written in full a few hundred.
MAX_TOKEN_CHARS = 1000
# How deeply an expression may nest (E113): each operator of a chain `a + b + c ...` (or
# `- - x`, `!!b`, ...) is one level. Every stage walks expressions recursively;
# afsmc.stack gives them the stack for this.
MAX_DEPTH = 5000
# How much of a long token a message quotes.
QUOTE_CHARS = 40


def clip(text: str, keep: int = QUOTE_CHARS) -> str:
    """`text` as a message quotes it: whole if short, else its start, '...' and its
    length ('aaaa...(40,000 characters)')."""
    if len(text) <= keep:
        return text
    return f"{text[:keep]}...({len(text):,} characters)"
