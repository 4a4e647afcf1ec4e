"""docs/language.md lists what the property language does not have, with the error each
gets: every example of that table, declared as a property of the patrol mission, gets the
code the table names, from `afsmc check`."""

from __future__ import annotations

import json
import re
from pathlib import Path

import pytest

from tests.conftest import EXAMPLES, ROOT, run_cli

DOC = ROOT / "docs" / "language.md"


def table() -> list[tuple[str, str]]:
    """(example property, expected code) for every example of the table."""
    text = DOC.read_text(encoding="utf-8")
    section = text.split("### What the property language does not have", 1)[1].split("\n\n|", 1)[1]
    rows = [r for r in ("|" + section).split("\n\n", 1)[0].splitlines()[2:]]
    out = []
    for row in rows:
        _, examples, error = [c.strip() for c in row.strip("|").split(" | ")]
        code = re.match(r"E\d{3}", error)
        assert code, row
        out += [(e, code.group()) for e in re.findall(r"`([^`]+)`", examples)]
    return out


EXAMPLES_TABLE = table()


def test_the_table_has_the_unsupported_features() -> None:
    shown = " ".join(e for e, _ in EXAMPLES_TABLE)
    for feature in ("S=?", "G F", "W", "multi(", "filter(", "E ["):
        assert feature in shown


@pytest.mark.parametrize(("example", "code"), EXAMPLES_TABLE, ids=[e for e, _ in EXAMPLES_TABLE])
def test_each_example_gets_the_error_the_table_names(example: str, code: str,
                                                     tmp_path: Path) -> None:
    base = "\n".join(line for line in (EXAMPLES / "patrol.afsm").read_text().splitlines()
                     if not line.startswith("property"))
    f = tmp_path / "p.afsm"
    # a path alone (`[ LRA ]`) is asked of the steps reward structure
    prop = f'R{{"steps"}}=? {example}' if example.startswith("[") else example
    f.write_text(f"{base}\nproperty p = {prop};\n")
    res = run_cli("check", "--json", str(f))
    assert res.code == 1
    errors = [d["code"] for d in json.loads(res.out) if d["severity"] == "error"]
    assert errors[:1] == [code], (prop, errors)
