"""Write docs/schemas/NAME.schema.json, the published JSON Schema of `afsmc NAME --json`
(verify, sweep, regions, simulate), from the pydantic models of afsmc/answer/.

Usage: python scripts/gen_schemas.py [--check]
--check writes nothing and exits 1 if a file differs from what it would write.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from afsmc.answer.schema import DOC_DIR, MODELS, REGENERATE, text  # noqa: E402


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--check", action="store_true",
                    help="exit 1 if a schema file is stale, without writing it")
    args = ap.parse_args()
    stale = []
    for name in MODELS:
        path = ROOT / DOC_DIR / f"{name}.schema.json"
        want = text(name)
        current = path.read_text(encoding="utf-8") if path.exists() else None
        if current == want:
            continue
        stale.append(path)
        if not args.check:
            path.parent.mkdir(parents=True, exist_ok=True)
            path.write_text(want, encoding="utf-8")
            print(f"wrote {path.relative_to(ROOT)}")
    if args.check and stale:
        for path in stale:
            print(f"{path.relative_to(ROOT)} is stale: run {REGENERATE}", file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
