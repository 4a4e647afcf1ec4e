"""Resolving a small module written in a test, and the codes of what it reports."""

from __future__ import annotations

from collections.abc import Mapping

import pytest

from afsmc.diagnostics import CompileError, Diagnostic
from afsmc.resolve import Resolved, resolve
from afsmc.syntax.parser import parse

PATH = "unit.afsm"

# One mode, one variable: the frame most tests add declarations to.
FRAME = """machine unit;
var x : [0..3] init 0;
mode A = 0 initial;
mode B = 1 final;
"""


def resolved(text: str, overrides: Mapping[str, str] | None = None, *,
             open_params: bool = False) -> Resolved:
    return resolve(parse(text, PATH), overrides, open_params=open_params)


def errors(text: str, overrides: Mapping[str, str] | None = None) -> list[Diagnostic]:
    """The diagnostics of a module that does not resolve, in source order."""
    with pytest.raises(CompileError) as info:
        resolved(text, overrides)
    return info.value.diagnostics


def codes(text: str, overrides: Mapping[str, str] | None = None) -> list[str]:
    return [d.code for d in errors(text, overrides) if d.is_error]
