"""`afsmc verify --causes` and `--baseline`: their lines after verify's table, and what
they add to `--json` (afsmc.report.causes, afsmc.report.baseline compute them)."""

from __future__ import annotations

from afsmc.report.baseline import Comparison, shown
from afsmc.report.causes import Split
from afsmc.text import num


def cause_lines(splits: dict[str, list[Split]]) -> list[str]:
    """Each property's causes, most probable first, and their sum."""
    from afsmc.commands.verify import table

    out: list[str] = []
    for name, parts in splits.items():
        for s in parts:
            under = "" if s.under == "value" else f", its {s.under} (under the scheduler " \
                "that attains it)"
            if s.midpoint:
                under += " with the interval probabilities at their midpoint"
            out += ["", f"causes of {name}{under}: what first led into the target"]
            rows = [["cause", "event", "during", "mode entered", "probability"]]
            rows += [[c.kind, c.event, c.during or "-", c.mode, num(c.probability)]
                     for c in s.causes]
            rows.append(["sum", "", "", "", num(s.summed)])
            out += ["  " + line for line in table(rows, {4})]
    return out


def baseline_lines(c: Comparison) -> list[str]:
    from afsmc.commands.verify import table

    rows = [["property", "old", "new", "old verdict", "new verdict", "change"]]
    for ch in c.changes:
        flag = ("WORSE" if ch.worse else "flipped" if ch.flipped else
                f"only in the {ch.only} run" if ch.only else
                f"moved {num(ch.moved)}" if ch.flagged else "")
        rows.append([ch.name, shown(ch.old, num), shown(ch.new, num), ch.old_verdict or "-",
                     ch.new_verdict or "-", flag])
    worse = len(c.worse)
    return ["", f"against {c.baseline} (tolerance {num(c.tolerance)}): "
            f"{len(c.flagged)} flagged, {worse} worse", *table(rows, set())]


def with_changes(answer: dict[str, object], splits: dict[str, list[Split]],
                 comparison: Comparison | None) -> dict[str, object]:
    """`verify --json`'s object with each split property's "causes" and the "baseline"."""
    props = answer.get("properties")
    if splits and isinstance(props, list):
        answer["properties"] = [
            {**e, "causes": [x for s in splits[e["name"]] for x in s.to_json()]}
            if isinstance(e, dict) and e.get("name") in splits else e for e in props]
    if comparison is not None:
        answer["baseline"] = comparison.to_json()
    return answer
