"""afsmc.check.sim_sources: a `from sim` constant names a registered simulator output
(E501), has the type its output's kind asks for (E503), and a policy of known keys (E504)."""

from __future__ import annotations

from afsmc.check.sim_sources import check_sim_sources
from tests.unit.check.rules import codes, run_rule


def _model(const: str) -> str:
    return f"""machine s;
{const}
mode A = 0 initial;
mode B = 1 final;
action Go in A {{ goto B; }}
"""


def test_a_registered_output_of_the_right_kind_is_fine() -> None:
    assert codes(check_sim_sources, _model(
        "const int T_GO = [1, 4] from sim uav.approach.duration;")) == []
    assert codes(check_sim_sources, _model("const prob P_FAIL = 0.01 from sim uav.grab.fail;")) == []


def test_an_unknown_output_is_e501_with_the_close_names() -> None:
    (d,) = run_rule(check_sim_sources, _model(
        "const int T_GO = [1, 4] from sim uav.aproach.duration;"))
    assert d.code == "E501"
    assert d.message == "unknown simulator output 'uav.aproach.duration' for constant 'T_GO'"
    assert d.hint is not None and "'uav.approach.duration'" in d.hint


def test_a_probability_in_an_int_is_e503() -> None:
    (d,) = run_rule(check_sim_sources, _model("const int P_FAIL = 0 from sim uav.grab.fail;"))
    assert d.code == "E503"
    assert d.message == "'uav.grab.fail' is a probability, but 'P_FAIL' is an 'int' constant"


def test_an_unknown_policy_key_is_e504() -> None:
    (d,) = run_rule(check_sim_sources, _model(
        "const int T_GO = [1, 4] from sim uav.approach.duration with coverag = 0.9;"))
    assert d.code == "E504"
    assert d.message == "unknown policy key 'coverag' for constant 'T_GO'"
    assert d.hint is not None and d.hint.startswith("did you mean 'coverage'?")
