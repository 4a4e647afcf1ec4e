"""The answers afsmc prints with `--json`, as frozen pydantic models: one module per
command (`verify`, `sweep`, `regions`, `simulate`, `conform`), what they share in `common`, and the
published JSON Schemas generated from them in `schema` (`afsmc schema NAME`,
docs/schemas/NAME.schema.json, versioned by `common.SCHEMA_VERSION`).

Each command's `...Output` model (a root model) takes every object the command prints: the
answer, a failure's diagnostics, and what a failed or stopped run had finished. The
package imports nothing else of afsmc, so that any stage may use it; this module imports
nothing at all, so that the CLI can offer the names without loading pydantic.
"""

# The commands whose --json output has a published schema (afsmc.answer.schema.MODELS).
NAMES = ("verify", "sweep", "regions", "simulate", "conform")
