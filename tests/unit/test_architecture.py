"""docs/architecture.md's claims about the tree, read from the source with `ast` (nothing is
executed): every module of afsmc/ belongs to one stage of the pipeline, by its package, and

(a) no stage imports a later one: not at module level, not inside a function, not under
    `if TYPE_CHECKING:`. A lazy import defers the cost, not the dependency, and a type named
    in a signature is knowledge of the later stage all the same;
(b) there is no import cycle inside a stage among the imports that run when a module is
    imported: those at module level (a class body's included), not those inside a function
    (the usual way to break a cycle is to import lazily, and such a cycle is no hazard at
    import time) nor those under TYPE_CHECKING (never run). The packages of a stage are
    layered the same way: no cycle between them either;
(c) every package of afsmc/, and every module directly in it, is in the table below;
(d) no folder of afsmc/ holds more than 15 modules (its `__init__.py` not counted).

An import `from P import N` counts as importing the module P.N when that is a module, else
the module P; `import a.b` counts as importing a.b (not its parent packages, although Python
runs their `__init__` first). Only imports of afsmc's own modules count.
"""

from __future__ import annotations

import ast
import re
from collections.abc import Iterable, Iterator, Mapping
from dataclasses import dataclass
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
PAGE = ROOT / "docs" / "architecture.md"
PACKAGE = "afsmc"

# The stages in pipeline order (docs/architecture.md, "Stages"), each with its packages and
# top-level modules, by dotted name. A module's stage is that of the longest name in this
# table that is the module itself or a package containing it; the root `afsmc` names only
# its own __init__ (so a new top-level module or package must be added here).
STAGES: tuple[tuple[str, tuple[str, ...]], ...] = (
    # shared leaves every stage may use: diagnostics as data, wording, interrupts, stack,
    # heap, child processes; the root package holds __version__
    ("leaves", ("afsmc", "afsmc.diagnostics", "afsmc.text", "afsmc.interrupt", "afsmc.stack",
                "afsmc.heap", "afsmc.lifetime", "afsmc.answer")),
    # source text -> AST
    ("source", ("afsmc.files", "afsmc.syntax", "afsmc.syntax.errors")),
    # AST -> resolved model (the IR and what every later stage asks of it)
    ("model", ("afsmc.model", "afsmc.resolve")),
    # resolved model -> checked IR (the checks read the simulator registry)
    ("check", ("afsmc.check", "afsmc.simlib")),
    # checked IR -> lowered and reduced IR
    ("lower", ("afsmc.lower",)),
    # the pipeline so far as two calls: load (source -> checked IR) and lowered
    ("pipeline", ("afsmc.compiler",)),
    # lowered IR -> PRISM/JANI/DOT text, simulated runs, Storm's and afsmc's numbers
    ("engines", ("afsmc.backends", "afsmc.controllers", "afsmc.sim", "afsmc.conform",
                 "afsmc.verify.plan", "afsmc.verify.engines", "afsmc.verify.lifting",
                 "afsmc.verify.stream", "afsmc.verify.kernels", "afsmc.verify.explorer",
                 "afsmc.verify.arrays")),
    # numbers -> one typed answer per property (verify.core drives the engines)
    ("answer", ("afsmc.verify.outcome", "afsmc.verify.core")),
    # many answers (sweeps, regions) and the reports rendered from answers; afsmc.verify,
    # the package's door, re-exports the core and the sweeps
    ("studies", ("afsmc.verify.reports", "afsmc.verify")),
    # the Python API for people, and the assurance case made from its answers
    ("library", ("afsmc.api", "afsmc.report")),
    # the command line and the editor
    ("cli", ("afsmc.commands", "afsmc.commands.render", "afsmc.cli", "afsmc.__main__",
             "afsmc.lsp")),
)

# The planned split of afsmc/verify/ (each flat module -> its subpackage). Until the modules
# are moved, each is staged as the subpackage it is planned for. When they are moved, empty
# this table: an entry whose flat module no longer exists fails
# test_the_planned_verify_split_is_current.
VERIFY_SPLIT: dict[str, str] = {}

# Imports that go to a later stage today, each with the change that removes it. Empty it.
KNOWN_UPWARD: dict[tuple[str, str], str] = {}

# The one import upward that is the design: the root package re-exports the Python API on
# first use (PEP 562 __getattr__, and its names for type checkers), so that `afsmc.load`
# works while `from afsmc import __version__` imports nothing else.
DOORS = {("afsmc", "afsmc.api")}

MAX_MODULES = 15
# Folders over the limit today, each with the change that brings it under. Shrink it; an
# entry that is no longer over the limit fails test_the_allow_list_of_large_folders_shrinks.
OVER_15_MODULES: dict[str, str] = {}


@dataclass(frozen=True)
class Import:
    target: str  # an afsmc module
    line: int
    when: str  # "module" (runs on import), "function" (runs when called), "type-checking"


def module_name(path: Path, root: Path = ROOT) -> str:
    parts = path.relative_to(root).with_suffix("").parts
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def modules(root: Path = ROOT) -> dict[str, Path]:
    return {module_name(p, root): p for p in sorted((root / PACKAGE).rglob("*.py"))}


def _is_type_checking(test: ast.expr) -> bool:
    return ((isinstance(test, ast.Name) and test.id == "TYPE_CHECKING")
            or (isinstance(test, ast.Attribute) and test.attr == "TYPE_CHECKING"))


def _walk(node: ast.AST, when: str) -> Iterator[tuple[ast.AST, str]]:
    """Every node under `node` with when it runs: inside a function (or lambda) it is
    "function", in the body of `if TYPE_CHECKING:` at module level "type-checking"."""
    for child in ast.iter_child_nodes(node):
        inner = when
        if isinstance(child, (ast.FunctionDef, ast.AsyncFunctionDef, ast.Lambda)):
            inner = "function"
        elif isinstance(child, ast.If) and when == "module" and _is_type_checking(child.test):
            for stmt in child.body:
                yield stmt, "type-checking"
                yield from _walk(stmt, "type-checking")
            for stmt in child.orelse:
                yield stmt, "module"
                yield from _walk(stmt, "module")
            continue
        yield child, inner
        yield from _walk(child, inner)


def imports(path: Path, known: Iterable[str], root: Path = ROOT) -> list[Import]:
    """The afsmc modules the file imports, anywhere in it; relative imports made absolute.
    `known`: the modules that exist (to tell `from P import submodule` from a name)."""
    known = set(known)
    name = module_name(path, root)
    package = name if path.name == "__init__.py" else name.rpartition(".")[0]

    def existing(dotted: str) -> str:
        while dotted and dotted not in known:
            dotted = dotted.rpartition(".")[0]
        return dotted

    out: list[Import] = []
    for node, when in _walk(ast.parse(path.read_text(encoding="utf-8"), str(path)), "module"):
        if isinstance(node, ast.Import):
            targets = [alias.name for alias in node.names]
        elif isinstance(node, ast.ImportFrom):
            base = node.module or ""
            if node.level:
                up = package.split(".")
                base = ".".join(up[:len(up) - (node.level - 1)] + ([base] if base else []))
            targets = [f"{base}.{a.name}" if f"{base}.{a.name}" in known else base
                       for a in node.names]
        else:
            continue
        for target in targets:
            found = existing(target)
            imp = Import(found, node.lineno, when)
            if (found == PACKAGE or found.startswith(PACKAGE + ".")) and imp not in out:
                out.append(imp)
    return out


def planned(module: str) -> str:
    """The module's name once afsmc/verify/ is split (itself if it is not a flat one)."""
    head, _, last = module.rpartition(".")
    if head == "afsmc.verify" and last in VERIFY_SPLIT:
        return f"{head}.{VERIFY_SPLIT[last]}.{last}"
    return module


STAGE_OF: dict[str, str] = {key: stage for stage, keys in STAGES for key in keys}
ORDER = {stage: i for i, (stage, _) in enumerate(STAGES)}


def table_key(module: str) -> str | None:
    """The longest key of STAGES that is the module or a package containing it (the root
    key covers only the root)."""
    name = planned(module)
    while name not in STAGE_OF or (name == PACKAGE and module != PACKAGE):
        name = name.rpartition(".")[0]
        if not name:
            return None
    return name


def stage(module: str) -> str:
    key = table_key(module)
    assert key is not None, f"{module} is in no stage of STAGES"
    return STAGE_OF[key]


def group(module: str) -> str:
    """The module's package in the table, a subpackage merged into its parent when both are
    of the same stage (afsmc.syntax.errors is part of afsmc.syntax)."""
    key = table_key(module)
    assert key is not None
    while (parent := key.rpartition(".")[0]) in STAGE_OF and parent != PACKAGE \
            and STAGE_OF[parent] == STAGE_OF[key]:
        key = parent
    return key


def _graph() -> dict[str, list[Import]]:
    found = modules()
    return {name: imports(path, found) for name, path in found.items()}


GRAPH = _graph()
GRAPH_PATHS = {name: path.relative_to(ROOT).as_posix() for name, path in modules().items()}


def test_the_package_is_read() -> None:
    assert len(GRAPH) > 100
    assert {"afsmc.compiler", "afsmc.verify", "afsmc.syntax.parser"} <= set(GRAPH)


def test_no_stage_imports_a_later_one() -> None:
    upward, known = [], set()
    for name, found in GRAPH.items():
        for imp in found:
            if ORDER[stage(imp.target)] <= ORDER[stage(name)] or (name, imp.target) in DOORS:
                continue
            if (name, imp.target) in KNOWN_UPWARD:
                known.add((name, imp.target))
                continue
            upward.append(f"{GRAPH_PATHS[name]}:{imp.line} ({stage(name)}) imports "
                          f"{imp.target} ({stage(imp.target)}), {imp.when}")
    assert upward == [], "imports of a later stage:\n" + "\n".join(upward)
    assert known == set(KNOWN_UPWARD), f"no longer upward, remove: {set(KNOWN_UPWARD) - known}"


def _cycles(edges: Mapping[str, set[str]]) -> list[list[str]]:
    """The strongly connected components with more than one node, or a node importing
    itself (Tarjan's algorithm, iterative so that no depth limit applies)."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on: set[str] = set()
    out: list[list[str]] = []
    for start in sorted(edges):
        if start in index:
            continue
        work = [(start, iter(sorted(edges.get(start, ()))))]
        index[start] = low[start] = len(index)
        stack.append(start)
        on.add(start)
        while work:
            node, children = work[-1]
            child = next(children, None)
            if child is not None:
                if child not in index:
                    index[child] = low[child] = len(index)
                    stack.append(child)
                    on.add(child)
                    work.append((child, iter(sorted(edges.get(child, ())))))
                elif child in on:
                    low[node] = min(low[node], index[child])
                continue
            work.pop()
            if work:
                low[work[-1][0]] = min(low[work[-1][0]], low[node])
            if low[node] == index[node]:
                component = []
                while True:
                    top = stack.pop()
                    on.discard(top)
                    component.append(top)
                    if top == node:
                        break
                if len(component) > 1 or node in edges.get(node, ()):
                    out.append(sorted(component))
    return out


def _run_on_import() -> dict[str, set[str]]:
    """The module-level imports between modules of the same stage."""
    return {name: {i.target for i in found if i.when == "module" and i.target != name
                   and stage(i.target) == stage(name)}
            for name, found in GRAPH.items()}


def test_no_import_cycle_inside_a_stage() -> None:
    cycles = _cycles(_run_on_import())
    assert cycles == [], ("module-level imports that close a cycle (import one of them in a "
                          f"function, or move what they share down): {cycles}")


def test_the_packages_of_a_stage_are_layered() -> None:
    edges: dict[str, set[str]] = {}
    for name, targets in _run_on_import().items():
        edges.setdefault(group(name), set()).update(
            group(t) for t in targets if group(t) != group(name))
    cycles = _cycles(edges)
    assert cycles == [], f"packages of one stage that import each other at module level: {cycles}"


def _packages() -> list[str]:
    """Every package (a folder with an __init__.py) and every module directly in afsmc/."""
    top = ROOT / PACKAGE
    return sorted({module_name(p.parent / "__init__.py") for p in top.rglob("__init__.py")}
                  | {module_name(p) for p in top.glob("*.py")})


def test_every_package_is_in_the_table() -> None:
    missing = [p for p in _packages() if planned(p) not in STAGE_OF]
    assert missing == [], f"add to STAGES (tests/unit/test_architecture.py): {missing}"


def test_the_table_names_nothing_that_does_not_exist() -> None:
    planned_packages = {f"afsmc.verify.{sub}" for sub in VERIFY_SPLIT.values()}
    stale = sorted(set(STAGE_OF) - set(_packages()) - planned_packages)
    assert stale == [], f"STAGES names what does not exist: {stale}"


def test_the_planned_verify_split_is_current() -> None:
    flat = {p.stem for p in (ROOT / "afsmc" / "verify").glob("*.py")} - {"__init__"}
    assert sorted(set(VERIFY_SPLIT) - flat) == [], "moved: remove these from VERIFY_SPLIT"
    assert sorted(flat - set(VERIFY_SPLIT)) == [], "put these in a subpackage of afsmc/verify/"


def _module_counts() -> dict[str, int]:
    counts: dict[str, int] = {}
    for path in (ROOT / PACKAGE).rglob("*.py"):
        if path.name != "__init__.py":
            folder = path.parent.relative_to(ROOT).as_posix()
            counts[folder] = counts.get(folder, 0) + 1
    return counts


def test_no_folder_holds_more_than_15_modules() -> None:
    over = {f: n for f, n in _module_counts().items()
            if n > MAX_MODULES and f not in OVER_15_MODULES}
    assert over == {}


def test_the_allow_list_of_large_folders_shrinks() -> None:
    counts = _module_counts()
    done = [f for f in OVER_15_MODULES if counts.get(f, 0) <= MAX_MODULES]
    assert done == [], f"now within {MAX_MODULES} modules, remove from OVER_15_MODULES: {done}"


def _page_stages() -> list[tuple[str, tuple[str, ...]]]:
    """The rows of the table under "## Stages" on the page: the stage and the dotted names
    in backticks of its last column."""
    section = PAGE.read_text(encoding="utf-8").split("## Stages", 1)[1].split("\n## ", 1)[0]
    rows = []
    for line in section.splitlines():
        cells = [c.strip() for c in line.strip().strip("|").split("|")]
        if len(cells) >= 3 and line.startswith("|") and cells[0] not in ("stage", "---"):
            rows.append((cells[0], tuple(re.findall(r"`(afsmc[\w.]*)`", cells[-1]))))
    return rows


def test_the_page_lists_the_same_stages() -> None:
    assert _page_stages() == [(name, keys) for name, keys in STAGES]


def _defines(path: Path) -> set[str]:
    """The names a module binds at top level (and lists in __all__)."""
    names: set[str] = set()
    for node in ast.parse(path.read_text(encoding="utf-8")).body:
        if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef, ast.ClassDef)):
            names.add(node.name)
        elif isinstance(node, (ast.Import, ast.ImportFrom)):
            names |= {(a.asname or a.name).split(".")[0] for a in node.names}
        elif isinstance(node, (ast.Assign, ast.AnnAssign)):
            for target in node.targets if isinstance(node, ast.Assign) else [node.target]:
                names |= {n.id for n in ast.walk(target) if isinstance(n, ast.Name)}
                if isinstance(target, ast.Name) and target.id == "__all__" and node.value:
                    names |= {c.value for c in ast.walk(node.value)
                              if isinstance(c, ast.Constant) and isinstance(c.value, str)}
    return names


def test_the_dotted_names_on_the_page_exist() -> None:
    # `afsmc.x.y` in backticks: a module or package (or a planned subpackage of
    # afsmc/verify/), a name a module defines, or an entry-point group of pyproject.toml.
    found = modules()
    planned_names = ({planned(m) for m in found}
                     | {f"afsmc.verify.{sub}" for sub in VERIFY_SPLIT.values()})
    groups = set(re.findall(r'entry-points\."([\w.]+)"', (ROOT / "pyproject.toml").read_text()))
    missing = []
    for name in sorted(set(re.findall(r"`(afsmc(?:\.\w+)*)`", PAGE.read_text(encoding="utf-8")))):
        owner, _, attr = name.rpartition(".")
        if name in found or name in planned_names or name in groups:
            continue
        if owner in found and attr in _defines(found[owner]):
            continue
        missing.append(name)
    assert missing == [], f"docs/architecture.md names what does not exist: {missing}"


def test_the_scan_tells_when_each_import_runs(tmp_path: Path) -> None:
    # The scan itself, on a package laid out under tmp_path.
    pkg = tmp_path / "afsmc" / "model"
    pkg.mkdir(parents=True)
    for name in ("__init__.py", "x.py", "y.py", "../__init__.py", "../cli.py"):
        (pkg / name).write_text("")
    (pkg / "x.py").write_text(
        "from typing import TYPE_CHECKING\n"
        "from . import y\n"
        "import afsmc.cli as c\n"
        "if TYPE_CHECKING:\n    from afsmc.model.y import Thing\n"
        "else:\n    from afsmc import model\n"
        "def f():\n    from ..cli import main\n"
        "class K:\n    from afsmc.model import y as z\n")
    found = imports(pkg / "x.py", modules(tmp_path), tmp_path)
    assert [(i.target, i.line, i.when) for i in found] == [
        ("afsmc.model.y", 2, "module"), ("afsmc.cli", 3, "module"),
        ("afsmc.model.y", 5, "type-checking"), ("afsmc.model", 7, "module"),
        ("afsmc.cli", 9, "function"), ("afsmc.model.y", 11, "module")]


def test_a_stage_is_found_by_the_longest_name_and_the_planned_split() -> None:
    assert stage("afsmc") == "leaves"
    assert stage("afsmc.syntax.errors.diagnose") == "source"
    assert stage("afsmc.verify") == "studies"
    assert planned("afsmc.verify.engines.storm") == "afsmc.verify.engines.storm"
    assert stage("afsmc.verify.engines.storm") == "engines"
    assert stage("afsmc.verify.engines.storm") == "engines"
    assert group("afsmc.syntax.errors.diagnose") == "afsmc.syntax"
    assert _cycles({"a": {"b"}, "b": {"c"}, "c": {"a"}, "d": {"d"}, "e": {"a"}}) == [
        ["a", "b", "c"], ["d"]]
