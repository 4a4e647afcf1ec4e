"""resolve() returns a typed `Resolved`: the model, and beside it the warnings, the names
the source uses, and (with open_params) the params without a value."""

from __future__ import annotations

import dataclasses

import pytest

from afsmc.model import ir
from afsmc.resolve import Resolved
from tests.unit.resolve.util import FRAME, errors, resolved


def test_the_result_is_frozen_and_the_model_has_no_side_channel() -> None:
    r = resolved(FRAME + "action Go in A when x < 3 { x += 1; }\n")
    assert isinstance(r, Resolved) and isinstance(r.model, ir.Model)
    with pytest.raises(dataclasses.FrozenInstanceError):
        r.warnings = ()  # type: ignore[misc]
    assert not hasattr(r.model, "cache")
    assert r.model.memo == ir.Memo()  # nothing derived yet
    assert r.model.name == "unit" and r.model.initial_mode.name == "A"


def test_warnings_are_on_the_result_and_errors_raise() -> None:
    r = resolved(FRAME + "action Go in * except {A} { skip; }\n")
    assert [d.code for d in r.warnings] == ["W603"]
    assert all(not d.is_error for d in r.warnings)
    assert [d.code for d in errors(FRAME + "action Go in Z { skip; }\n")] == ["E215"]


def test_used_names_hold_constants_read_only_where_the_ir_keeps_no_reference() -> None:
    r = resolved(FRAME + "const int N = 3;\nconst int M = N - 1;\nvar y : [0..N] init 0;\n"
                 "formula f = y + M;\nconst int Unused = 1;\n"
                 "action Go in A when f < 3 { y := min(N, y + 1); }\n")
    assert {"N", "M", "f"} <= r.used_names and "Unused" not in r.used_names


def test_open_params_are_stand_ins_with_the_e206_they_would_be() -> None:
    text = FRAME + "param int N;\nparam double p;\nconst double q = p / 2;\n" \
        "action Go in A when x < N weight q { skip; }\n"
    assert {d.code for d in errors(text)} == {"E206"}
    r = resolved(text, open_params=True)
    assert sorted(r.open_params) == ["N", "p"]
    assert r.open_params["N"].code == "E206"
    assert r.open_reads["q"] == frozenset({"p"})
    assert r.open_reads["N"] == frozenset({"N"})
    assert r.model.constant("N").value == 0


def test_without_open_params_nothing_is_open() -> None:
    r = resolved(FRAME + "param int N = 1;\naction Go in A when x < N { skip; }\n")
    assert r.open_params == {} and r.open_reads == {}


def test_the_machine_name_defaults_to_the_file_name() -> None:
    r = resolved(FRAME.replace("machine unit;\n", "") + "action Go in A { skip; }\n")
    assert r.model.name == "unit"
