"""The published JSON Schemas of the five `--json` outputs: `afsmc schema NAME` prints one,
docs/schemas/NAME.schema.json holds it (scripts/gen_schemas.py writes them).

Each schema is JSON Schema draft 2020-12, generated from the pydantic models of
:mod:`afsmc.answer`; its `$id` is `urn:afsmc:schema:NAME:VERSION` with the version of
:data:`afsmc.answer.common.SCHEMA_VERSION`. The text is byte-deterministic: keys sorted,
two-space indents, ASCII, one newline at the end.
"""

from __future__ import annotations

import json
from typing import Any

from pydantic import BaseModel
from pydantic.json_schema import GenerateJsonSchema, JsonSchemaValue
from pydantic_core import core_schema

from afsmc.answer import NAMES
from afsmc.answer.common import SCHEMA_VERSION
from afsmc.answer.conform import ConformOutput
from afsmc.answer.regions import RegionsOutput
from afsmc.answer.simulate import SimulateOutput
from afsmc.answer.sweep import SweepOutput
from afsmc.answer.verify import VerifyOutput

# command -> the model of every object its --json prints
MODELS: dict[str, type[BaseModel]] = dict(zip(
    NAMES, (VerifyOutput, SweepOutput, RegionsOutput, SimulateOutput, ConformOutput),
    strict=True))
DIALECT = "https://json-schema.org/draft/2020-12/schema"
DOC_DIR = "docs/schemas"
REGENERATE = "python scripts/gen_schemas.py"


class _Generator(GenerateJsonSchema):
    """pydantic's generator, without a title per field (the key says it) and without a
    `"default": null` on a key that is absent rather than null (`Absent`)."""

    def field_title_should_be_set(self, schema: Any) -> bool:
        return False

    def default_schema(self, schema: core_schema.WithDefaultSchema) -> JsonSchemaValue:
        out = super().default_schema(schema)
        if out.get("default", ...) is None and not _nullable(out):
            out = {k: v for k, v in out.items() if k != "default"}
        return out


def _nullable(schema: JsonSchemaValue) -> bool:
    if schema.get("type") == "null":
        return True
    return any(_nullable(s) for s in schema.get("anyOf", ()))


def identifier(name: str) -> str:
    """The `$id` of command `name`'s schema."""
    return f"urn:afsmc:schema:{name}:{SCHEMA_VERSION}"


def schema(name: str) -> dict[str, Any]:
    """The JSON Schema of `afsmc NAME --json`, as a dict."""
    body = _one_line(MODELS[name].model_json_schema(schema_generator=_Generator))
    return {**body, "$schema": DIALECT, "$id": identifier(name),
            "title": f"afsmc {name} --json, version {SCHEMA_VERSION}"}


def _one_line(node: Any) -> Any:
    """The schema with each description on one line (a docstring's are wrapped)."""
    if isinstance(node, list):
        return [_one_line(v) for v in node]
    if not isinstance(node, dict):
        return node
    return {k: " ".join(v.split()) if k == "description" and isinstance(v, str)
            else _one_line(v) for k, v in node.items()}


def text(name: str) -> str:
    """The schema as the byte-deterministic text `afsmc schema NAME` prints."""
    return json.dumps(schema(name), indent=2, sort_keys=True, ensure_ascii=True) + "\n"


def typed(name: str, obj: Any) -> BaseModel:
    """`obj`, the object `afsmc NAME --json` prints, as the frozen pydantic model of its
    schema (for `verify`: an `afsmc.answer.verify.Verification`): the typed answer the
    Python API's `answer()` returns. Raises pydantic's ValidationError where `obj` is not
    what the schema says."""
    root = getattr(MODELS[name].model_validate(obj), "root", None)  # each model a RootModel
    assert isinstance(root, BaseModel)
    return root


def published(name: str, obj: Any) -> Any:
    """`obj`, the object `afsmc NAME --json` prints, through its published model: checked
    against the schema and written as the model writes it, so that what a command prints
    is what its schema says (a key the schema does not know is a bug, found here before a
    reader finds it)."""
    return MODELS[name].model_validate(obj).model_dump(mode="json", by_alias=True)
