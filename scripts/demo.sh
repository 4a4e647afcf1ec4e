#!/usr/bin/env bash
# The main job: installs everything, then checks, compiles, draws and verifies the UAV mission.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh
mkdir -p out
.venv/bin/afsmc check examples/uav.afsm
.venv/bin/afsmc compile examples/uav.afsm -t prism -o out/
.venv/bin/afsmc verify examples/uav.afsm
