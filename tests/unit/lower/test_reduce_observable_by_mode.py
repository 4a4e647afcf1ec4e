"""observable_by_mode(): the variables each mode's labels, rewards and properties read,
computed once per mode an expression names (and once for the rest), agree with folding
every expression in every mode (at_mode, the definition); and a mission of thousands of
modes, each named by its own label, folds each label twice, not once per mode."""

from __future__ import annotations

import pytest

from afsmc.lower import reduce
from afsmc.lower.reduce import _observed, at_mode, observable_by_mode
from afsmc.model import expr as E
from afsmc.model import ir
from tests.unit.lower.models import model_of

MIXED = """machine m;
var x : [0..3] init 0;
var y : [0..3] init 0;
var z : [0..3] init 0;
var u : [0..3] init 0;
mode A = 0 initial;
mode B = 1;
mode C = 2;
mode D = 3 final;
formula atB = mode == B;
label xa = mode == A && x > 0;
label yb = !atB || y == 1;
label zc = (mode == C ? z : 0) > 1 || mode != A && u > 2;
label far = mode == D;
action Go in A { goto B; x := 1; }
action On in B { goto C; y := 2; }
action Up in C { goto D; z := 1; }
rewards cost { [Go] true : u; mode == C : y; }
property p = P=? [ F x == 1 && mode == D ];
"""


def per_mode(model: ir.Model) -> dict[int, set[str]]:
    """The definition: every expression folded in every mode it is read in."""
    out: dict[int, set[str]] = {m.number: set() for m in model.modes}
    for e, where in _observed(model):
        for m in out if where is None else where:
            out[m] |= E.vars_read(at_mode(e, m, model))
    return out


def chain(n: int) -> str:
    lines = ["machine big;", "var x : [0..10] init 0;"]
    lines += [f"mode M{i} = {i}{' initial' if i == 0 else ' final' if i == n else ''};"
              for i in range(n + 1)]
    for i in range(n):
        lines += [f"label l{i} = x == {i % 10} && mode == M{i};",
                  f"action A{i} in M{i} {{ goto M{i + 1}; x := {i % 10}; }}"]
    return "\n".join(lines) + "\n"


def test_agrees_with_folding_in_every_mode() -> None:
    for text in (MIXED, chain(30)):
        model = model_of(text)
        modes = [m.number for m in model.modes]
        assert observable_by_mode(model, modes) == per_mode(model)
    model = model_of(MIXED)
    got = observable_by_mode(model, [0, 1, 2, 3])
    assert got[0] == {"x", "y", "u"}  # u: Go's reward is read where Go leaves
    assert got[2] == {"y", "z", "u"} and got[3] == {"x", "y", "u"}  # z in C, x in A and D


def test_a_label_naming_one_mode_is_folded_twice_not_once_per_mode(
        monkeypatch: pytest.MonkeyPatch) -> None:
    """Each of n labels names one mode: 2n folds (its mode, the others), not n * (n + 1)
    (folding every label in every mode took minutes for 12,000 modes; the times are in
    docs/benchmarks.md, "Input size scaling")."""
    folds = []
    real = reduce._fold_at
    monkeypatch.setattr(reduce, "_fold_at", lambda e, m: folds.append(m) or real(e, m))
    for n in (250, 2000):
        folds.clear()
        model = model_of(chain(n))
        modes = [m.number for m in model.modes]
        live = observable_by_mode(model, modes)
        assert live[modes[0]] == {"x"} and live[modes[-1]] == set()
        assert len(folds) == 2 * n
