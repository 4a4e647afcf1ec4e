"""Interval probabilities `const prob P = [lo, hi]`: one fixed value in the interval, the
midpoint for the point-valued checks; their errors (E204, E205, E207, E250)."""

from __future__ import annotations

import pytest

from tests.unit.resolve.util import FRAME, codes, errors, resolved

USE = "action Go in A when x < 3 {\n    1 - P_S: x += 1;\n    P_S: skip;\n}\n"


def test_an_interval_probability_keeps_its_ends_and_its_midpoint_as_value() -> None:
    model = resolved(FRAME + "const prob P_S = [0.05, 0.15];\n" + USE).model
    c = model.constant("P_S")
    assert c.prob_interval == (0.05, 0.15)
    assert c.value == pytest.approx(0.1)
    assert c.is_prob_interval and not c.is_interval  # no floor/ceil choice
    assert model.prob_intervals == (c,) and not model.is_nondeterministic


def test_a_hazard_probability_may_be_an_interval() -> None:
    model = resolved(FRAME + "const prob P_S = [0.01, 0.02];\naction Go in A { skip; }\n"
                     "hazard H from {A} with probability P_S { goto B; }\n").model
    assert model.constant("P_S").prob_interval == (0.01, 0.02)


@pytest.mark.parametrize(("decl", "code"), [
    ("const prob P_S = [0.2, 0.1];", "E205"),
    ("const prob P_S = [-0.1, 0.1];", "E207"),
    ("const prob P_S = [0.5, 1.5];", "E207"),
    ("const double P_S = [0.1, 0.2];", "E204"),
])
def test_an_interval_probability_must_lie_in_0_1_and_not_be_empty(decl: str, code: str) -> None:
    assert codes(FRAME + decl + "\n" + USE)[0] == code


def test_an_empty_interval_probability_says_so() -> None:
    (d,) = errors(FRAME + "const prob P_S = [0.2, 0.1];\n" + USE)
    assert d.message == "interval [0.2, 0.1] of 'P_S' is empty"


@pytest.mark.parametrize("where", [
    "action Go in A when x < 3 && P_S > 0.1 { 0.5: x += 1; 0.5: skip; }\n",
    "action Go in A weight P_S { skip; }\n",
    "const prob Q = 1 - P_S;\naction Go in A { Q: x += 1; 1 - Q: skip; }\n",
])
def test_an_interval_probability_outside_probabilities_is_e250(where: str) -> None:
    ds = errors(FRAME + "const prob P_S = [0.05, 0.15];\n" + where)
    assert [d.code for d in ds if d.is_error][:1] == ["E250"]
    assert "can only be used in probabilities" in ds[0].message
