"""The published JSON Schemas (docs/schemas/NAME.schema.json): what scripts/gen_schemas.py
writes from the models of afsmc/answer/ and `afsmc schema NAME` prints, valid draft 2020-12
schemas with a versioned `$id`, every key described; the models frozen and closed."""

from __future__ import annotations

import inspect
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import jsonschema
import pytest
from pydantic import BaseModel

from afsmc.answer import NAMES, common, regions, simulate, sweep, verify
from afsmc.answer.schema import DOC_DIR, MODELS, REGENERATE, identifier, schema, text
from tests.conftest import ROOT, run_cli
from tests.unit.test_architecture import imports, modules


@pytest.mark.parametrize("name", NAMES)
def test_the_checked_in_schema_is_current(name: str) -> None:
    path = ROOT / DOC_DIR / f"{name}.schema.json"
    assert path.read_text(encoding="utf-8") == text(name), f"{path} is stale: run `{REGENERATE}`"


@pytest.mark.parametrize("name", NAMES)
def test_afsmc_schema_prints_the_checked_in_file(name: str) -> None:
    r = run_cli("schema", name)
    assert r.code == 0 and r.err == "", r.err
    assert r.out == (ROOT / DOC_DIR / f"{name}.schema.json").read_text(encoding="utf-8")


def test_afsmc_schema_refuses_a_command_without_one() -> None:
    r = run_cli("schema", "check")
    assert r.code == 2 and "invalid choice: 'check'" in r.err, r.err


def test_the_commands_with_a_schema_are_the_models() -> None:
    assert tuple(MODELS) == NAMES


@pytest.mark.parametrize("name", NAMES)
def test_each_schema_is_a_versioned_draft_2020_12_schema(name: str) -> None:
    s = schema(name)
    jsonschema.Draft202012Validator.check_schema(s)
    assert s["$schema"] == "https://json-schema.org/draft/2020-12/schema"
    assert s["$id"] == identifier(name) == f"urn:afsmc:schema:{name}:{common.SCHEMA_VERSION}"
    # byte-deterministic: sorted keys, ASCII, one newline at the end
    assert text(name).isascii() and text(name).endswith("}\n") and text(name) == text(name)


def _objects(node: Any) -> Iterator[dict[str, Any]]:
    """Every object schema (one with "properties") in a schema."""
    if isinstance(node, dict):
        if node.get("type") == "object" and isinstance(node.get("properties"), dict):
            yield node
        for v in node.values():
            yield from _objects(v)
    elif isinstance(node, list):
        for v in node:
            yield from _objects(v)


@pytest.mark.parametrize("name", NAMES)
def test_every_object_and_key_is_described(name: str) -> None:
    s = schema(name)
    for title, d in s["$defs"].items():
        assert d.get("description"), f"{title} has no description (its docstring)"
    for obj in _objects(s):
        assert obj.get("additionalProperties") is False, obj.get("title")
        bare = [k for k, v in obj["properties"].items() if not v.get("description")]
        assert not bare, f"{obj.get('title')}: keys without a description: {bare}"
        # a field's title would only repeat its key
        assert not [k for k, v in obj["properties"].items() if "title" in v]


def _models() -> list[type[BaseModel]]:
    out = []
    for module in (common, verify, sweep, regions, simulate):
        out += [m for _, m in inspect.getmembers(module, inspect.isclass)
                if issubclass(m, common.Answer) and m.__module__ == module.__name__]
    return out


@pytest.mark.parametrize("model", _models(), ids=lambda m: m.__name__)
def test_every_model_is_frozen_and_closed(model: type[BaseModel]) -> None:
    assert model.model_config.get("frozen") is True
    assert model.model_config.get("extra") == "forbid"


def test_the_answers_import_nothing_else_of_afsmc() -> None:
    # any stage may use them; afsmc/answer/__init__.py imports nothing, for the CLI
    package = ROOT / "afsmc" / "answer"
    known = modules()
    for path in sorted(package.glob("*.py")):
        outside = sorted(i.target for i in imports(path, known)
                         if not i.target.startswith("afsmc.answer"))
        assert not outside, f"{path.name} imports {outside}"
    assert not [i for i in imports(package / "__init__.py", known)
                if i.target != "afsmc.answer"]


def test_an_absent_key_is_left_out_and_never_null() -> None:
    """Python's None stands for a key that is left out; in JSON such a key is absent or
    has a value. An optional nullable key is written when it was given."""
    def diag(**extra: Any) -> str:
        return verify.Diagnostic(code="E001", severity="error", message="m",
                                 **extra).model_dump_json()

    assert diag() == diag(hint=None) == '{"code":"E001","severity":"error","message":"m"}'
    with pytest.raises(ValueError, match="never null"):
        common.Diagnostic.model_validate_json('{"code": "E001", "severity": "error", '
                                              '"message": "m", "hint": null}')
    box: dict[str, Any] = dict(requirement="r", box={}, coverage=1, target_coverage=0.9,
                               holds=1, fails=0, unknown=0, rounds=1, states=1, seconds=0,
                               verdict="holds", reason="r", from_file=[], region_meaning=None,
                               min=None, max=None,
                               error=None, decided_by=None, engine="lifting", regions=[])
    assert "feasible" not in regions.Regions(**box).model_dump(mode="json")
    none = regions.Regions(**box, feasible=None, feasible_method=None)
    assert none.model_dump(mode="json")["feasible"] is None
    assert regions.Regions.model_validate_json(none.model_dump_json()) == none


def test_a_partial_result_dumps_its_diagnostics_first() -> None:
    point = sweep.Sweep(file="f", variable="K", kind="const", type="dtmc", properties=[],
                        points=[])
    partial = sweep.SweepPartial(**point.model_dump(), diagnostics=[], interrupted=True)
    assert list(partial.model_dump())[:3] == ["interrupted", "diagnostics", "file"]


def test_the_sweeps_from_key_is_written_as_from() -> None:
    r = sweep.VerdictRange(verdict="holds", from_=1, to=2)
    assert r.model_dump(mode="json", by_alias=True) == {"verdict": "holds", "from": 1, "to": 2}
    assert sweep.VerdictRange.model_validate_json('{"verdict": "holds", "from": 1, "to": 2}') == r


def test_the_docs_link_the_schemas() -> None:
    page = (ROOT / "docs" / "verification.md").read_text(encoding="utf-8")
    for name in NAMES:
        assert f"schemas/{name}.schema.json" in page, name
    assert Path(ROOT / "scripts" / "gen_schemas.py").exists()


def test_an_infinite_number_is_refused() -> None:
    # JSON has none: a model never dumps Infinity (or null in its place) silently
    with pytest.raises(ValueError, match="finite"):
        common.Threshold(op=">=", bound=float("inf"))
