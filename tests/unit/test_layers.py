"""The pipeline's layering (docs/architecture.md): the early stages, afsmc.syntax and
afsmc.model, never import a later one, and the checks import no stage after them, not even
inside a function (a late import hides a cycle; it does not remove it). Read from the
source with `ast`, so nothing is executed."""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
PACKAGE = ROOT / "afsmc"
EARLY = ("syntax", "model", "resolve")
LATER = ("afsmc.check", "afsmc.lower", "afsmc.backends", "afsmc.verify", "afsmc.sim", "afsmc.simlib",
         "afsmc.commands", "afsmc.cli", "afsmc.lsp", "afsmc.compiler", "afsmc.api")


def _module_name(path: Path, root: Path = ROOT) -> str:
    parts = path.relative_to(root).with_suffix("").parts
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def imported(path: Path, root: Path = ROOT) -> set[str]:
    """Every module the file imports, anywhere in it: `from a import b` counts as both
    `a` and `a.b` (b may be a submodule); relative imports are made absolute."""
    name = _module_name(path, root)
    package = name if path.name == "__init__.py" else name.rpartition(".")[0]
    out: set[str] = set()
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"), str(path))):
        if isinstance(node, ast.Import):
            out |= {alias.name for alias in node.names}
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                base = package.split(".")
                base = base[:len(base) - (node.level - 1)]
                module = ".".join(base + ([node.module] if node.module else []))
            else:
                module = node.module or ""
            out.add(module)
            out |= {f"{module}.{alias.name}" for alias in node.names}
    return out


def _is_within(module: str, package: str) -> bool:
    return module == package or module.startswith(package + ".")


EARLY_FILES = sorted(p for layer in EARLY for p in (PACKAGE / layer).rglob("*.py"))


def test_the_early_layers_have_modules() -> None:
    assert {p.parent.name for p in EARLY_FILES} >= set(EARLY)
    assert any(p.name == "resolver.py" for p in EARLY_FILES)


@pytest.mark.parametrize("path", EARLY_FILES, ids=lambda p: str(p.relative_to(PACKAGE)))
def test_early_layers_import_no_later_stage(path: Path) -> None:
    bad = sorted(m for m in imported(path) if any(_is_within(m, p) for p in LATER))
    assert not bad, f"{_module_name(path)} imports a later stage: {', '.join(bad)}"


# The checks may use the simulator registry (afsmc.simlib: which simulators exist, for
# `from sim` constants), but no stage that consumes their verdict.
AFTER_CHECK = ("afsmc.lower", "afsmc.backends", "afsmc.verify", "afsmc.sim", "afsmc.commands", "afsmc.cli",
               "afsmc.lsp", "afsmc.compiler", "afsmc.api")
CHECK_FILES = sorted((PACKAGE / "check").rglob("*.py"))


@pytest.mark.parametrize("path", CHECK_FILES, ids=lambda p: str(p.relative_to(PACKAGE)))
def test_checks_import_no_later_stage(path: Path) -> None:
    bad = sorted(m for m in imported(path) if any(_is_within(m, p) for p in AFTER_CHECK))
    assert not bad, f"{_module_name(path)} imports a later stage: {', '.join(bad)}"


AFTER_LOWER = ("afsmc.backends", "afsmc.verify", "afsmc.sim", "afsmc.commands", "afsmc.cli",
               "afsmc.lsp", "afsmc.compiler", "afsmc.api")
LOWER_FILES = sorted((PACKAGE / "lower").rglob("*.py"))


@pytest.mark.parametrize("path", LOWER_FILES, ids=lambda p: str(p.relative_to(PACKAGE)))
def test_lowering_imports_no_later_stage(path: Path) -> None:
    bad = sorted(m for m in imported(path) if any(_is_within(m, p) for p in AFTER_LOWER))
    assert not bad, f"{_module_name(path)} imports a later stage: {', '.join(bad)}"


# The Python API (afsmc.api) is a top layer like the CLI: the commands call into it, and it
# calls the stages. Below it, no stage imports it or a command; it imports no command.
BELOW_API = ("backends", "verify", "sim", "simlib", "diagnostics")
BELOW_API_FILES = [*sorted(p for layer in BELOW_API for p in (PACKAGE / layer).rglob("*.py")),
                   PACKAGE / "compiler.py", PACKAGE / "files.py", PACKAGE / "text.py"]
API_FILES = sorted((PACKAGE / "api").rglob("*.py"))


@pytest.mark.parametrize("path", BELOW_API_FILES, ids=lambda p: str(p.relative_to(PACKAGE)))
def test_stages_import_neither_the_api_nor_the_commands(path: Path) -> None:
    top = ("afsmc.api", "afsmc.commands", "afsmc.cli")
    bad = sorted(m for m in imported(path) if any(_is_within(m, p) for p in top))
    assert not bad, f"{_module_name(path)} imports a top layer: {', '.join(bad)}"


@pytest.mark.parametrize("path", API_FILES, ids=lambda p: str(p.relative_to(PACKAGE)))
def test_the_api_imports_no_command(path: Path) -> None:
    bad = sorted(m for m in imported(path) if any(_is_within(m, p) for p in
                                                  ("afsmc.commands", "afsmc.cli", "afsmc.lsp")))
    assert not bad, f"{_module_name(path)} imports the CLI: {', '.join(bad)}"


def test_the_import_scan_sees_function_level_and_relative_imports(tmp_path: Path) -> None:
    # The scan itself, on a file laid out as afsmc/model/x.py under tmp_path.
    target = tmp_path / "afsmc" / "model" / "x.py"
    target.parent.mkdir(parents=True)
    target.write_text("def f():\n    from afsmc.check.search import find\n"
                      "    from ..backends import dot\n    import afsmc.cli\n")
    assert {"afsmc.check.search", "afsmc.backends.dot", "afsmc.cli"} <= imported(target, tmp_path)
