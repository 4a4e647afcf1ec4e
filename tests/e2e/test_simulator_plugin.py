"""The worked simulator plugin (examples/plugin-example): the registry loads it through the
`afsmc.simulators` entry point, without installing it into the environment, and
`afsmc sim-check` runs its simulator and judges the example spec's constants by it."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from collections.abc import Iterator
from importlib.metadata import EntryPoint
from pathlib import Path

import numpy as np
import pytest

from afsmc.simlib import registry
from tests.conftest import EXAMPLES, ROOT

PLUGIN = EXAMPLES / "plugin-example"
ENTRY = "rover_models.sims:SIMULATORS"


@pytest.fixture
def plugin_registered(monkeypatch: pytest.MonkeyPatch) -> Iterator[None]:
    """The registry with the plugin's entry point beside the installed ones, as
    `pip install examples/plugin-example` would make it."""
    monkeypatch.syspath_prepend(str(PLUGIN))
    installed = registry.entry_points
    ours = EntryPoint(name="rover", value=ENTRY, group=registry.ENTRY_POINT_GROUP)

    def with_plugin(group: str) -> list[EntryPoint]:
        return [*installed(group=group), ours]

    monkeypatch.setattr(registry, "entry_points", with_plugin)
    registry.reload()
    yield
    monkeypatch.undo()
    registry.reload()
    sys.modules.pop("rover_models.sims", None)
    sys.modules.pop("rover_models", None)


def test_the_registry_loads_the_plugin_from_its_entry_point(plugin_registered: None) -> None:
    assert {"rover.drive.duration", "rover.drive.battery", "rover.drive.stuck"} <= set(
        registry.available())
    assert registry.kind("rover.drive.stuck") == "probability"
    assert registry.kind("rover.drive.duration") == "duration"
    x = registry.sample("rover.drive.duration", 1000, 0)
    assert x.shape == (1000,) and np.all(x > 0)
    assert np.array_equal(x, registry.sample("rover.drive.duration", 1000, 0))  # reproducible
    assert "uav.transport.drop" in registry.available()  # the built-ins stay


def test_without_the_plugin_its_outputs_are_unknown() -> None:
    registry.reload()
    assert "rover.drive.duration" not in registry.available()


def _dist_info(folder: Path) -> None:
    """The metadata `pip install` writes, by hand: a distribution with the entry point,
    found by importlib.metadata on the path."""
    info = folder / "afsmc_rover_models-0.1.0.dist-info"
    info.mkdir()
    (info / "METADATA").write_text("Metadata-Version: 2.1\nName: afsmc-rover-models\n"
                                   "Version: 0.1.0\n")
    (info / "entry_points.txt").write_text(f"[afsmc.simulators]\nrover = {ENTRY}\n")


@pytest.mark.slow
def test_sim_check_judges_the_example_spec_by_the_plugin(tmp_path: Path) -> None:
    _dist_info(tmp_path)
    env = dict(os.environ)
    env["PYTHONPATH"] = os.pathsep.join([str(ROOT), str(PLUGIN), str(tmp_path)])
    r = subprocess.run([sys.executable, "-m", "afsmc", "sim-check", str(PLUGIN / "rover.afsm"),
                        "--json"], capture_output=True, text=True, env=env, timeout=300,
                       check=False)
    assert r.returncode == 0, r.stderr
    data = json.loads(r.stdout)
    assert [(c["name"], c["verdict"]) for c in data["constants"]] == [
        ("T_DRIVE", "consistent"), ("P_STUCK", "consistent")]
    r = subprocess.run([sys.executable, "-m", "afsmc", "verify", str(PLUGIN / "rover.afsm"),
                        "--json"], capture_output=True, text=True, env=env, timeout=300,
                       check=False)
    assert r.returncode == 0, r.stderr
    assert json.loads(r.stdout)["probability_intervals"]["box"] == {
        "P_STUCK": [0.0124, 0.0173]}
