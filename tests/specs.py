"""Small .afsm specs that several test modules share."""

from __future__ import annotations

from pathlib import Path

# Four states to a final mode: the smallest machine with a label and a property.
SMALL = """machine small;
var x : [0..3] init 0;
mode A = 0 initial;
mode B = 1 final;
action Up in A when x < 3 { x += 1; }
action Done in A when x == 3 { goto B; }
label done = mode == B;
property reach = P=? [ F "done" ];
"""

# A bool param that switches a hazard on: sweeps and --const over true/false.
BOOL_PARAM = """machine windy;
param bool WINDY = false;
var x : [0..3] init 0;
mode A initial;
mode B final;
action Go in A when x < 3 { 0.5: x := x + 1; 0.5: skip; }
action Fin in A when x == 3 weight 0.5 { goto B; }
hazard Gust from {A} with probability (WINDY ? 0.1 : 0) { goto B; }
label done = mode == B && x == 3;
property p = P=? [ F "done" ];
"""

BOM = "\ufeff"


def patrol_with_requirements(folder: Path) -> Path:
    """examples/patrol.afsm with two requirements (one bounds a failure from above, one
    asks for success), written into `folder`: the report's and the sensitivities' tests."""
    from tests.conftest import EXAMPLES

    path = folder / "patrol_req.afsm"
    path.write_text((EXAMPLES / "patrol.afsm").read_text(encoding="utf-8") + """
property fault_low = P<=0.2 [ F "halted" ];
property finish_ok = P>=0.8 [ F "done" ];
""", encoding="utf-8")
    return path
