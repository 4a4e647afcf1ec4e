"""Small .afsm specs that several test modules share."""

from __future__ import annotations

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

BOM = "\ufeff"
