"""A bug in afsmc (an exception escaping a command) is exit 3, one line on stderr and a
traceback file, never a traceback on the terminal."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

from tests.conftest import run_cli


def test_a_bug_in_afsmc_is_one_line_and_a_traceback_file(monkeypatch: pytest.MonkeyPatch) -> None:
    """An exception that escapes a command is afsmc's bug, not the user's: exit 3, one line
    on stderr naming a file that holds the traceback, and no traceback on the terminal."""
    import afsmc.commands.check as check

    def broken(args: object) -> int:
        raise ValueError("an impossible state")

    monkeypatch.delenv("AFSMC_TRACEBACK", raising=False)
    monkeypatch.setattr(check, "run", broken)
    result = run_cli("check", "examples/patrol.afsm")
    assert result.code == 3
    assert "Traceback" not in result.err
    match = re.search(r"internal error .*ValueError: an impossible state; the traceback is in "
                      r"(\S+); please report it", result.err)
    assert match, result.err
    saved = Path(match.group(1))
    try:
        text = saved.read_text()
        assert "Traceback" in text and "an impossible state" in text
    finally:
        saved.unlink()


def test_a_bug_under_json_is_one_json_object_with_e009(monkeypatch: pytest.MonkeyPatch) -> None:
    import json

    import afsmc.commands.check as check

    def broken(args: object) -> int:
        raise ValueError("an impossible state")

    monkeypatch.delenv("AFSMC_TRACEBACK", raising=False)
    monkeypatch.setattr(check, "run", broken)
    result = run_cli("check", "--json", "examples/patrol.afsm")
    assert result.code == 3
    (d,) = json.loads(result.out)["diagnostics"]
    assert d["code"] == "E009" and d["severity"] == "error"
    Path(re.search(r"the traceback is in (\S+);", d["message"]).group(1)).unlink()  # type: ignore[union-attr]


def test_a_recursion_error_is_e114_naming_every_input(monkeypatch: pytest.MonkeyPatch) -> None:
    """The backstop behind E113/E246: a RecursionError in a command is E114 on the files it
    was given (check takes several), not an internal error."""
    import afsmc.commands.check as check

    def too_deep(args: object) -> int:
        raise RecursionError("maximum recursion depth exceeded")

    monkeypatch.setattr(check, "run", too_deep)
    result = run_cli("check", "examples/patrol.afsm", "examples/uav.afsm")
    assert result.code == 1
    assert ("error[E114]: examples/patrol.afsm, examples/uav.afsm: an expression is nested "
            "too deeply for afsmc") in result.err
