"""Diagnostics as data for other programs: a JSON list (`afsmc check --json`), and a SARIF
2.1.0 log (`afsmc check --format sarif`) for code-scanning tools, whose rules are the
registry's codes."""

from __future__ import annotations

import json
import os
from collections.abc import Iterable
from pathlib import Path
from urllib.parse import quote

from afsmc import __version__
from afsmc.diagnostics.codes import REGISTRY, Code
from afsmc.diagnostics.model import Diagnostic, Span

SARIF_SCHEMA = "https://json.schemastore.org/sarif-2.1.0.json"


def to_json(diags: Iterable[Diagnostic]) -> str:
    return json.dumps([d.to_json() for d in diags], indent=2)


def to_sarif(diags: Iterable[Diagnostic]) -> str:
    """A SARIF 2.1.0 log of one run of afsmc: each result is one diagnostic, each rule a
    code of the registry that a result reports (in the registry's order), with its title
    and explanation. Columns count characters (Unicode code points), as afsmc's do; the
    end of a region is the column after its last character, as a span's is."""
    diags = list(diags)
    reported = {d.code for d in diags}
    rules = [code for code in REGISTRY.values() if code in reported]
    index = {str(code): i for i, code in enumerate(rules)}
    log = {
        "$schema": SARIF_SCHEMA,
        "version": "2.1.0",
        "runs": [{
            "tool": {"driver": {
                "name": "afsmc",
                "version": __version__,
                "rules": [_rule(code) for code in rules],
            }},
            "columnKind": "unicodeCodePoints",
            "results": [_result(d, index) for d in diags],
        }],
    }
    return json.dumps(log, indent=2, ensure_ascii=False)


def _rule(code: Code) -> dict[str, object]:
    rule: dict[str, object] = {
        "id": str(code),
        "shortDescription": {"text": code.title},
        "defaultConfiguration": {"level": code.severity.value},
    }
    ex = code.explanation
    if ex is not None:
        rule["fullDescription"] = {"text": ex.prose}
        rule["help"] = {
            "text": ex.prose,
            "markdown": f"{ex.prose}\n\n## Wrong\n\n{ex.wrong.markdown}\n\n"
                        f"## Right\n\n{ex.right.markdown}\n",
        }
    return rule


def _result(d: Diagnostic, index: dict[str, int]) -> dict[str, object]:
    text = d.message if not d.hint else f"{d.message}\nhint: {d.hint}"
    result: dict[str, object] = {
        "ruleId": d.code,
        "level": d.severity.value,
        "message": {"text": text},
    }
    if d.code in index:
        result["ruleIndex"] = index[d.code]
    if d.span is not None:
        result["locations"] = [{"physicalLocation": _physical(d.span)}]
    if d.related:
        result["relatedLocations"] = [
            {"id": i, "physicalLocation": _physical(r.span), "message": {"text": r.message}}
            for i, r in enumerate(d.related)]
    return result


def _physical(span: Span) -> dict[str, object]:
    return {
        "artifactLocation": {"uri": artifact_uri(span.source.path)},
        "region": {"startLine": span.line, "startColumn": span.column,
                   "endLine": span.end_line, "endColumn": span.end_column},
    }


def artifact_uri(path: str) -> str:
    """A file's path as a URI: a relative reference for a relative path (as code-scanning
    tools resolve against the checkout), file:// for an absolute one."""
    if os.path.isabs(path):
        return Path(path).as_uri()
    return quote(Path(path).as_posix())
