"""Every code that afsmc/ can report is declared in the registry, once, with the severity
it is reported at; every declaration is well formed."""

from __future__ import annotations

import ast
import re
from pathlib import Path

import pytest

from afsmc.diagnostics import codes
from afsmc.diagnostics.codes import GROUPS, REGISTRY, Code, group_of, lookup
from tests.conftest import ROOT

CODE = re.compile(r"[EWN]\d{3}")
SOURCES = sorted(p for p in (ROOT / "afsmc").rglob("*.py")
                 if p.parent != ROOT / "afsmc" / "diagnostics" or p.name != "codes.py")


def _trees() -> list[tuple[Path, ast.Module]]:
    return [(p, ast.parse(p.read_text(encoding="utf-8"), str(p))) for p in SOURCES]


TREES = _trees()


def code_of(node: ast.AST) -> str | None:
    """The code a node names: a string literal that is a whole code ("E301"), a reference
    to the registry (`codes.E301`), or a name imported from it (`from ...codes import E301`)."""
    if isinstance(node, ast.Constant) and isinstance(node.value, str):
        name = node.value
    elif isinstance(node, ast.Attribute):
        name = node.attr
    elif isinstance(node, ast.alias):
        name = node.asname or node.name
    else:
        return None
    return name if CODE.fullmatch(name) else None


def emitted() -> dict[str, list[str]]:
    """Each code afsmc/ names, with where."""
    found: dict[str, list[str]] = {}
    for path, tree in TREES:
        for node in ast.walk(tree):
            if isinstance(node, ast.ImportFrom) and node.module == "afsmc.diagnostics.codes":
                names = [code_of(a) for a in node.names]
            elif isinstance(node, ast.Constant | ast.Attribute):
                names = [code_of(node)]
            else:
                continue
            for name in names:
                if name is not None:
                    found.setdefault(name, []).append(f"{path.relative_to(ROOT)}:{node.lineno}")
    return found


def test_every_code_that_afsmc_names_is_in_the_registry() -> None:
    missing = {c: where for c, where in emitted().items() if c not in REGISTRY}
    assert not missing, ("codes used in afsmc/ but not declared in "
                         f"afsmc/diagnostics/codes.py: {missing}")


def test_the_scan_finds_the_codes_it_should() -> None:
    # guards the scan itself: a few codes from each stage are found where they are
    found = emitted()
    for code in ("E001", "E101", "E203", "E301", "W309", "E402", "N412", "E501", "E610"):
        assert code in found, code


SEVERITIES = {"error": "ERROR", "warning": "WARNING", "note": "NOTE"}


def _reported_at() -> list[tuple[str, str, str]]:
    """(code, severity, where) of every site that names both: `rep.error("E301", ...)`,
    `Diagnostic("E301", Severity.ERROR, ...)`, `{"code": "E009", "severity": "error"}`."""
    out = []
    for path, tree in TREES:
        for node in ast.walk(tree):
            where = f"{path.relative_to(ROOT)}:{getattr(node, 'lineno', 0)}"
            if isinstance(node, ast.Call) and node.args:
                first = node.args[0]
                # "E245" if ... else "E249" names two
                alternatives = [first.body, first.orelse] if isinstance(first, ast.IfExp) \
                    else [first]
                codes_here = [c for c in map(code_of, alternatives) if c is not None]
                func = node.func
                if isinstance(func, ast.Attribute) and func.attr in SEVERITIES:
                    out += [(c, SEVERITIES[func.attr], where) for c in codes_here]
                elif len(node.args) > 1 and isinstance(node.args[1], ast.Attribute) \
                        and isinstance(node.args[1].value, ast.Name) \
                        and node.args[1].value.id == "Severity":
                    out += [(c, node.args[1].attr, where) for c in codes_here]
            elif isinstance(node, ast.Dict):
                pairs = {k.value: v for k, v in zip(node.keys, node.values, strict=True)
                         if isinstance(k, ast.Constant)}
                code, sev = code_of(pairs.get("code", ast.Pass())), pairs.get("severity")
                if code and isinstance(sev, ast.Constant) and sev.value in SEVERITIES:
                    out.append((code, SEVERITIES[sev.value], where))
    return out


@pytest.mark.slow
def test_each_code_is_reported_at_its_declared_severity() -> None:
    sites = _reported_at()
    assert len(sites) > 100  # the scan sees the call sites
    wrong = [(c, sev, where) for c, sev, where in sites
             if c in REGISTRY and REGISTRY[c].severity.name != sev]
    assert not wrong, wrong


def test_each_declaration_names_its_own_code() -> None:
    for name, value in vars(codes).items():
        if isinstance(value, Code):
            assert name == value, f"{name} = Code({value!r}, ...)"
    assert len(REGISTRY) == sum(isinstance(v, Code) for v in vars(codes).values())


@pytest.mark.parametrize("code", list(REGISTRY.values()), ids=list(REGISTRY))
def test_a_title_is_one_lower_case_line(code: Code) -> None:
    title = code.title
    assert title and "\n" not in title and title == title.strip(), title
    assert not title.endswith("."), title
    assert not title[0].isupper(), title


def test_every_code_is_in_one_group_and_the_groups_follow_the_registry() -> None:
    heads = [group_of(c) for c in REGISTRY]
    assert [h for h, _ in GROUPS] == list(dict.fromkeys(heads))  # in order, none empty


def test_a_code_is_a_string_with_its_severity_and_title() -> None:
    e301 = codes.E301
    assert e301 == "E301" and hash(e301) == hash("E301") and f"{e301}" == "E301"
    assert e301.severity.value == "error" and e301.title == "weights of enabled actions tie"
    assert lookup("e301") is e301 and lookup("E300") is None
    with pytest.raises(ValueError, match="W and three digits"):
        Code("E999", codes.Severity.WARNING, "x")
