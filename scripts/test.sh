#!/usr/bin/env bash
# The test command: installs everything, then runs lint, types and the test suite.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh
.venv/bin/ruff check afsmc tests benchmarks
.venv/bin/mypy
.venv/bin/pytest "$@"
