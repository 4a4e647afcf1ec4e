"""The size rule of docs/architecture.md: no module under afsmc/ is longer than 600 lines and
no function (or method) longer than 100, so that each file stays one stage a newcomer can
read. Read from the source with `ast`, so nothing is executed."""

from __future__ import annotations

import ast
from pathlib import Path

from tests.conftest import ROOT

PACKAGE = ROOT / "afsmc"
MAX_MODULE_LINES = 600
MAX_FUNCTION_LINES = 100


def _modules() -> list[Path]:
    return sorted(PACKAGE.rglob("*.py"))


def _long_functions(text: str, name: str) -> list[str]:
    """`name:line function: N lines` for each function or method longer than the limit."""
    found = []
    for node in ast.walk(ast.parse(text, name)):
        if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
            assert node.end_lineno is not None
            length = node.end_lineno - node.lineno + 1
            if length > MAX_FUNCTION_LINES:
                found.append(f"{name}:{node.lineno} {node.name}: {length} lines")
    return found


def test_the_package_has_modules() -> None:
    assert len(_modules()) > 10


def test_no_module_is_longer_than_600_lines() -> None:
    long = [f"{p.relative_to(ROOT)}: {n} lines" for p in _modules()
            if (n := len(p.read_text(encoding="utf-8").splitlines())) > MAX_MODULE_LINES]
    assert long == []


def test_no_function_is_longer_than_100_lines() -> None:
    long = [f for p in _modules()
            for f in _long_functions(p.read_text(encoding="utf-8"), str(p.relative_to(ROOT)))]
    assert long == []


def test_the_function_scan_sees_methods_and_nested_functions() -> None:
    body = "\n".join(f"        x{i} = {i}" for i in range(MAX_FUNCTION_LINES))
    text = f"class C:\n    def m(self):\n        def inner():\n            pass\n{body}\n"
    assert _long_functions(text, "sample.py") == [
        f"sample.py:2 m: {MAX_FUNCTION_LINES + 3} lines"]
    nested = "def outer():\n    def inner():\n" + body.replace("        ", "        ") + "\n"
    assert [f.split(" ")[1] for f in _long_functions(nested, "n.py")] == ["outer:", "inner:"]
