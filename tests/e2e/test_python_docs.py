"""The Python shown in README.md and docs/verification.md runs, as a plain script (no
`if __name__ == "__main__":` guard), so the documented API cannot drift from the code."""

from __future__ import annotations

import os
import re
import subprocess
import sys
from pathlib import Path

import pytest

from tests.conftest import ROOT

pytestmark = [pytest.mark.storm, pytest.mark.slow]  # Storm, a sweep and a simulation: ~20 s


def python_block(page: Path, heading: str) -> str:
    section = page.read_text(encoding="utf-8").split(heading, 1)[1]
    match = re.search(r"```python\n(.*?)```", section, re.S)
    assert match, f"{page.name}: no Python under {heading!r}"
    return match.group(1)


@pytest.mark.parametrize(("page", "heading"), [
    ("README.md", "## From Python and Jupyter"),
    ("docs/verification.md", "## From Python"),
    ("docs/report.md", "# The assurance case"),
])
def test_the_documented_python_runs_as_a_plain_script(page: str, heading: str,
                                                      tmp_path: Path) -> None:
    code = python_block(ROOT / page, heading)
    script = tmp_path / "doc.py"
    # the examples as the page names them, from a scratch directory for what it writes
    script.write_text(code.replace('"examples/', f'"{ROOT}/examples/'))
    env = {**os.environ, "PYTHONPATH": os.pathsep.join(
        [str(ROOT), *filter(None, [os.environ.get("PYTHONPATH")])])}
    proc = subprocess.run([sys.executable, str(script)], cwd=tmp_path, env=env,
                          capture_output=True, text=True, timeout=600)
    assert proc.returncode == 0, proc.stderr
    if 'save("report.html")' in code:
        page = (tmp_path / "report.html").read_text(encoding="utf-8")
        assert page.startswith("<!DOCTYPE html>") and 'id="how-it-fails"' in page
    if 'save("patrol.svg")' in code:
        assert (tmp_path / "patrol.svg").read_text().lstrip().startswith("<?xml")
