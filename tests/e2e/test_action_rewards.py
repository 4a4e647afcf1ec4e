"""Reward structures of action rewards only: an instantaneous reward of one is E247, the
reward queries Storm answers on them stay allowed."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from tests.conftest import run_cli

pytestmark = pytest.mark.storm

AC = """machine ac;
mode S = 0 initial;
mode D = 1 final;
action Go in S { 0.5: goto D; 0.5: skip; }
rewards ac { [Go] true : 1; }
rewards both { [Go] true : 1; mode == S : 1; }
label done = mode == D;
"""


def test_an_instantaneous_reward_of_action_rewards_only_is_an_error(tmp_path: Path) -> None:
    path = tmp_path / "ac.afsm"
    path.write_text(AC + 'property i = R{"ac"}=? [ I=3 ];\n', encoding="utf-8")
    r = run_cli("check", str(path))
    assert r.code == 1 and "error[E247]" in r.err
    path.write_text(AC, encoding="utf-8")
    r = run_cli("verify", str(path), "--formula", 'R{"ac"}=? [ I=3 ]')
    assert r.code == 1 and "E247" in r.out + r.err and "E404" not in r.out + r.err


@pytest.mark.parametrize("via", ["prism", "jani"])
def test_the_reward_queries_storm_answers_stay_allowed(tmp_path: Path, via: str) -> None:
    # Storm answers these on action-only and mixed structures (checked on every engine
    # by hand; C unbounded is the sparse engine's only); E247 leaves them alone.
    path = tmp_path / "ac.afsm"
    path.write_text(AC, encoding="utf-8")
    r = run_cli("verify", str(path), "--via", via, "--engine", "sparse", "--json",
                "--formula", 'R{"ac"}=? [ C<=3 ]', "--formula", 'R{"ac"}=? [ F "done" ]',
                "--formula", 'R{"ac"}=? [ C ]', "--formula", 'R{"both"}=? [ I=2 ]')
    assert r.code == 0, r.out + r.err
    values = [p["value"] for p in json.loads(r.out)["properties"]]
    assert values == pytest.approx([1.75, 2.0, 2.0, 0.25])
