"""`afsmc check --werror`: warnings exit 1, and the message says why."""

from __future__ import annotations

from pathlib import Path

from tests.conftest import EXAMPLES, run_cli
from tests.specs import BOOL_PARAM

PATROL = str(EXAMPLES / "patrol.afsm")


def test_werror_says_why_warnings_exit_1(tmp_path: Path) -> None:
    path = tmp_path / "warned.afsm"
    path.write_text(BOOL_PARAM.replace("var x : [0..3] init 0;",
                                       "var x : [0..3] init 0;\nvar unused : [0..1] init 0;"))
    plain = run_cli("check", str(path))
    assert plain.code == 0 and "W303" in plain.err, plain.err
    strict = run_cli("check", "--werror", str(path))
    assert strict.code == 1
    assert "afsmc: --werror: 1 warning(s) treated as errors" in strict.err, strict.err
    clean = run_cli("check", "--werror", PATROL)
    assert clean.code == 0 and "--werror" not in clean.err, clean.err
