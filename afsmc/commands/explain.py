"""`afsmc explain CODE`: what a diagnostic code means, with a wrong and a right example
(as `rustc --explain` does); `afsmc explain` lists every code with its severity and title,
`afsmc explain --markdown` prints docs/diagnostics.md."""

from __future__ import annotations

import argparse
import difflib

from afsmc.commands.common import usage_error
from afsmc.diagnostics.codes import GROUPS, REGISTRY, lookup
from afsmc.diagnostics.docs import page
from afsmc.diagnostics.explain import as_text


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("code", nargs="?", metavar="CODE",
                   help="a diagnostic code, e.g. E301 (without: list every code)")
    p.add_argument("--markdown", action="store_true",
                   help="print every explanation as Markdown (docs/diagnostics.md)")


def run(args: argparse.Namespace) -> int:
    if args.markdown:
        if args.code:
            usage_error("--markdown prints every code; give no CODE with it")
        print(page(), end="")
        return 0
    if args.code is None:
        print(listing())
        return 0
    code = lookup(args.code)
    if code is None:
        usage_error(f"no diagnostic code {args.code!r}{_suggestion(args.code)}; "
                    "'afsmc explain' lists every code")
    assert code is not None
    print(as_text(code, code.severity.value, code.title, code.explanation))
    return 0


def listing() -> str:
    """Every code, a line each, under the headings of its range."""
    out: list[str] = []
    for heading, prefixes in GROUPS:
        out += ["", heading] if out else [heading]
        out += [f"  {c}  {c.severity.value:<7}  {c.title}"
                for c in REGISTRY.values() if c[:2] in prefixes]
    return "\n".join(out)


def _one_edit(code: str, text: str) -> bool:
    """`text` is `code` with one character changed, added or left out."""
    if len(code) == len(text):
        return sum(a != b for a, b in zip(code, text, strict=True)) == 1
    short, long_ = sorted((code, text), key=len)
    return len(long_) == len(short) + 1 and any(
        long_[:i] + long_[i + 1:] == short for i in range(len(long_)))


def _suggestion(text: str) -> str:
    """` (did you mean E301?)` for a text close to codes: a look-alike letter for a digit
    (E3O1), one character changed, added or left out (every such code), the three digits
    of a code (301: E301 or W301), or else the closest by difflib."""
    text = text.strip().upper()
    # Letters that look like digits, in a code's digit positions: E3O1 is E301.
    text = text[:1] + text[1:].translate(str.maketrans("OIL", "011"))
    if text.isdigit():
        close = [c for c in REGISTRY if c[1:] == text]
    elif text in REGISTRY:
        close = [text]
    else:
        close = [c for c in REGISTRY if _one_edit(c, text)]
        close = close or difflib.get_close_matches(text, list(REGISTRY), n=1, cutoff=0.6)
    if not close:
        return ""
    return " (did you mean " + (close[0] if len(close) == 1 else
                                ", ".join(close[:-1]) + " or " + close[-1]) + "?)"
