#!/usr/bin/env bash
# The main job: installs everything, then checks, compiles, draws and verifies the UAV mission.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh
mkdir -p out
afsmc=.venv/bin/afsmc
echo "== afsmc check examples/uav.afsm"
$afsmc check examples/uav.afsm
echo "== afsmc compile (PRISM and JANI) into out/"
$afsmc compile examples/uav.afsm -t prism -o out/
$afsmc compile examples/uav.afsm -t jani -o out/
echo "== afsmc diagram -> out/uav.svg"
$afsmc diagram examples/uav.afsm -o out/uav.svg
echo "== afsmc verify examples/uav.afsm (default instance)"
$afsmc verify examples/uav.afsm --progress
