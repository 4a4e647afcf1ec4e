"""Tiny models for the lowering and reduction unit tests, and helpers to evaluate what
lower() makes of them."""

from __future__ import annotations

from typing import Any

from afsmc.compiler import load
from afsmc.lower.lowering import Command, Lowered
from afsmc.model import ir
from afsmc.model.evaluate import Env, evaluate

# Up beats Stop below K (weight 0.8 > 0.5) and loses at K (0.2 < 0.5): Definition 2's
# arg-max. STEP is an interval constant: one command per end under nondet.
CLIMB = """
machine climb;
param int K = 5;
const prob P_OK = 0.9;
const int STEP = [1, 2];
var x : [0..K] init 0 clamp;
mode Climb = 0 initial;
mode Top = 1 final;
mode Fell = 2 final;
action Up in Climb weight (x < K ? 0.8 : 0.2) { P_OK: x += STEP; 1 - P_OK: goto Fell; }
action Stop in Climb weight 0.5 { goto Top; }
label top = mode == Top;
property top = P=? [ F "top" ];
"""

# One action and a probabilistic hazard woven into it.
GEOMETRIC = """
machine geo;
const prob P_WIN = 0.3;
const prob Q = 0.05;
mode Try = 0 initial;
mode Won = 1 final;
mode Lost = 2 final;
action Attempt in Try { P_WIN: goto Won; 1 - P_WIN: skip; }
hazard Fail from {Try} with probability Q { goto Lost; }
label won = mode == Won;
property win = P=? [ F "won" ];
"""

# Count stops at 2: from then on no action of Count is enabled (a deadlock self-loop).
STUCK = """
machine stuck;
var n : [0..2] init 0;
mode Count = 0 initial;
mode Done = 1 final;
action Inc in Count when n < 2 { n += 1; }
label two = n == 2;
property two = P=? [ F "two" ];
"""


def model_of(text: str, name: str = "spec") -> ir.Model:
    """The resolved model of `text`, before the checks."""
    return load(f"{name}.afsm", text=text, run_checks=False).model


def consts(low: Lowered) -> dict[str, Any]:
    """Every constant's value, the generated interval ends (STEP_lo, ...) included."""
    out: dict[str, Any] = dict(low.model.const_values)
    out.update({gen: value for gen, (_, value) in low.bounds.items()})
    return out


def value(low: Lowered, e: Any, mode: str, **variables: Any) -> Any:
    """`e` evaluated in one state: `mode` and the given variable values."""
    env = Env(vars=variables, mode=low.model.mode(mode).number, consts=consts(low),
              formulas={f.name: f.value for f in low.model.formulas},
              weight=lambda a: evaluate(low.weights[a], env))
    return evaluate(e, env)


def commands(low: Lowered, action: str) -> list[Command]:
    return [c for c in low.commands if c.action == action]


# tmp is read in Use only: after Use it is dead, so the reduction resets it on the way to
# Done and the two Done states (tmp = 1, tmp = 2) become one.
DEAD = """
machine dead;
var tmp : [0..2] init 0;
mode Pick = 0 initial;
mode Use = 1;
mode Done = 2 final;
action Choose in Pick { 0.5: tmp := 1, goto Use; 0.5: tmp := 2, goto Use; }
action One in Use when tmp == 1 { goto Done; }
action Two in Use when tmp == 2 { goto Done; }
label done = mode == Done;
property done = P=? [ F "done" ];
property one = P=? [ F mode == Use && tmp == 1 ];
"""

# t only grows and is only compared with 3: every value from 3 on is one state.
COUNTER = """
machine counter;
var t : [0..10] init 0 clamp;
mode Run = 0 initial;
mode Done = 1 final;
action Tick in Run { 0.8: t += 1; 0.2: goto Done; }
label late = t >= 3;
property late = P=? [ F "late" ];
property done_late = P=? [ F mode == Done && t >= 3 ];
"""

# Declared wide counter first, tuples field by field, a bool last: the reordering puts
# the bool first, interleaves the fields (pos.x, ret.x, pos.y, ret.y), the counter last.
ORDER = """
machine order;
var time : [0..100] init 0 clamp;
var pos : (x: [0..3], y: [0..3]) init (0, 0);
var ret : (x: [0..3], y: [0..3]) init (0, 0);
var busy : bool init false;
mode Go = 0 initial;
mode Done = 1 final;
action Step in Go when pos.x < 3 {
    0.5: pos.x += 1, ret.y := pos.x, time += 1, busy := true;
    0.5: pos.y := 1, goto Done;
}
action Stop in Go when pos.x == 3 { goto Done; }
label far = time >= 2 && ret.y >= 1 && busy;
property far = P=? [ F "far" ];
"""
