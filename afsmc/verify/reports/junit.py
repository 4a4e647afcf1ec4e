"""`afsmc verify --junit FILE`: the requirements as a JUnit XML report for CI servers.

One testsuite (the file), one testcase per requirement (a property with a threshold):
`holds` passes; `fails` and `depends` are failures, `undecided` an error (no verdict), each
with the values in its message. Properties without a threshold are not tests and are left
out. The XML is byte-deterministic (no timestamps or host names); the times are Storm's.
"""

from __future__ import annotations

from xml.etree import ElementTree as ET

from afsmc.files import write_atomic
from afsmc.text import num
from afsmc.verify.outcome.results import PropertyResult, VerifyResult


def _values(p: PropertyResult) -> str:
    """`min 0.810218, max 0.831584 (each within 1e-06)` or `value 0.5 (exact)`."""
    keys = ("value",) if p.value is not None else ("min", "max", "uniform")
    parts = [f"{k} {num(getattr(p, k))}" for k in keys if getattr(p, k) is not None]
    bound = ("exact" if p.error == 0 else f"each within {num(p.error)}" if p.error
             else "no error bound")
    return ", ".join(parts) + f" ({bound})"


def junit_xml(res: VerifyResult) -> str:
    """The JUnit XML text of `res`'s requirements."""
    reqs = [p for p in res.properties if p.threshold is not None]
    kinds = [p.verdict.kind if p.verdict is not None else "undecided" for p in reqs]
    suite = ET.Element("testsuite", {
        "name": f"afsmc verify {res.path}",
        "tests": str(len(reqs)),
        "failures": str(sum(k in ("fails", "depends") for k in kinds)),
        "errors": str(sum(k == "undecided" for k in kinds)),
        "skipped": "0",
        "time": f"{res.total_time:.3f}"})
    for p, kind in zip(reqs, kinds, strict=True):
        case = ET.SubElement(suite, "testcase", {
            "classname": f"{res.machine}", "name": f"{p.name}: {p.formula}",
            "time": f"{sum(p.seconds.values()):.3f}"})
        reason = p.verdict.reason if p.verdict is not None else "no value"
        message = f"{kind}: {reason}; {_values(p)}"
        if kind in ("fails", "depends"):
            ET.SubElement(case, "failure", {"message": message, "type": kind}).text = message
        elif kind == "undecided":
            ET.SubElement(case, "error", {"message": message, "type": kind}).text = message
        else:
            ET.SubElement(case, "system-out").text = message
    root = ET.Element("testsuites", {"name": "afsmc"})
    root.append(suite)
    ET.indent(root)
    return '<?xml version="1.0" encoding="utf-8"?>\n' + ET.tostring(root, "unicode") + "\n"


def write_junit(path: str, res: VerifyResult) -> None:
    """Write the report to `path`, whole or not at all, never over the checked file."""
    write_atomic(path, junit_xml(res), protect=(res.path,))
