"""Machine names: a machine named after its file gets a name Storm reads, and the names
afsmc reserves are the ones Storm refuses."""

from __future__ import annotations

from pathlib import Path

import pytest
import stormpy

from afsmc.compiler import load
from afsmc.lower.lowering import lower
from afsmc.model.names import RESERVED, STORM_KEYWORDS
from tests.specs import SMALL
from tests.storm_util import storm_prism

pytestmark = pytest.mark.storm


@pytest.mark.parametrize("stem", ["init", "module", "true", "rewards", "dtmc", "floor", "F", "9lives",
                                  "café-1"])
def test_a_machine_named_by_its_file_gets_a_name_storm_reads(tmp_path: Path, stem: str) -> None:
    """Without a `machine` line the module is named after the file; a user cannot be
    blamed for the file's name, so it is made safe rather than refused."""
    path = tmp_path / f"{stem}.afsm"
    path.write_text(SMALL.split("\n", 1)[1])
    model = load(str(path)).model
    assert model.name.isascii() and model.name.isidentifier() and model.name not in RESERVED
    _, values = storm_prism(lower(model), tmp_path)
    assert values == {"reach": 1.0}


def test_storm_refuses_the_names_afsmc_reserves_for_it(tmp_path: Path) -> None:
    """The lists in afsmc.model.names are not stale: Storm's PRISM parser refuses its own
    keywords and PRISM's as a module name (player/endplayer: newer Storm releases only)."""
    names = [*sorted(STORM_KEYWORDS - {"player", "endplayer"}), "init", "module", "true", "dtmc"]
    refused = []
    for name in names:
        path = tmp_path / f"{name}.prism"
        path.write_text(f"dtmc\nmodule {name}\n  x : [0..1] init 0;\n  [] x = 0 -> (x'=1);\nendmodule\n")
        try:
            stormpy.parse_prism_program(str(path))
        except RuntimeError:
            refused.append(name)
    assert refused == names
