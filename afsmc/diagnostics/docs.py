"""docs/diagnostics.md, generated from the registry and the explanation files
(scripts/gen_diagnostics_doc.py writes it; `afsmc explain --markdown` prints it)."""

from __future__ import annotations

from afsmc.diagnostics.codes import GROUPS, REGISTRY, Code

DOC_PATH = "docs/diagnostics.md"
REGENERATE = "python scripts/gen_diagnostics_doc.py"


def page() -> str:
    """The whole page: an index of every code by range, then each code's explanation."""
    out = [
        "# Diagnostics",
        "",
        f"<!-- Generated from afsmc/diagnostics/codes.py and afsmc/diagnostics/explanations/"
        f" by `{REGENERATE}`; do not edit. -->",
        "",
        "Every problem afsmc reports has a code: `E` for an error (exit 1), `W` for a warning, "
        "`N` for a note. `afsmc explain CODE` prints a code's explanation in the terminal, "
        "`afsmc explain` lists them all, and `afsmc check --format json` or `--format sarif` "
        "writes the diagnostics for other programs.",
        "",
    ]
    for heading, codes in _groups():
        out += [f"- [{heading}](#{_anchor(heading)}): "
                + ", ".join(f"[{c}](#{c.lower()})" for c in codes)]
    for heading, codes in _groups():
        out += ["", f"## {heading}"]
        for code in codes:
            out += ["", *_entry(code)]
    return "\n".join(out) + "\n"


def _groups() -> list[tuple[str, list[Code]]]:
    return [(heading, [c for c in REGISTRY.values() if c[:2] in prefixes])
            for heading, prefixes in GROUPS]


def _anchor(heading: str) -> str:
    """GitHub's anchor of a heading: lower case, spaces as '-', other punctuation gone."""
    return "".join(ch for ch in heading.lower().replace(" ", "-") if ch.isalnum() or ch in "-_")


def _entry(code: Code) -> list[str]:
    lines = [f'<a id="{code.lower()}"></a>', "", f"### {code}: {code.title}", "",
             f"*{code.severity.value}*", ""]
    ex = code.explanation
    if ex is None:
        return [*lines, "No explanation is written yet."]
    return [*lines, ex.prose, "", "#### Wrong", "", ex.wrong.markdown, "",
            "#### Right", "", ex.right.markdown]
