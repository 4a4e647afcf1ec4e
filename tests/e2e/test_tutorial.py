"""docs/tutorial.ipynb runs clean in a real Jupyter kernel (nbclient + ipykernel), and is
committed without outputs."""

from __future__ import annotations

import os
from pathlib import Path

import pytest

from tests.conftest import ROOT

NOTEBOOK = ROOT / "docs" / "tutorial.ipynb"


def test_the_tutorial_is_committed_without_outputs() -> None:
    import nbformat

    nb = nbformat.read(NOTEBOOK, as_version=4)
    nbformat.validate(nb)
    code = [c for c in nb.cells if c.cell_type == "code"]
    assert code
    assert all(c.outputs == [] and c.execution_count is None for c in code)


@pytest.mark.storm
@pytest.mark.slow  # a kernel, Storm and a simulation: about 30 s
def test_the_tutorial_runs_clean_in_a_kernel(tmp_path: Path,
                                             monkeypatch: pytest.MonkeyPatch) -> None:
    import nbformat
    from nbclient import NotebookClient

    # The kernel is a new process: it finds this checkout's afsmc through PYTHONPATH, and
    # writes the tutorial's files in tmp_path, its working directory.
    monkeypatch.setenv("PYTHONPATH", os.pathsep.join(
        [str(ROOT), *filter(None, [os.environ.get("PYTHONPATH")])]))
    nb = nbformat.read(NOTEBOOK, as_version=4)
    NotebookClient(nb, timeout=300, kernel_name="python3",
                   resources={"metadata": {"path": str(tmp_path)}}).execute()
    outputs = {c.id: c.outputs for c in nb.cells if c.cell_type == "code"}
    errors = [o for out in outputs.values() for o in out if o.output_type == "error"]
    assert not errors, errors
    assert (tmp_path / "patrol.afsm").exists()
    shown = [o for out in outputs.values() for o in out if "data" in o]
    kinds = {k for o in shown for k in o["data"]}
    # tables (results, pandas), the AfsmError, the plot and the diagram
    assert {"text/html", "image/png", "image/svg+xml"} <= kinds
    error_html = next(o["data"]["text/html"] for o in shown
                      if "afsmc-diagnostics" in o["data"].get("text/html", ""))
    assert "E102" in error_html
