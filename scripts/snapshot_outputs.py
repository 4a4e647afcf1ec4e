"""Write every compiler output (PRISM, JANI, DOT, diagnostics) for the examples and test cases.

Run it before and after a change that must not alter output, then compare the two folders:

    python scripts/snapshot_outputs.py /tmp/before
    ... change ...
    python scripts/snapshot_outputs.py /tmp/after && diff -r /tmp/before /tmp/after

Each input is compiled with every resolution and with and without the reductions, so the
comparison covers lowering, each reduction and each backend byte for byte.
"""

from __future__ import annotations

import io
import sys
from contextlib import redirect_stderr, redirect_stdout
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
VARIANTS = (
    ("default", ()),
    ("uniform", ("--resolve", "uniform")),
    ("lo", ("--resolve", "lo")),
    ("noreduce", ("--no-reduce",)),
)


def _run(argv: list[str]) -> tuple[int, str, str]:
    from afsmc.cli import main

    out, err = io.StringIO(), io.StringIO()
    with redirect_stdout(out), redirect_stderr(err):
        try:
            code = main(argv)
        except SystemExit as exc:
            code = int(exc.code or 0)
    return code, out.getvalue(), err.getvalue()


def inputs() -> list[Path]:
    return sorted(ROOT.glob("examples/*.afsm")) + sorted(ROOT.glob("tests/golden/cases/*/input.afsm"))


def main(dest: str) -> int:
    target = Path(dest)
    target.mkdir(parents=True, exist_ok=True)
    for path in inputs():
        rel = str(path.relative_to(ROOT))
        stem = rel.replace("/", "__")
        code, out, err = _run(["check", rel])
        (target / f"{stem}.check").write_text(f"exit {code}\n{out}{err}")
        if code != 0:
            continue
        for name, extra in VARIANTS:
            for lang in ("prism", "jani", "dot"):
                code, out, err = _run(["compile", rel, "-t", lang, "-o", "-", *extra])
                (target / f"{stem}.{name}.{lang}").write_text(f"exit {code}\n{out}{err}")
    return 0


if __name__ == "__main__":
    if len(sys.argv) != 2 or sys.argv[1].startswith("-"):
        print(__doc__.strip().splitlines()[0] + "\n\nusage: python scripts/snapshot_outputs.py DIR",
              file=sys.stderr)
        sys.exit(2)
    sys.exit(main(sys.argv[1]))
