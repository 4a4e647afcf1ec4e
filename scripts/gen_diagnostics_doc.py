"""Write docs/diagnostics.md from the registry of diagnostic codes and their explanation
files (afsmc/diagnostics/codes.py, afsmc/diagnostics/explanations/<CODE>.md).

Usage: python scripts/gen_diagnostics_doc.py [--check]
--check writes nothing and exits 1 if the page differs from what it would write.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from afsmc.diagnostics.docs import DOC_PATH, page  # noqa: E402


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--check", action="store_true",
                    help="exit 1 if the page is stale, without writing it")
    args = ap.parse_args()
    path = ROOT / DOC_PATH
    text = page()
    current = path.read_text(encoding="utf-8") if path.exists() else None
    if args.check:
        if current != text:
            print(f"{DOC_PATH} is stale: run python scripts/gen_diagnostics_doc.py",
                  file=sys.stderr)
            return 1
        return 0
    if current != text:
        path.write_text(text, encoding="utf-8")
        print(f"wrote {DOC_PATH}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
