"""A small MDP for the verify stage's unit tests: interval steps, two final modes."""

from __future__ import annotations

from afsmc.compiler import load
from afsmc.model import ir

TEXT = """machine tiny;
const int STEP = [1, 2];
var x : [0..8] init 0 clamp;
mode Run = 0 initial;
mode End = 1 final;
mode Crash = 2 final;
action Go in Run when x < 8 { 0.8: x += STEP; 0.2: x += 1; }
action Stop in Run when x >= 8 { goto End; }
hazard Trip from {0} with probability 0.05 { goto Crash; }
label low = x <= 5;
label done = mode == End;
property stay  = P=? [ G<=4 "low" ];
property short = Pmin=? [ G<=3 "low" ];
property done  = P=? [ F "done" ];
property far   = P=? [ F x >= 4 ];
"""


def tiny(text: str = TEXT) -> ir.Model:
    """The checked model of `text` (its path is only a name)."""
    return load("tiny.afsm", None, text=text).model


def prop(model: ir.Model, name: str) -> ir.Property:
    return next(p for p in model.properties if p.name == name)
