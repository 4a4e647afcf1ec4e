#!/usr/bin/env bash
# The test command: installs everything, then runs lint, types and the test suite.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh
.venv/bin/ruff check afsmc tests benchmarks scripts
.venv/bin/mypy
# one worker per core (`-n 0` after the script's name runs in one process)
.venv/bin/pytest -n auto --dist worksteal "$@"
